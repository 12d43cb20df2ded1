#pragma once
// The queue between two threads (agvslamd's and agvslam-run's pipeline stages, local mapping and loop closing):
// bounded, and when it is full a push either
//   newest wins  never waits: the oldest waiting item is dropped and counted (a camera: a late frame is worth
//                less than the next one; loop closing: the newest keyframes matter most),
//   refuse new   never waits: the new item is refused and counted (local mapping: tracking offers the next
//                keyframe again later), or
//   lossless     waits for room (a dataset played as fast as the pipeline goes: every frame processed).
// pop() waits at most a timeout, so a consumer loop stays alive (watchdog) while nothing arrives; pop_unless()
// waits until an item arrives or the caller's stop condition holds. close() wakes everyone: pushes are refused
// from then on and pop() returns what is left, then nothing.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>

namespace agvslam {

enum class QueuePolicy { kNewestWins, kRefuseNew, kLossless };

enum class PushResult {
  kQueued,               // room was there (or, lossless, made)
  kQueuedDroppedOldest,  // newest wins: queued, the oldest item dropped for it
  kRefused,              // refuse new: the queue was full, the item is discarded
  kClosed,               // the queue was closed, the item is discarded
};

template <typename T>
class BoundedQueue {
 public:
  // capacity >= 1 (std::invalid_argument otherwise).
  BoundedQueue(std::size_t capacity, QueuePolicy policy) : capacity_(capacity), policy_(policy) {
    if (capacity_ == 0) throw std::invalid_argument("BoundedQueue: the capacity must be at least 1");
  }
  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  PushResult push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (closed_) return PushResult::kClosed;
    PushResult result = PushResult::kQueued;
    if (items_.size() >= capacity_) {
      switch (policy_) {
        case QueuePolicy::kLossless:
          not_full_.wait(lock, [&] { return items_.size() < capacity_ || closed_; });
          if (closed_) return PushResult::kClosed;
          break;
        case QueuePolicy::kNewestWins:
          items_.pop_front();
          ++dropped_;
          result = PushResult::kQueuedDroppedOldest;
          break;
        case QueuePolicy::kRefuseNew:
          ++dropped_;
          return PushResult::kRefused;
      }
    }
    items_.push_back(std::move(item));
    ++pushed_;
    not_empty_.notify_one();
    return result;
  }

  // Waits up to `timeout` for an item. nullopt on timeout, or when closed and empty.
  template <typename Rep, typename Period>
  std::optional<T> pop(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!not_empty_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_; })) return std::nullopt;
    return take_locked();
  }

  // Waits until an item arrives or `stop()` is true; nullopt once stop() is true (items stay queued) or the queue
  // is closed and empty. stop() is evaluated under the queue's lock: whoever makes it true calls wake() after.
  template <typename Stop>
  std::optional<T> pop_unless(Stop stop) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return stop() || !items_.empty() || closed_; });
    if (stop()) return std::nullopt;
    return take_locked();
  }

  // Never waits.
  std::optional<T> try_pop() {
    std::lock_guard<std::mutex> lock(mutex_);
    return take_locked();
  }

  // Wakes every pop_unless() to evaluate its stop condition again.
  void wake() {
    std::lock_guard<std::mutex> lock(mutex_);
    not_empty_.notify_all();
  }

  // Discards what is queued (not counted as dropped); returns how many items that was.
  std::size_t clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::size_t n = items_.size();
    items_.clear();
    not_full_.notify_all();
    return n;
  }

  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
    not_full_.notify_all();
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
  bool empty() const { return size() == 0; }
  // Items lost to a full queue: dropped (newest wins) or refused (refuse new).
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  // Items accepted.
  uint64_t pushed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }

 private:
  std::optional<T> take_locked() {
    if (items_.empty()) return std::nullopt;
    std::optional<T> item(std::move(items_.front()));
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }

  const std::size_t capacity_;
  const QueuePolicy policy_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false;
  uint64_t dropped_ = 0;
  uint64_t pushed_ = 0;
};

}  // namespace agvslam
