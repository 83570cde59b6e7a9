#pragma once
// A thread that runs posted jobs one at a time, in the order they were posted: the dense
// stages' way off the caller's thread (DenseMapper's meshing, TsdfIntegrator's fusion).
// A job may count against the capacity of the waiting line (frames) or not (small jobs that
// must never be lost, such as a change of scale); when the line is full, post() waits for a
// place or drops the oldest counted job. The thread starts at the first post(), optionally at a
// lower priority than the poster's (lowerCurrentThreadPriority); the destructor runs what is
// still waiting, then joins.
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "vitamin_e/common/thread_priority.h"

namespace vitamin_e {

enum class WhenFull { kWait, kDropOldest };

template <typename Job>
class SerialWorker {
 public:
  using Run = std::function<void(Job&)>;
  using Counts = std::function<bool(const Job&)>;

  // `run` is called on the worker thread; `counts` says which jobs take a place in the line
  // (empty: all of them); the worker thread runs `nice_increment` nice levels below the thread
  // of the first post() (lowerCurrentThreadPriority; throws std::invalid_argument outside [0, 19]).
  explicit SerialWorker(Run run, Counts counts = {}, int nice_increment = 0)
      : run_(std::move(run)), counts_(std::move(counts)), nice_increment_(checkedNiceIncrement(nice_increment)) {}
  ~SerialWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    posted_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;

  // Queues `job` behind the others. When it counts and `capacity` counted jobs already wait,
  // waits until one is taken (kWait) or drops the oldest of them (kDropOldest). Returns the
  // number of jobs dropped.
  std::size_t post(Job job, std::size_t capacity, WhenFull when_full) {
    capacity = std::max<std::size_t>(1, capacity);
    std::size_t dropped = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
      if (counts(job) && countedWaiting() >= capacity) {
        if (when_full == WhenFull::kWait) {
          changed_.wait(lock, [&] { return stop_ || countedWaiting() < capacity; });
        } else {
          waiting_.erase(std::find_if(waiting_.begin(), waiting_.end(), [this](const Job& j) { return counts(j); }));
          ++dropped;
        }
      }
      waiting_.push_back(std::move(job));
    }
    posted_.notify_one();
    return dropped;
  }

  // Returns when every job posted so far has run (or was cleared).
  void waitIdle() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return waiting_.empty() && !running_; });
  }

  // Drops the waiting jobs (a running one finishes); returns how many of them counted.
  std::size_t clear() {
    std::size_t counted = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      counted = countedWaiting();
      waiting_.clear();
    }
    changed_.notify_all();
    return counted;
  }

 private:
  static int checkedNiceIncrement(int increment) {
    if (!isNiceIncrement(increment)) {
      throw std::invalid_argument("SerialWorker: the nice increment must be in [0, 19]");
    }
    return increment;
  }
  bool counts(const Job& job) const { return !counts_ || counts_(job); }
  std::size_t countedWaiting() const {
    return static_cast<std::size_t>(
        std::count_if(waiting_.begin(), waiting_.end(), [this](const Job& j) { return counts(j); }));
  }

  void loop() {
    // Not being allowed to lower its priority (another system) costs only the reason for it.
    lowerCurrentThreadPriority(nice_increment_);
    for (;;) {
      Job job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        posted_.wait(lock, [this] { return stop_ || !waiting_.empty(); });
        if (waiting_.empty()) return;  // stopped, and nothing is left to run
        job = std::move(waiting_.front());
        waiting_.pop_front();
        running_ = true;
      }
      changed_.notify_all();
      run_(job);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        running_ = false;
      }
      changed_.notify_all();
    }
  }

  const Run run_;
  const Counts counts_;
  const int nice_increment_;
  std::mutex mutex_;
  std::condition_variable posted_;   // a job arrived, or stop
  std::condition_variable changed_;  // a job was taken or finished, or the line was cleared
  std::deque<Job> waiting_;
  bool running_ = false;
  bool stop_ = false;
  std::thread thread_;  // last: started at the first post, after the members it uses
};

}  // namespace vitamin_e
