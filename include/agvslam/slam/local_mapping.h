#pragma once
// The local-mapping stage (ORB-SLAM2's LocalMapping): for each new keyframe, in its own thread,
//   insertion (observations, covisibility, spanning tree) -> recent map point culling -> new map points by
//   triangulation with the covisible keyframes -> duplicate fusion with the neighbours -> local bundle adjustment
//   (Ceres, Schur complement, Huber loss) -> keyframe culling (90 % redundancy) -> hand-over to the next stage
//   (the loop-closing slot: set_keyframe_sink).
//
// Tracking hands keyframes over through a bounded queue (mapping.queue_capacity): try_insert() never blocks and
// returns false when the queue is full (tracking then skips the keyframe, as ORB-SLAM2 does). The map mutex is
// taken per step and released while Ceres solves, so tracking waits at most one step.
//
// Without start(), nothing runs in the background: process_pending() runs the queued keyframes in the caller's
// thread (deterministic runs and tests).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/keyframe_worker.h"
#include "agvslam/slam/matcher.h"
#include "agvslam/slam/optimizer.h"
#include "agvslam/slam/place_recognition.h"
#include "agvslam/slam/slam_config.h"

namespace agvslam::slam {

class Map;

struct LocalMappingStats {
  uint64_t keyframes_processed = 0;
  uint64_t points_created = 0;  // by triangulation
  uint64_t points_fused = 0;
  uint64_t points_culled = 0;  // recent points removed by the culling test
  uint64_t keyframes_culled = 0;
  uint64_t ba_runs = 0;
  uint64_t ba_aborted = 0;
  uint64_t ba_outliers = 0;        // observations removed by local BA
  uint64_t keyframes_skipped = 0;  // refused because the queue was full
  // Milliseconds of the last processed keyframe, per step.
  double insert_ms = 0, culling_ms = 0, triangulation_ms = 0, fusion_ms = 0, ba_ms = 0, kf_culling_ms = 0, total_ms = 0;
};

// Milliseconds per step for one keyframe.
struct KeyframeMappingTimes {
  uint64_t keyframe_id = 0;
  double insert_ms = 0, culling_ms = 0, triangulation_ms = 0, fusion_ms = 0, ba_ms = 0, kf_culling_ms = 0, total_ms = 0;
};

class LocalMapping {
 public:
  LocalMapping(const SlamConfig& config, Map& map, const StereoIntrinsics& intrinsics);
  ~LocalMapping();
  LocalMapping(const LocalMapping&) = delete;
  LocalMapping& operator=(const LocalMapping&) = delete;

  // Starts / stops the background thread (stop() finishes the keyframe in progress, leaves the rest queued).
  void start();
  void stop();
  bool running() const { return worker_.running(); }

  // Tracking side. Never blocks; false when the queue is full.
  bool try_insert(const KeyFramePtr& kf);
  std::size_t queue_length() const;
  // True while no keyframe is being processed and none is queued (ORB-SLAM2's AcceptKeyFrames).
  bool idle() const;
  // Asks a running local BA to stop at its next iteration (a new keyframe is waiting).
  void interrupt_ba() { abort_ba_.store(true); }

  // Runs the queued keyframes in the caller's thread (only when not started).
  void process_pending();
  // Blocks until the queue is empty and the mapper is idle (both modes).
  void wait_until_idle();
  // Drops the queued keyframes and the mapper's state; waits for the keyframe in progress. The caller then
  // clears the map, and keeps the returned (dropped) keyframes until it has: their points are in the map.
  [[nodiscard]] std::vector<KeyFramePtr> reset();
  // Tracking side: blocks up to timeout_ms until the queue has room for a keyframe (interrupting a local BA first);
  // true when it has. Without the thread: true when it has room now.
  bool wait_for_room(double timeout_ms);

  // The loop closer's input: called with each processed keyframe, in the mapping thread, without the map mutex
  // (it must not block).
  void set_keyframe_sink(std::function<void(const KeyFramePtr&)> sink) { sink_ = std::move(sink); }
  // The keyframe database (set before the first keyframe): keyframes get their BoW and enter the inverse index.
  void set_place_recognition(std::shared_ptr<PlaceRecognition> place) { place_ = std::move(place); }
  // Stops local mapping between keyframes for as long as the returned lock is held (loop correction, global BA
  // update, map saving): asks a running local BA to stop, then waits for the keyframe in progress. Keyframes
  // queued meanwhile are processed afterwards. Lock order: this before the map mutex.
  std::unique_lock<std::mutex> pause() {
    abort_ba_.store(true);
    return std::unique_lock<std::mutex>(worker_.work_mutex());
  }

  // TEST ONLY (a slower computer than the one running the tests): sleeps this long after each step of every
  // keyframe (insertion, culling, triangulation, fusion, local BA, keyframe culling), without the map mutex; an
  // interrupted BA (interrupt_ba) cuts its sleep short as it cuts the solver. 0: off. Never set on a vehicle.
  void set_test_step_delay_ms(double ms) { test_step_delay_ms_ = ms; }

  LocalMappingStats stats() const;
  // Per-keyframe step times since the start (a few dozen bytes per keyframe).
  std::vector<KeyframeMappingTimes> timing_history() const;

 private:
  void process(const KeyFramePtr& kf);
  void process_new_keyframe(KeyFrame& kf);
  void cull_recent_points(const KeyFrame& kf);
  void create_new_map_points(KeyFrame& kf);
  void search_in_neighbours(KeyFrame& kf);
  void local_bundle_adjustment(KeyFrame& kf);
  void cull_keyframes(KeyFrame& kf);
  void test_step_delay(bool abortable) const;

  SlamConfig config_;
  Map& map_;
  StereoIntrinsics intrinsics_;
  Matcher matcher_;

  std::atomic<bool> abort_ba_{false};
  double test_step_delay_ms_ = 0;

  std::list<MapPointPtr> recent_points_;
  std::function<void(const KeyFramePtr&)> sink_;
  std::shared_ptr<PlaceRecognition> place_;
  mutable std::mutex stats_mutex_;
  LocalMappingStats stats_;
  std::vector<KeyframeMappingTimes> history_;
  KeyframeWorker worker_;  // last: its thread stops before the members it uses go
};

}  // namespace agvslam::slam
