#include "agvslam/slam/keyframe_worker.h"

#include <stdexcept>
#include <utility>

namespace agvslam::slam {

KeyframeWorker::KeyframeWorker(std::size_t capacity, WhenFull when_full, std::function<void(const KeyFramePtr&)> work)
    : capacity_(capacity), when_full_(when_full), work_(std::move(work)) {
  if (capacity_ == 0) throw std::invalid_argument("KeyframeWorker: the queue capacity must be at least 1");
}

KeyframeWorker::~KeyframeWorker() { stop(); }

void KeyframeWorker::start() {
  if (thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = false;
  }
  thread_ = std::thread([this] { run(); });
}

void KeyframeWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

KeyframeWorker::Pushed KeyframeWorker::push(const KeyFramePtr& kf) {
  Pushed result = Pushed::kQueued;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (queue_.size() >= capacity_) {
      if (when_full_ == WhenFull::kRefuseNew) return Pushed::kRefused;
      queue_.pop_front();
      result = Pushed::kQueuedDroppedOldest;
    }
    queue_.push_back(kf);
  }
  queue_cv_.notify_one();
  return result;
}

std::size_t KeyframeWorker::size() const {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return queue_.size();
}

bool KeyframeWorker::idle() const {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  return !busy_ && queue_.empty();
}

KeyFramePtr KeyframeWorker::take_locked() {
  if (queue_.empty()) return nullptr;
  KeyFramePtr kf = std::move(queue_.front());
  queue_.pop_front();
  busy_ = true;
  return kf;
}

void KeyframeWorker::done() {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  busy_ = false;
  if (queue_.empty()) idle_cv_.notify_all();
}

void KeyframeWorker::process_pending() {
  if (thread_.joinable()) return;
  for (;;) {
    KeyFramePtr kf;
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      kf = take_locked();
    }
    if (!kf) return;
    {
      std::lock_guard<std::mutex> work(work_mutex_);
      work_(kf);
    }
    done();
  }
}

void KeyframeWorker::wait_until_idle() {
  if (!thread_.joinable()) {
    process_pending();
    return;
  }
  std::unique_lock<std::mutex> lock(queue_mutex_);
  idle_cv_.wait(lock, [&] { return (!busy_ && queue_.empty()) || stop_; });
}

void KeyframeWorker::clear() {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  queue_.clear();
}

void KeyframeWorker::run() {
  for (;;) {
    KeyFramePtr kf;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (stop_) {
        busy_ = false;
        idle_cv_.notify_all();
        return;
      }
      kf = take_locked();
    }
    {
      std::lock_guard<std::mutex> work(work_mutex_);
      work_(kf);
    }
    done();
  }
}

}  // namespace agvslam::slam
