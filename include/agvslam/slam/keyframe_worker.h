#pragma once
// A bounded queue of keyframes served by one worker: its own thread after start(), or the caller's thread in
// process_pending() (deterministic runs and tests). Local mapping (tracking's keyframes; a full queue refuses the
// new one) and loop closing (local mapping's keyframes; a full queue drops its oldest) are both built on it.
//
// The stage's work function runs with the work mutex held; a stage that must stop the worker between keyframes
// (LocalMapping::pause, reset) takes that mutex.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "agvslam/core/bounded_queue.h"
#include "agvslam/slam/key_frame.h"

namespace agvslam::slam {

class KeyframeWorker {
 public:
  enum class WhenFull { kRefuseNew, kDropOldest };
  enum class Pushed { kQueued, kQueuedDroppedOldest, kRefused };

  // capacity >= 1 (std::invalid_argument otherwise).
  KeyframeWorker(std::size_t capacity, WhenFull when_full, std::function<void(const KeyFramePtr&)> work);
  ~KeyframeWorker();
  KeyframeWorker(const KeyframeWorker&) = delete;
  KeyframeWorker& operator=(const KeyframeWorker&) = delete;

  // Starts / stops the thread; stop() finishes the keyframe in progress and leaves the rest queued.
  void start();
  void stop();
  bool running() const { return thread_.joinable(); }

  // Never blocks.
  Pushed push(const KeyFramePtr& kf);
  std::size_t size() const { return queue_.size(); }
  bool empty() const { return queue_.empty(); }
  // No keyframe queued and none in progress.
  bool idle() const;
  // Without the thread: runs the queued keyframes in the caller's thread (nothing when the thread runs).
  void process_pending();
  // Thread: blocks until idle (or stopped). Without it: process_pending().
  void wait_until_idle();
  // Drops the queued keyframes (the one in progress goes on) and returns them: points that tracking created for a
  // queued keyframe are already in the map and observe it through a raw pointer, so the caller keeps them alive
  // until those points are gone.
  [[nodiscard]] std::vector<KeyFramePtr> clear();
  // Blocks until the queue has room for one more keyframe, the worker stops, or timeout_ms passes; true when there
  // is room. Without the thread: true when there is room now.
  bool wait_for_room(double timeout_ms);
  // Held while a keyframe is processed.
  std::mutex& work_mutex() { return work_mutex_; }

 private:
  void run();
  void process(const KeyFramePtr& kf);  // the work under the work mutex, then the keyframe counts as done

  const std::size_t capacity_;
  const std::function<void(const KeyFramePtr&)> work_;
  BoundedQueue<KeyFramePtr> queue_;

  // Keyframes queued or in progress: idle() is pending_ == 0, which a keyframe taken off the queue but not yet
  // processed does not satisfy.
  mutable std::mutex pending_mutex_;
  std::condition_variable idle_cv_;
  std::size_t pending_ = 0;
  std::atomic<bool> stop_{false};
  std::mutex work_mutex_;
  std::thread thread_;
};

}  // namespace agvslam::slam
