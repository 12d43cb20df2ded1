#include "agvslam/slam/keyframe_worker.h"

#include <chrono>
#include <utility>

namespace agvslam::slam {

KeyframeWorker::KeyframeWorker(std::size_t capacity, WhenFull when_full, std::function<void(const KeyFramePtr&)> work)
    : capacity_(capacity),
      work_(std::move(work)),
      queue_(capacity, when_full == WhenFull::kRefuseNew ? QueuePolicy::kRefuseNew : QueuePolicy::kNewestWins) {}

KeyframeWorker::~KeyframeWorker() { stop(); }

void KeyframeWorker::start() {
  if (thread_.joinable()) return;
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
}

void KeyframeWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    stop_.store(true);
  }
  idle_cv_.notify_all();
  queue_.wake();
  if (thread_.joinable()) thread_.join();
}

KeyframeWorker::Pushed KeyframeWorker::push(const KeyFramePtr& kf) {
  std::lock_guard<std::mutex> lock(pending_mutex_);
  switch (queue_.push(kf)) {
    case PushResult::kQueued:
      ++pending_;
      return Pushed::kQueued;
    case PushResult::kQueuedDroppedOldest:  // one queued keyframe replaced by another
      return Pushed::kQueuedDroppedOldest;
    case PushResult::kRefused:
    case PushResult::kClosed:
      break;
  }
  return Pushed::kRefused;
}

bool KeyframeWorker::idle() const {
  std::lock_guard<std::mutex> lock(pending_mutex_);
  return pending_ == 0;
}

void KeyframeWorker::process(const KeyFramePtr& kf) {
  {
    std::lock_guard<std::mutex> work(work_mutex_);
    work_(kf);
  }
  std::lock_guard<std::mutex> lock(pending_mutex_);
  --pending_;
  idle_cv_.notify_all();  // idle waiters and trackers waiting for room
}

void KeyframeWorker::process_pending() {
  if (thread_.joinable()) return;
  while (std::optional<KeyFramePtr> kf = queue_.try_pop()) process(*kf);
}

void KeyframeWorker::wait_until_idle() {
  if (!thread_.joinable()) {
    process_pending();
    return;
  }
  std::unique_lock<std::mutex> lock(pending_mutex_);
  idle_cv_.wait(lock, [&] { return pending_ == 0 || stop_.load(); });
}

std::vector<KeyFramePtr> KeyframeWorker::clear() {
  std::vector<KeyFramePtr> dropped;
  std::lock_guard<std::mutex> lock(pending_mutex_);
  while (std::optional<KeyFramePtr> kf = queue_.try_pop()) dropped.push_back(std::move(*kf));
  pending_ -= dropped.size();
  idle_cv_.notify_all();
  return dropped;
}

bool KeyframeWorker::wait_for_room(double timeout_ms) {
  std::unique_lock<std::mutex> lock(pending_mutex_);
  if (!thread_.joinable()) return queue_.size() < capacity_;
  return idle_cv_.wait_for(lock, std::chrono::duration<double, std::milli>(timeout_ms), [&] {
    return queue_.size() < capacity_ || stop_.load();
  }) && queue_.size() < capacity_;
}

void KeyframeWorker::run() {
  while (std::optional<KeyFramePtr> kf = queue_.pop_unless([this] { return stop_.load(); })) {
    {
      std::lock_guard<std::mutex> lock(pending_mutex_);  // a tracker waiting for room sees it now
    }
    idle_cv_.notify_all();
    process(*kf);
  }
}

}  // namespace agvslam::slam
