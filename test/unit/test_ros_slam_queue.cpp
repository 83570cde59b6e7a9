// The tracking nodelet's SLAM queue, without a ROS master: the live queue
// keeps the newest frame, the bag queue blocks its producer, commands go before frames,
// close() wakes everyone and the work already posted still runs. Waits are on events (a
// thread's progress), never on sleeps.
#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <thread>
#include <vector>

#include "vitamin_e/ros/slam_queue.h"

using vitamin_e_ros::SlamQueue;

namespace {

using Queue = SlamQueue<int>;

// The next item: a frame (>= 0) or a command run here (-1); -2 once closed and empty.
int take(Queue& q) {
  std::optional<int> frame;
  Queue::Command command;
  if (!q.next(&frame, &command)) return -2;
  if (command) {
    command();
    return -1;
  }
  return frame.value_or(-3);  // -3: neither a command nor a frame, which next() never gives
}

}  // namespace

TEST(RosSlamQueue, LiveKeepsTheNewestFrame) {
  Queue q(1, true);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(q.push(i));  // never blocks
  auto c = q.counts();
  EXPECT_EQ(c.waiting, 1u);
  EXPECT_EQ(c.dropped, 4u);
  EXPECT_EQ(c.pushed, 5u);
  EXPECT_EQ(take(q), 4);
  EXPECT_TRUE(q.counts().busy);
}

TEST(RosSlamQueue, BagBlocksTheProducerAndLosesNothing) {
  Queue q(2, false);
  std::atomic<int> pushed{0};
  std::thread producer([&] {
    for (int i = 0; i < 6; ++i) {
      q.push(i);
      ++pushed;
    }
  });
  std::vector<int> got;
  for (int i = 0; i < 6; ++i) {
    got.push_back(take(q));
    // The producer is at most `capacity` frames ahead of the consumer (+1 being handed over).
    EXPECT_LE(pushed.load(), static_cast<int>(got.size()) + 2 + 1);
  }
  producer.join();
  EXPECT_EQ(got, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(q.counts().dropped, 0u);
}

TEST(RosSlamQueue, CommandsGoBeforeWaitingFrames) {
  Queue q(4, false);
  q.push(1);
  q.push(2);
  int ran = 0;
  EXPECT_TRUE(q.post([&] { ran = 7; }));
  EXPECT_EQ(take(q), -1);
  EXPECT_EQ(ran, 7);
  EXPECT_EQ(take(q), 1);
  EXPECT_EQ(take(q), 2);
}

TEST(RosSlamQueue, CloseWakesAProducerBlockedOnAFullQueue) {
  Queue q(1, false);
  ASSERT_TRUE(q.push(0));
  std::promise<bool> second;
  std::thread producer([&] { second.set_value(q.push(1)); });  // blocks: the queue is full
  q.close();
  auto result = second.get_future();
  EXPECT_FALSE(result.get()) << "a push after close() must be refused";
  producer.join();
  EXPECT_FALSE(q.post([] {}));
  EXPECT_EQ(take(q), -2) << "closed: the waiting frame is discarded";
  EXPECT_EQ(q.counts().discarded, 1u);
}

TEST(RosSlamQueue, CloseRunsTheCommandsAlreadyPostedAndEndsTheConsumer) {
  Queue q(4, true);
  q.push(5);
  int ran = 0;
  ASSERT_TRUE(q.post([&] { ++ran; }));
  q.close();
  EXPECT_EQ(take(q), -1);
  EXPECT_EQ(ran, 1);
  EXPECT_EQ(take(q), -2);
}

TEST(RosSlamQueue, ConsumerWaitingForWorkIsWokenByClose) {
  Queue q(1, true);
  std::promise<int> result;
  std::thread consumer([&] { result.set_value(take(q)); });
  q.close();
  EXPECT_EQ(result.get_future().get(), -2);
  consumer.join();
}

TEST(RosSlamQueue, WaitForEndsEarlyOnClose) {
  Queue q(1, true);
  std::promise<bool> waited;
  std::thread holder([&] { waited.set_value(q.waitFor(600.0)); });  // a frame held "forever"
  q.close();
  EXPECT_FALSE(waited.get_future().get()) << "close() must end the hold (the test would time out otherwise)";
  holder.join();
  EXPECT_FALSE(q.waitFor(0.0));
  Queue open(1, true);
  EXPECT_TRUE(open.waitFor(0.001));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
