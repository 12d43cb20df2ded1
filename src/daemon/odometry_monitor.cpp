#include "agvslam/daemon/odometry_monitor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "agvslam/eval/odometry_check.h"

namespace agvslam::daemon {

using drivers::OdometryCheck;
using drivers::OdometryCheckState;

OdometryMonitor::OdometryMonitor(const OdometryMonitorConfig& config) : config_(config) {
  last_.state = OdometryCheckState::kNoOdometry;
}

void OdometryMonitor::add_odometry(const OdometryRate& sample) {
  if (!odometry_.empty() && sample.t_ns <= odometry_.back().t_ns) {
    ++odometry_out_of_order_;
    return;
  }
  ++odometry_samples_;
  odometry_.push_back(sample);
  // Keep one sample at or before the window's first pose (integration starts there; the poses lag the odometry by
  // the pipeline's latency), but never more than a window and kMaxLagS behind the newest sample (no poses for a
  // long while: nothing to compare with).
  constexpr double kMaxLagS = 60.0;
  const int64_t newest = odometry_.back().t_ns;
  int64_t keep_from = poses_.empty() ? newest - static_cast<int64_t>(config_.window_s * 1e9) : poses_.front().t_ns;
  keep_from = std::max(keep_from, newest - static_cast<int64_t>((config_.window_s + kMaxLagS) * 1e9));
  while (odometry_.size() > 2 && odometry_[1].t_ns <= keep_from) odometry_.pop_front();
}

OdometryCheckState OdometryMonitor::odometry_state(int64_t t_ns) const {
  if (odometry_samples_ == 0) return OdometryCheckState::kNoOdometry;
  if (t_ns - odometry_.back().t_ns > static_cast<int64_t>(config_.stale_ms) * 1000000)
    return OdometryCheckState::kStale;
  return OdometryCheckState::kOff;  // neither: the window decides
}

OdometryCheck OdometryMonitor::add_pose(int64_t t_ns, const SE3d& T_map_base, bool tracking) {
  if (!tracking) {
    poses_.clear();
  } else {
    if (!poses_.empty() && t_ns <= poses_.back().t_ns) poses_.clear();  // time went back (a dataset looped)
    poses_.push_back(StampedPose{t_ns, T_map_base});
    // The window: the newest pose at or before t - window_s, and everything after it.
    const int64_t start_ns = t_ns - static_cast<int64_t>(config_.window_s * 1e9);
    while (poses_.size() > 2 && poses_[1].t_ns <= start_ns) poses_.pop_front();
  }
  last_ = evaluate();
  const OdometryCheckState odo = odometry_state(t_ns);
  if (odo != OdometryCheckState::kOff) last_.state = odo;
  return last_;
}

OdometryCheck OdometryMonitor::status_at(int64_t t_ns) const {
  OdometryCheck c = last_;
  const OdometryCheckState odo = odometry_state(t_ns);
  if (odo != OdometryCheckState::kOff) c.state = odo;
  return c;
}

OdometryCheck OdometryMonitor::evaluate() const {
  OdometryCheck c;
  c.state = OdometryCheckState::kTooLittleMotion;
  if (poses_.size() < 2 || odometry_.size() < 2) return c;
  const int64_t odo_first = odometry_.front().t_ns, odo_last = odometry_.back().t_ns;
  const auto covered = std::count_if(poses_.begin(), poses_.end(),
                                     [&](const StampedPose& p) { return p.t_ns >= odo_first && p.t_ns <= odo_last; });
  if (covered < 2) return c;

  eval::OdometryCheckConfig ec;
  ec.disagreement_ratio = config_.tolerance;
  ec.distance_tolerance = config_.tolerance;
  ec.min_yaw_rate_degps = config_.min_yaw_rate_degps;
  const Trajectory poses(poses_.begin(), poses_.end());
  const eval::PlanarTrack odometry = eval::planar_track(std::vector<OdometryRate>(odometry_.begin(), odometry_.end()));
  const eval::OdometryCheckResult r = eval::check_against_odometry(poses, eval::BodyAxes::kBase, odometry, ec);
  c.distance_ratio = r.distance_ratio;
  c.speed_rmse_mps = r.speed_rmse_mps;
  c.heading_difference_deg = r.heading_difference_deg;
  c.window_s = r.duration_s;
  // Full: the compared span reaches back a window, less a pose period or so of slack.
  if (r.duration_s < 0.9 * config_.window_s) return c;
  const double heading_floor_deg = config_.min_yaw_rate_degps * r.duration_s;
  const bool moving = std::max(r.trajectory_distance_m, r.odometry_distance_m) >= config_.min_distance_m;
  const bool turning =
      std::max(std::abs(r.trajectory_heading_change_deg), std::abs(r.odometry_heading_change_deg)) >= heading_floor_deg;
  if (!moving && !turning) return c;
  const bool distance_off = moving && !(std::isfinite(r.distance_ratio) && r.distance_within_tolerance);
  const bool heading_off = std::abs(r.heading_difference_deg) >
                           config_.tolerance * std::max(std::abs(r.odometry_heading_change_deg), heading_floor_deg);
  c.state = distance_off || heading_off ? OdometryCheckState::kDisagrees : OdometryCheckState::kAgrees;
  return c;
}

}  // namespace agvslam::daemon
