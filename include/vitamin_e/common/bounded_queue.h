#pragma once
// A bounded, thread-safe FIFO joining two owned stages. push() either blocks
// while the queue is full (offline: every item is processed) or drops the
// oldest item (live: stale frames are not worth processing). close() wakes
// every waiter; pop() then drains what is left and returns false when empty.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>

namespace vitamin_e {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity, bool drop_oldest = false)
      : capacity_(capacity == 0 ? 1 : capacity), drop_oldest_(drop_oldest) {}

  // Returns false if the queue is closed (item discarded). *dropped counts the
  // items pushed out in drop-oldest mode.
  bool push(T item, std::size_t* dropped = nullptr) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!drop_oldest_) not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    while (items_.size() >= capacity_) {
      items_.pop_front();
      if (dropped) ++*dropped;
    }
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }

  // Blocks until an item is available or the queue is closed and empty.
  std::optional<T> pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }

  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  std::size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }

 private:
  const std::size_t capacity_;
  const bool drop_oldest_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace vitamin_e
