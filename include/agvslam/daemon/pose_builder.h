#pragma once
// Turns the tracker's result for one frame into the PoseSample every output publishes (REP-105).
//
// Frames. The SLAM estimates T_w_c: the rectified left camera c in the world w of the map, whose origin is the
// camera at the first keyframe (optical axes: z forward, x right, y down). The vehicle wants base_link in a map
// frame with z up. With T_base_cam (the extrinsic, BaseLinkConfig) the map frame is defined as base_link at the
// map's first keyframe:
//     T_map_base = T_base_cam * T_w_c * T_base_cam^-1
// so the vehicle starts at the origin with heading 0, and on a level floor the map's z axis is up.
//
// Velocity: finite difference of consecutive tracked poses, in base_link axes (nav_msgs/Odometry's twist):
//     T_prev_cur = T_map_base(prev)^-1 * T_map_base(cur),  v = t(T_prev_cur) / dt,  w = log(R(T_prev_cur)) / dt
// only when the previous frame was tracked too and 0 < dt <= max_velocity_gap; otherwise zero with a large
// covariance (1e6, "unknown").
// Covariance: CovarianceConfig's heuristic (diagonal; the tracker reports none).
// Map id: the tracker's (a new map after a long loss); no velocity across a change of map.
// States: kOk -> tracking (pose published); kInitialising -> not_initialized; kLost -> lost. A sample that is not
// tracking carries the last good pose (or identity before the first), zero twist and a 1e6 covariance: outputs
// that always carry a pose (CAN) flag it by the state, never with a made-up pose.

#include <cstdint>

#include "agvslam/daemon/daemon_config.h"
#include "agvslam/drivers/pose_sample.h"
#include "agvslam/slam/system.h"

namespace agvslam::daemon {

drivers::TrackingState to_output_state(slam::TrackingState state);

// Variance used for "unknown" (REP-147 style large value rather than -1, which some consumers reject).
inline constexpr double kUnknownVariance = 1e6;

class PoseSampleBuilder {
 public:
  PoseSampleBuilder(const SE3d& T_base_cam, const CovarianceConfig& covariance, double max_velocity_gap_s = 0.5);

  // Fills the pose, twist, covariance and state of `out` from one tracked frame (capture_t_ns: CLOCK_REALTIME
  // stamp; it becomes out.t_ns). The counters (frame_index, fps, ...) are the caller's.
  void build(const slam::TrackResult& result, int64_t capture_t_ns, drivers::PoseSample& out);

  // A sample for a moment with no new frame (heartbeat), from the last sample published: state lost
  // (not_initialized when no frame was ever tracked), its pose, unknown twist and covariance. Counters are kept.
  static void build_heartbeat(int64_t t_ns, bool ever_tracked, drivers::PoseSample& inout);

  SE3d to_base(const SE3d& T_w_c) const { return T_base_cam_ * T_w_c * T_cam_base_; }
  SE3d to_camera(const SE3d& T_map_base) const { return T_cam_base_ * T_map_base * T_base_cam_; }
  bool ever_tracked() const { return ever_tracked_; }
  const SE3d& T_base_cam() const { return T_base_cam_; }

  // Standard deviations of the heuristic for a pose from `inliers` map point inliers.
  double position_sd_m(int inliers) const;
  double rotation_sd_rad(int inliers) const;

 private:
  SE3d T_base_cam_, T_cam_base_;
  CovarianceConfig cov_;
  double max_gap_s_;
  bool ever_tracked_ = false;
  bool prev_valid_ = false;
  SE3d prev_T_map_base_ = SE3d::Identity();
  int64_t prev_t_ns_ = 0;
  uint32_t prev_map_id_ = 0;
};

}  // namespace agvslam::daemon
