#pragma once
// The tracking nodelet's hand-over to its SLAM thread: frames in a bounded
// queue, and commands (work of a service: reset, map export) that the SLAM thread runs
// between two frames, before any waiting frame.
//   live (drop_oldest): push() never blocks; a frame arriving at a full queue pushes out the
//     oldest waiting one (counted as dropped): the newest frame is processed next.
//   bag: push() blocks while the queue is full: no frame is lost, the producer waits.
// close() wakes every waiter: push() and post() refuse from then on, waitFor() returns early,
// next() still hands out the commands already posted (their callers wait for them), then
// returns false; the frames still waiting are discarded (counted).
// ROS-free: unit-tested without a master (test/unit/test_ros_slam_queue.cpp).
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <utility>

namespace vitamin_e_ros {

template <class Frame>
class SlamQueue {
 public:
  using Command = std::function<void()>;

  struct Counts {
    std::size_t capacity = 0;
    std::size_t pushed = 0;     // frames accepted
    std::size_t dropped = 0;    // pushed out by a newer frame (drop_oldest)
    std::size_t discarded = 0;  // still waiting at close()
    std::size_t waiting = 0;    // frames in the queue now
    bool busy = false;          // the consumer is on an item (from next() until its next call)
  };

  SlamQueue(std::size_t capacity, bool drop_oldest)
      : capacity_(capacity == 0 ? 1 : capacity), drop_oldest_(drop_oldest) {}

  // Producer. False when closed (the frame is discarded).
  bool push(Frame frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!drop_oldest_) not_full_.wait(lock, [&] { return closed_ || frames_.size() < capacity_; });
    if (closed_) return false;
    while (frames_.size() >= capacity_) {
      frames_.pop_front();
      ++dropped_;
    }
    frames_.push_back(std::move(frame));
    ++pushed_;
    changed_.notify_all();
    return true;
  }

  // Work for the consumer, run before the next frame. False when closed (not run).
  bool post(Command command) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return false;
    commands_.push_back(std::move(command));
    changed_.notify_all();
    return true;
  }

  // Consumer: blocks until there is a command (set *command) or a frame (set *frame), or the
  // queue is closed with no command left (returns false).
  bool next(std::optional<Frame>* frame, Command* command) {
    std::unique_lock<std::mutex> lock(mutex_);
    busy_ = false;
    frame->reset();
    *command = nullptr;
    changed_.wait(lock, [&] { return closed_ || !commands_.empty() || !frames_.empty(); });
    if (!commands_.empty()) {
      *command = std::move(commands_.front());
      commands_.pop_front();
    } else if (!closed_) {
      *frame = std::move(frames_.front());
      frames_.pop_front();
      not_full_.notify_one();
    } else {
      discarded_ += frames_.size();
      frames_.clear();
      return false;
    }
    busy_ = true;
    return true;
  }

  // Waits `seconds` unless the queue is closed first (returns false then).
  bool waitFor(double seconds) {
    std::unique_lock<std::mutex> lock(mutex_);
    return !changed_.wait_for(lock, std::chrono::duration<double>(seconds), [&] { return closed_; });
  }

  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    changed_.notify_all();
    not_full_.notify_all();
  }

  Counts counts() const {
    std::lock_guard<std::mutex> lock(mutex_);
    Counts c;
    c.capacity = capacity_;
    c.pushed = pushed_;
    c.dropped = dropped_;
    c.discarded = discarded_ + (closed_ ? frames_.size() : 0);
    c.waiting = frames_.size();
    c.busy = busy_;
    return c;
  }

  bool dropsOldest() const { return drop_oldest_; }

 private:
  const std::size_t capacity_;
  const bool drop_oldest_;
  mutable std::mutex mutex_;
  std::condition_variable changed_, not_full_;
  std::deque<Frame> frames_;
  std::deque<Command> commands_;
  std::size_t pushed_ = 0, dropped_ = 0, discarded_ = 0;
  bool busy_ = false;
  bool closed_ = false;
};

}  // namespace vitamin_e_ros
