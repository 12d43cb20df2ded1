#pragma once
// The queue between two of agvslamd's threads: bounded, and either
//   newest wins  push() never waits: when full, the oldest waiting item is dropped and counted (a camera: a late
//                frame is worth less than the next one), or
//   lossless     push() waits for room (a dataset played as fast as the pipeline goes: every frame processed).
// pop() waits at most a timeout, so a consumer loop stays alive (watchdog) while nothing arrives. close() wakes
// everyone: pushes are refused from then on and pop() returns what is left, then nothing.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace agvslam::daemon {

enum class QueuePolicy { kNewestWins, kLossless };

template <typename T>
class BoundedQueue {
 public:
  BoundedQueue(std::size_t capacity, QueuePolicy policy) : capacity_(capacity == 0 ? 1 : capacity), policy_(policy) {}
  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  // Newest wins: returns false when an older item was dropped to make room. Lossless: waits for room; returns false
  // only when the queue was closed (the item is discarded).
  bool push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (closed_) return false;
    bool kept_all = true;
    if (policy_ == QueuePolicy::kLossless) {
      not_full_.wait(lock, [&] { return items_.size() < capacity_ || closed_; });
      if (closed_) return false;
    } else if (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped_;
      kept_all = false;
    }
    items_.push_back(std::move(item));
    ++pushed_;
    not_empty_.notify_one();
    return kept_all;
  }

  // Waits up to `timeout` for an item. nullopt on timeout, or when closed and empty.
  template <typename Rep, typename Period>
  std::optional<T> pop(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!not_empty_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_; })) return std::nullopt;
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

  bool closed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_;
  }
  // True when closed and nothing is left to pop.
  bool drained() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_ && items_.empty();
  }
  std::size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  std::size_t capacity() const { return capacity_; }
  QueuePolicy policy() const { return policy_; }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  uint64_t pushed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }

 private:
  const std::size_t capacity_;
  const QueuePolicy policy_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t pushed_ = 0;
};

}  // namespace agvslam::daemon
