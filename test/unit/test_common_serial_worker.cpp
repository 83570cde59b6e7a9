// SerialWorker: jobs run on one other thread in the order posted; a full line waits or drops
// its oldest counted job, never an uncounted one; clear() and the destructor. A gate holds the
// worker in its first job, so that what waits is known without any timing. The worker thread's
// priority: the given nice levels below the poster's.
#include <gtest/gtest.h>

#include <algorithm>
#include <future>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "vitamin_e/common/serial_worker.h"
#include "vitamin_e/common/thread_priority.h"

namespace {

using vitamin_e::SerialWorker;
using vitamin_e::WhenFull;

// Job values >= 0 count against the capacity; negative ones (a "scaling") do not.
struct Recorder {
  std::mutex mutex;
  std::vector<int> ran;
  std::vector<std::thread::id> threads;
  std::shared_future<void> gate;  // the job 0 waits for it
  void run(const int& job) {
    if (job == 0 && gate.valid()) gate.wait();
    std::lock_guard<std::mutex> lock(mutex);
    ran.push_back(job);
    threads.push_back(std::this_thread::get_id());
  }
  std::vector<int> taken() {
    std::lock_guard<std::mutex> lock(mutex);
    return ran;
  }
};

std::unique_ptr<SerialWorker<int>> makeWorker(Recorder* r) {
  return std::make_unique<SerialWorker<int>>([r](int& job) { r->run(job); }, [](const int& job) { return job >= 0; });
}

// A worker held in job 0 (at the gate) with job 1 waiting behind it: posting 1 with capacity 1
// returns only once job 0 has left the line, i.e. runs. open_.set_value() lets it go on.
class HeldWorker : public ::testing::Test {
 protected:
  HeldWorker() {
    recorder_.gate = open_.get_future().share();
    worker_ = makeWorker(&recorder_);
    worker_->post(0, 1, WhenFull::kWait);
    worker_->post(1, 1, WhenFull::kWait);
  }
  Recorder recorder_;
  std::promise<void> open_;
  std::unique_ptr<SerialWorker<int>> worker_;
};

TEST(SerialWorker, RunsJobsInPostOrderOnOneOtherThread) {
  Recorder r;
  auto worker = makeWorker(&r);
  for (int i = 1; i <= 50; ++i) EXPECT_EQ(worker->post(i, 100, WhenFull::kWait), 0u);
  worker->waitIdle();
  std::vector<int> expected;
  for (int i = 1; i <= 50; ++i) expected.push_back(i);
  EXPECT_EQ(r.taken(), expected);
  for (const auto& id : r.threads) {
    EXPECT_EQ(id, r.threads.front());
    EXPECT_NE(id, std::this_thread::get_id());
  }
}

TEST_F(HeldWorker, AFullLineDropsItsOldestCountedJobNeverAnUncountedOne) {
  EXPECT_EQ(worker_->post(-1, 2, WhenFull::kDropOldest), 0u);
  EXPECT_EQ(worker_->post(2, 2, WhenFull::kDropOldest), 0u);  // line: 1, -1, 2
  EXPECT_EQ(worker_->post(3, 2, WhenFull::kDropOldest), 1u);  // drops 1 (not -1)
  EXPECT_EQ(worker_->post(-2, 2, WhenFull::kDropOldest), 0u);
  EXPECT_EQ(worker_->post(4, 2, WhenFull::kDropOldest), 1u);  // drops 2
  open_.set_value();
  worker_->waitIdle();
  EXPECT_EQ(recorder_.taken(), (std::vector<int>{0, -1, 3, -2, 4}));
}

TEST_F(HeldWorker, AWaitingPostLosesNothing) {
  std::promise<void> posted;
  std::thread poster([&] {
    EXPECT_EQ(worker_->post(2, 1, WhenFull::kWait), 0u);  // waits for job 1 to leave the line
    posted.set_value();
  });
  open_.set_value();
  posted.get_future().wait();
  poster.join();
  worker_->waitIdle();
  EXPECT_EQ(recorder_.taken(), (std::vector<int>{0, 1, 2}));
}

TEST_F(HeldWorker, ClearDropsTheWaitingJobsAndCountsTheCountedOnes) {
  worker_->post(-1, 10, WhenFull::kWait);
  worker_->post(2, 10, WhenFull::kWait);
  EXPECT_EQ(worker_->clear(), 2u);  // jobs 1 and 2; -1 is dropped too, uncounted
  open_.set_value();
  worker_->waitIdle();
  EXPECT_EQ(recorder_.taken(), (std::vector<int>{0}));
  worker_->post(5, 1, WhenFull::kWait);  // still working after a clear
  worker_->waitIdle();
  EXPECT_EQ(recorder_.taken(), (std::vector<int>{0, 5}));
}

TEST_F(HeldWorker, TheDestructorRunsWhatWaitsThenJoins) {
  worker_->post(2, 10, WhenFull::kWait);
  open_.set_value();
  worker_.reset();
  EXPECT_EQ(recorder_.taken(), (std::vector<int>{0, 1, 2}));
}

TEST(SerialWorker, WithoutAPostThereIsNoThreadAndNothingToWaitFor) {
  Recorder r;
  auto worker = makeWorker(&r);
  worker->waitIdle();
  EXPECT_EQ(worker->clear(), 0u);
  worker.reset();
  EXPECT_TRUE(r.taken().empty());
}

// The dense stages' threads yield the cores to the SLAM's: the worker runs its jobs the given
// number of nice levels below the thread that posted first (at most 19), 0 leaves it alone.
TEST(SerialWorker, RunsItsJobsTheGivenNiceLevelsBelowThePoster) {
  const int poster = vitamin_e::currentThreadNice();
  for (const int increment : {0, 3, 19}) {
    int seen = -100;
    {
      SerialWorker<int> worker([&seen](int&) { seen = vitamin_e::currentThreadNice(); }, {}, increment);
      worker.post(1, 1, WhenFull::kWait);
      worker.waitIdle();
    }
    EXPECT_EQ(seen, std::min(vitamin_e::kMaxNice, poster + increment)) << increment;
  }
  EXPECT_EQ(vitamin_e::currentThreadNice(), poster);  // the poster's own priority is untouched
  EXPECT_THROW(SerialWorker<int>([](int&) {}, {}, -1), std::invalid_argument);
  EXPECT_THROW(SerialWorker<int>([](int&) {}, {}, 20), std::invalid_argument);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
