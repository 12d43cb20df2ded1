#include "agvslam/daemon/pose_builder.h"

#include <algorithm>
#include <cmath>

namespace agvslam::daemon {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

drivers::Matrix6d diagonal(double sd_translation, double sd_rotation) {
  drivers::Matrix6d m = drivers::Matrix6d::Zero();
  for (int i = 0; i < 3; ++i) m(i, i) = sd_translation * sd_translation;
  for (int i = 3; i < 6; ++i) m(i, i) = sd_rotation * sd_rotation;
  return m;
}

}  // namespace

drivers::TrackingState to_output_state(slam::TrackingState state) {
  switch (state) {
    case slam::TrackingState::kOk:
      return drivers::TrackingState::kTracking;
    case slam::TrackingState::kInitialising:
      return drivers::TrackingState::kNotInitialized;
    case slam::TrackingState::kLost:
      return drivers::TrackingState::kLost;
  }
  return drivers::TrackingState::kLost;
}

PoseSampleBuilder::PoseSampleBuilder(const SE3d& T_base_cam, const CovarianceConfig& covariance,
                                     double max_velocity_gap_s)
    : T_base_cam_(T_base_cam), T_cam_base_(T_base_cam.inverse()), cov_(covariance), max_gap_s_(max_velocity_gap_s) {}

double PoseSampleBuilder::position_sd_m(int inliers) const {
  const int n = std::max(inliers, cov_.min_inliers);
  return cov_.position_sd_m * std::sqrt(static_cast<double>(cov_.reference_inliers) / n);
}

double PoseSampleBuilder::rotation_sd_rad(int inliers) const {
  const int n = std::max(inliers, cov_.min_inliers);
  return cov_.rotation_sd_deg * kDegToRad * std::sqrt(static_cast<double>(cov_.reference_inliers) / n);
}

void PoseSampleBuilder::build(const slam::TrackResult& r, int64_t capture_t_ns, drivers::PoseSample& out) {
  out.t_ns = capture_t_ns;
  out.tracking_state = to_output_state(r.state);
  out.map_id = r.map_id;
  // A new map's poses are in another frame: no velocity from the difference with the old map's last pose.
  if (r.map_id != prev_map_id_) prev_valid_ = false;
  prev_map_id_ = r.map_id;
  if (r.state != slam::TrackingState::kOk || !r.pose_valid) {
    // No pose for this frame: the last good one (identity before the first), flagged by the state.
    out.T_map_base = prev_T_map_base_;
    out.cov_pose = drivers::Matrix6d::Identity() * kUnknownVariance;
    out.v_base_mps.setZero();
    out.w_base_radps.setZero();
    out.cov_twist = drivers::Matrix6d::Identity() * kUnknownVariance;
    prev_valid_ = false;
    return;
  }
  const SE3d T_map_base = to_base(r.T_w_c);
  out.T_map_base = T_map_base;
  const int inliers = r.counts.inliers;
  out.cov_pose = diagonal(position_sd_m(inliers), rotation_sd_rad(inliers));

  const double dt_s = static_cast<double>(capture_t_ns - prev_t_ns_) * 1e-9;
  if (prev_valid_ && dt_s > 0 && dt_s <= max_gap_s_) {
    const SE3d T_prev_cur = prev_T_map_base_.inverse() * T_map_base;
    const Eigen::AngleAxisd aa(T_prev_cur.linear());
    out.v_base_mps = T_prev_cur.translation() / dt_s;
    out.w_base_radps = aa.axis() * (aa.angle() / dt_s);
    const double scale = std::sqrt(static_cast<double>(cov_.reference_inliers) / std::max(inliers, cov_.min_inliers));
    out.cov_twist = diagonal(cov_.velocity_sd_mps * scale, cov_.angular_sd_degps * kDegToRad * scale);
  } else {
    out.v_base_mps.setZero();
    out.w_base_radps.setZero();
    out.cov_twist = drivers::Matrix6d::Identity() * kUnknownVariance;
  }
  prev_valid_ = true;
  ever_tracked_ = true;
  prev_T_map_base_ = T_map_base;
  prev_t_ns_ = capture_t_ns;
}

void PoseSampleBuilder::build_heartbeat(int64_t t_ns, bool ever_tracked, drivers::PoseSample& out) {
  out.t_ns = t_ns;
  out.tracking_state = ever_tracked ? drivers::TrackingState::kLost : drivers::TrackingState::kNotInitialized;
  out.cov_pose = drivers::Matrix6d::Identity() * kUnknownVariance;
  out.v_base_mps.setZero();
  out.w_base_radps.setZero();
  out.cov_twist = drivers::Matrix6d::Identity() * kUnknownVariance;
}

}  // namespace agvslam::daemon
