#pragma once
// A bounded queue of keyframes served by one worker: its own thread after start(), or the caller's thread in
// process_pending() (deterministic runs and tests). Local mapping (tracking's keyframes; a full queue refuses the
// new one) and loop closing (local mapping's keyframes; a full queue drops its oldest) are both built on it.
//
// The stage's work function runs with the work mutex held; a stage that must stop the worker between keyframes
// (LocalMapping::pause, reset) takes that mutex.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include "agvslam/slam/key_frame.h"

namespace agvslam::slam {

class KeyframeWorker {
 public:
  enum class WhenFull { kRefuseNew, kDropOldest };
  enum class Pushed { kQueued, kQueuedDroppedOldest, kRefused };

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
  std::size_t size() const;
  bool empty() const { return size() == 0; }
  // No keyframe queued and none in progress.
  bool idle() const;
  // Without the thread: runs the queued keyframes in the caller's thread (nothing when the thread runs).
  void process_pending();
  // Thread: blocks until idle (or stopped). Without it: process_pending().
  void wait_until_idle();
  // Drops the queued keyframes (the one in progress goes on).
  void clear();
  // Held while a keyframe is processed.
  std::mutex& work_mutex() { return work_mutex_; }

 private:
  void run();
  // Takes the next keyframe off the queue and marks the worker busy; null when the queue is empty.
  KeyFramePtr take_locked();
  void done();

  const std::size_t capacity_;
  const WhenFull when_full_;
  const std::function<void(const KeyFramePtr&)> work_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_, idle_cv_;
  std::deque<KeyFramePtr> queue_;
  bool busy_ = false;
  bool stop_ = false;
  std::mutex work_mutex_;
  std::thread thread_;
};

}  // namespace agvslam::slam
