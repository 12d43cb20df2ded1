#pragma once
// The loop-closing stage (ORB-SLAM2's LoopClosing, stereo: poses are SE(3), the scale is known).
//
// For each keyframe that local mapping has finished (LocalMapping's keyframe sink -> a bounded queue):
//   1. detection: bag-of-words candidates that are not connected to the keyframe and score at least as well as
//      its worst covisible neighbour, grouped by covisibility (PlaceRecognition::loop_candidates); a candidate
//      is consistent when its group (it and its connected keyframes) overlaps a group of the previous keyframes
//      `consistency` times in a row (ORB-SLAM2: 3). A candidate that is not (yet) consistent is verified too, and
//      accepted when `covisible_consistency` of the keyframe's 5 best covisible keyframes confirm the corrected
//      pose (ORB-SLAM3's check in the covisibility graph: the loop neighbourhood's points, projected with the
//      neighbour's predicted pose, give >= min_refined_inliers inliers of a motion-only BA that moves it by at
//      most confirmation_max_m / confirmation_max_deg). An AGV's loop often overlaps its start for only a
//      keyframe or two before it stops;
//   2. verification: BoW matches with the candidate (>= min_bow_matches), 3-point SE(3) RANSAC on the 3-D
//      matches (inliers by reprojection in both keyframes), more matches by projection, a Ceres refinement
//      (>= min_refined_inliers), then projection of the candidate's whole neighbourhood with the corrected pose
//      (>= min_total_matches);
//   3. correction, with local mapping paused and the map mutex held: the keyframe's covisible neighbourhood moves
//      with it (poses and their map points), duplicated map points are fused (the loop's points replace the
//      current ones), the new covisibility links are collected, and the SE(3) pose graph over the essential graph
//      (spanning tree + covisibility >= essential_min_weight + loop edges + the new links) is optimised with
//      Ceres; every map point follows its reference keyframe's correction; a loop edge joins the two keyframes;
//   4. global bundle adjustment of all keyframes and points in a background thread, which never holds the map
//      while it solves (tracking and local mapping go on); its result is merged with local mapping paused:
//      optimised keyframes and points take their new values, keyframes created meanwhile follow their spanning-
//      tree parent's correction and other points their reference keyframe's (ORB-SLAM2's RunGlobalBundleAdjustment).
//      A new loop aborts a running global BA.
//
// Threads: start() runs steps 1-3 in their own thread. Without start(), process_pending() runs the queued
// keyframes, and the global BA, in the caller's thread (deterministic runs). Lock order: the loop closer's work,
// then LocalMapping::pause(), then the map mutex.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/keyframe_worker.h"
#include "agvslam/slam/matcher.h"
#include "agvslam/slam/optimizer.h"
#include "agvslam/slam/place_recognition.h"
#include "agvslam/slam/slam_config.h"

namespace agvslam::slam {

class Map;
class LocalMapping;

// One closed loop.
struct LoopEvent {
  uint64_t keyframe_id = 0, loop_keyframe_id = 0;  // the current keyframe and the matched old one
  uint64_t frame_id = 0, loop_frame_id = 0;
  int64_t t_ns = 0;
  int bow_matches = 0, ransac_inliers = 0, refined_inliers = 0, total_matches = 0;
  int confirmations = -1;  // covisible keyframes that confirmed it (-1: consistent over time, not needed)
  double correction_m = 0, correction_deg = 0;  // how far the keyframe moved
  int fused_points = 0;
  std::size_t graph_keyframes = 0, graph_edges = 0;
  double detect_ms = 0;   // detection + verification (map mutex held while matching)
  double correct_ms = 0;  // correction incl. pose graph (local mapping paused, map mutex held)
  double pose_graph_ms = 0;
  double global_ba_ms = -1;        // solve time of the global BA that followed (-1: none or aborted)
  double global_ba_merge_ms = -1;  // time the merge held the map
};

struct LoopClosingStats {
  uint64_t keyframes_processed = 0;
  uint64_t keyframes_dropped = 0;      // queue full: the oldest waiting keyframe was dropped
  uint64_t consistent_detections = 0;  // keyframes with a candidate consistent `consistency` times
  uint64_t rejected_geometry = 0;      // ... that failed verification
  uint64_t rejected_correction = 0;    // ... rejected by max_correction_m
  uint64_t loops_closed = 0;
  uint64_t global_ba_runs = 0, global_ba_aborted = 0;
  std::vector<LoopEvent> loops;
};

class LoopClosing {
 public:
  LoopClosing(const SlamConfig& config, Map& map, LocalMapping& mapper, std::shared_ptr<PlaceRecognition> place,
              const StereoIntrinsics& intrinsics);
  ~LoopClosing();
  LoopClosing(const LoopClosing&) = delete;
  LoopClosing& operator=(const LoopClosing&) = delete;

  void start();
  // Stops the thread (the keyframe in progress is finished) and aborts a running global BA.
  void stop();
  bool running() const { return worker_.running(); }

  // Local mapping's sink. Never blocks; drops the oldest queued keyframe when the queue is full.
  void insert(const KeyFramePtr& kf);
  std::size_t queue_length() const;
  // Runs the queued keyframes (and any global BA) in the caller's thread (only when not started).
  void process_pending();
  // Blocks until the queue is empty, no keyframe is being processed and no global BA runs.
  void wait_until_idle();
  // Drops the queue and the detection state, aborts a global BA (before the map is cleared or replaced).
  void reset();

  bool global_ba_running() const { return gba_running_.load(); }
  LoopClosingStats stats() const;

 private:
  struct ConsistentGroup {
    std::vector<uint64_t> keyframes;  // sorted ids
    int consistency = 0;
  };
  struct LoopCandidate {
    KeyFrame* kf = nullptr;
    bool consistent = false;  // consistent over `consistency` keyframes
  };

  void process(const KeyFramePtr& kf);
  bool detect_loop(KeyFrame& kf);
  bool verify_loop(KeyFrame& kf, LoopEvent& event);
  void correct_loop(KeyFrame& kf, LoopEvent& event);
  void release_candidates();
  // Covisible keyframes of kf whose predicted corrected pose the loop neighbourhood's points confirm.
  int covisible_confirmations(const KeyFrame& kf, std::vector<double>* errors);
  // Global BA: solve (without locks) then merge; loop_kf_id names the loop it follows.
  void run_global_ba(uint64_t loop_kf_id, std::size_t event_index);
  void start_global_ba(uint64_t loop_kf_id, std::size_t event_index);
  void stop_global_ba();

  SlamConfig config_;
  Map& map_;
  LocalMapping& mapper_;
  std::shared_ptr<PlaceRecognition> place_;
  StereoIntrinsics intrinsics_;
  Matcher matcher_;

  // Detection state (loop thread only).
  std::vector<ConsistentGroup> consistent_groups_;
  std::vector<LoopCandidate> enough_consistent_;
  uint64_t last_loop_kf_id_ = 0;
  // Verification result.
  KeyFrame* matched_kf_ = nullptr;
  bool matched_consistent_ = false;
  SE3d T_cur_w_corrected_ = SE3d::Identity();
  std::vector<MapPointPtr> current_matches_;  // per keypoint of the current keyframe: the loop's point
  std::vector<MapPointPtr> loop_points_;      // map points of the loop keyframe's neighbourhood

  // Global BA.
  std::thread gba_thread_;
  std::atomic<bool> gba_abort_{false};
  std::atomic<bool> gba_running_{false};

  mutable std::mutex stats_mutex_;
  LoopClosingStats stats_;
  KeyframeWorker worker_;  // last: its thread stops before the members it uses go
};

}  // namespace agvslam::slam
