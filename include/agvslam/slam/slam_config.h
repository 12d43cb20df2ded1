#pragma once
// Settings of the stereo SLAM back end (tracking, local mapping, optimiser), one struct per stage, loaded from
// params/slam.yaml. Defaults are ORB-SLAM2's stereo values (paper 004 III.C uses ORB-SLAM2's framework); every
// value is explained in params/slam.yaml. Each section's keys, ranges, units and echo are one table in
// src/slam/slam_config.cpp (agvslam/core/param_table.h).

#include <string>
#include <vector>

namespace agvslam::slam {

// Section `tracking`.
struct TrackingConfig {
  // A stereo point is "close" (trusted for depth, created as a map point at once) when its depth is below
  // close_depth_baselines * baseline_m (ORB-SLAM2's ThDepth: 35-40 baselines).
  double close_depth_baselines = 40.0;
  int min_init_features = 500;        // stereo initialisation needs more keypoints than this (ORB-SLAM2) ...
  int min_init_stereo = 100;          // ... of which at least this many with stereo depth
  int motion_model_radius_px = 7;     // search window (x scale of the level) when projecting the last frame
  int min_motion_model_matches = 20;  // below this the window is doubled, then the model is given up
  int min_frame_inliers = 10;         // motion-model / reference-keyframe tracking succeeds above this
  int min_reference_matches = 15;     // reference-keyframe tracking needs this many descriptor matches
  double reference_ratio = 0.7;       // best-to-second ratio of the reference-keyframe matching
  bool bow_matching = true;           // reference keyframe matched by bag of words (brute force without a vocabulary)
  double local_map_radius = 1.0;      // search window factor for local map points (ORB-SLAM2's th = 1)
  int min_local_map_inliers = 30;     // local-map tracking succeeds with at least this many inliers
  int max_local_keyframes = 80;       // size cap of the local map (keyframes)
  // Keyframe decision (ORB-SLAM2's NeedNewKeyFrame).
  int keyframe_max_frames = 0;  // insert at least every this many frames (0 = the frame rate)
  int keyframe_min_frames = 0;
  double keyframe_ref_ratio = 0.75;   // fewer inliers than this x the reference keyframe's tracked points
  int keyframe_close_tracked = 100;   // close points: fewer tracked than this and ...
  int keyframe_close_untracked = 70;  // ... more untracked than this -> insert
  int keyframe_max_new_points = 100;  // a new keyframe creates at least this many of its closest stereo points
  // Revisits: no new keyframe where an older keyframe (made >= keyframe_revisit_min_age_s before the frame)
  // already sees the place from within keyframe_revisit_distance_m and keyframe_revisit_angle_deg and observes at
  // least keyframe_revisit_shared of the frame's inliers; tracking takes it as the reference instead. This keeps the
  // map bounded when the vehicle drives the same route again. keyframe_revisit_distance_m = 0 turns it off.
  double keyframe_revisit_distance_m = 0.2;
  double keyframe_revisit_angle_deg = 10.0;
  double keyframe_revisit_shared = 0.5;
  double keyframe_revisit_min_age_s = 1.0;
  // Stops: a keyframe when the camera comes to rest (speed <= keyframe_stop_speed_mps) at least
  // keyframe_stop_distance_m from where the last keyframe was made (0 = off).
  double keyframe_stop_speed_mps = 0.1;
  double keyframe_stop_distance_m = 0.2;
  // Loss: after this many consecutive failed frames with a map of fewer than reset_max_keyframes keyframes, the
  // map is reset and initialised again (ORB-SLAM2 does the same with <= 5 keyframes).
  int reset_max_keyframes = 5;
  int reset_after_lost_frames = 5;
  // A keyframe is due but local mapping's queue is full: tracking waits up to this long (ms) for room rather than
  // skip it (0: skip at once, as ORB-SLAM2 does), and up to keyframe_queue_wait_weak_ms when the frame has, or at
  // its inliers' decline since the last frame the next frame will have, fewer than twice min_local_map_inliers.
  double keyframe_queue_wait_ms = 100;
  double keyframe_queue_wait_weak_ms = 1000;
  // Lost this long (s, by frame time stamps, counting only frames with enough features to start a map) without
  // relocalising: a new map is started from the current stereo frame (0: never; loaded maps are never replaced).
  double new_map_after_lost_s = 1.0;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `mapping`.
struct LocalMappingConfig {
  int queue_capacity = 3;             // keyframes waiting for the local mapper (tracking skips a keyframe when full)
  int triangulation_neighbours = 10;  // covisible keyframes searched for new map points
  bool triangulation_bow = false;     // true: candidate pairs from the vocabulary's direct index (ORB-SLAM2);
                                      // false: epipolar-segment search (more accurate: params/slam.yaml)
  int fusion_neighbours = 10;         // first-order neighbours for duplicate fusion (+ 5 second-order each)
  int fusion_second_order = 5;
  double fusion_radius = 3.0;               // search window factor (x scale) for duplicate fusion
  int local_ba_iterations_first = 5;        // robust pass
  int local_ba_iterations_second = 10;      // after outlier removal
  int max_local_ba_keyframes = 20;          // optimised keyframes (covisible with the new one, best first)
  double map_point_min_found_ratio = 0.25;  // culled below found/visible
  int map_point_min_observations = 3;       // culled when seen by fewer keyframes 2 keyframes after its creation
  double keyframe_redundancy = 0.9;         // culled when this fraction of its points is seen by >= 3 others
  int keyframe_redundancy_observers = 3;
  int max_keyframes = 0;  // hard cap on the map (oldest redundant removed first); 0 = no cap

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `optimizer`.
struct OptimizerConfig {
  double chi2_mono = 5.991;          // 95 % of chi-square with 2 DOF
  double chi2_stereo = 7.815;        // 95 % of chi-square with 3 DOF
  int motion_rounds = 4;             // motion-only BA: rounds of optimise + outlier classification
  int motion_iterations = 10;        // per round
  int motion_robust_rounds = 2;      // the Huber loss is used in the first rounds only (ORB-SLAM2: 2)
  bool local_ba_dense_schur = true;  // DENSE_SCHUR for the reduced camera system (SPARSE_SCHUR otherwise)

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `relocalisation` (ORB-SLAM2's Relocalization): bag-of-words candidates, BoW matching, PnP RANSAC
// (EPnP), motion-only BA, projection search for more matches.
struct RelocalisationConfig {
  int max_candidates = 10;             // candidate keyframes tried per frame (best group first)
  int min_bow_matches = 15;            // a candidate needs this many BoW matches for PnP
  double bow_ratio = 0.75;             // best-to-second ratio of the BoW matching
  int pnp_iterations = 300;            // RANSAC iterations per candidate
  double pnp_reprojection_px = 4.0;    // RANSAC inlier threshold (px, level 0)
  int min_pnp_inliers = 10;            // PnP needs this many inliers
  int min_inliers = 50;                // inliers after motion-only BA + projection search for success
  double projection_radius_px = 10.0;  // first projection search window (then 3 px, distance <= 64)

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `loop_closing` (ORB-SLAM2's LoopClosing, stereo: SE(3), scale known).
struct LoopClosingConfig {
  bool enabled = true;                   // needs a vocabulary
  int queue_capacity = 20;               // keyframes waiting for the loop closer (the oldest is dropped when full)
  int min_keyframes_between_loops = 10;  // no loop detection within this many keyframes of the last loop / start
  int consistency = 3;                   // covisibility-consistent candidate groups in a row (ORB-SLAM2)
  int covisible_consistency = 1;         // ... or covisible keyframes confirming a verified candidate (0: off)
  double confirmation_max_m = 0.05;      // a confirming keyframe's pose moves at most this much ...
  double confirmation_max_deg = 1.0;     // ... and turns at most this much from its predicted corrected pose
  double bow_ratio = 0.75;               // BoW matching ratio between the keyframe and a candidate
  int min_bow_matches = 20;              // candidates with fewer BoW matches are discarded
  int ransac_iterations = 300;           // 3-point SE(3) RANSAC on the 3-D matches
  double ransac_chi2 = 9.210;            // inlier test: reprojection chi-square (2 DOF, 99 %) in both keyframes
  int min_ransac_inliers = 20;
  double projection_radius_px = 7.5;  // SearchBySim3 window (then 10 px for the loop neighbourhood)
  int min_refined_inliers = 20;       // after the SE(3) refinement
  int min_total_matches = 40;         // matches with the whole loop neighbourhood to accept the loop
  double max_correction_m = 0;        // reject loops that move the keyframe by more than this (0: no limit)
  int essential_min_weight = 100;     // covisibility edges of the essential graph
  int pose_graph_iterations = 20;
  bool global_ba = true;  // global bundle adjustment after each loop (background thread)
  int global_ba_iterations = 10;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `retirement`: map points on objects that move after they were mapped (a parked forklift drives off, a
// pallet is carried away) leave the map. Each frame, every local map point predicted in view gives evidence: it
// lies in the dynamic mask with the image showing a surface at its depth (the object it lies on moves), or it is
// not matched and the image shows a surface behind where it should be (it left). A point with evidence in
// min_frames of its last window_frames conclusive frames, one of them a surface behind it, is retired: removed from
// the map and its keyframes, whose keypoints never carry a point again.
struct RetirementConfig {
  bool enabled = true;              // params/slam.yaml says why
  int window_frames = 6;            // conclusive frames remembered per point
  int min_frames = 3;               // ... of which this many with evidence retire it
  double chi2_mono = 9.210;         // 99 % of chi-square with 2 DOF: a match within it renews the reference
  double chi2_stereo = 11.345;      // 99 % of chi-square with 3 DOF: the same with stereo
  double depth_chi2 = 6.635;        // 99 % of chi-square with 1 DOF: disparity agreement of the image probe
  double probe_sigma_px = 1.0;      // the probe's own disparity noise (integer search + parabola), px
  int probe_half_size_px = 3;       // probe patch (2 h + 1)^2 px in the left and right image
  double probe_min_zncc = 0.8;      // a patch pair at this correlation or above shows a surface at that disparity
  double probe_min_contrast = 4.0;  // grey-level standard deviation below which a patch says nothing

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct SlamConfig {
  TrackingConfig tracking;
  LocalMappingConfig mapping;
  OptimizerConfig optimizer;
  RelocalisationConfig relocalisation;
  LoopClosingConfig loop_closing;
  RetirementConfig retirement;

  void validate(const std::string& source) const;
  std::vector<std::string> describe() const;
};

// Loads params/slam.yaml over the defaults (absent keys keep their default). Throws InputError naming the file and
// the field for a missing file, bad YAML, an unknown key, or a value of the wrong type or out of range.
SlamConfig load_slam_config(const std::string& path);

}  // namespace agvslam::slam
