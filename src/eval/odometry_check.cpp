#include "agvslam/eval/odometry_check.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "agvslam/core/error.h"

namespace agvslam::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

Eigen::Vector3d body_up(BodyAxes axes) {
  return axes == BodyAxes::kCamera ? Eigen::Vector3d(0, -1, 0) : Eigen::Vector3d(0, 0, 1);
}

double wrap_pi(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a <= -M_PI) a += 2 * M_PI;
  return a;
}

// The rotation's angle about `axis` (unit, body frame): the twist of its swing-twist decomposition.
double twist_angle(const Eigen::Matrix3d& R, const Eigen::Vector3d& axis) {
  const Eigen::Quaterniond q(R);
  return wrap_pi(2.0 * std::atan2(q.vec().dot(axis), q.w()));
}

// Linear interpolation of a track's accumulated values at t_ns (inside its span).
void sample(const PlanarTrack& track, int64_t t_ns, double& distance_m, double& heading_rad) {
  const auto it = std::lower_bound(track.t_ns.begin(), track.t_ns.end(), t_ns);
  std::size_t k = static_cast<std::size_t>(it - track.t_ns.begin());
  if (k == 0) {
    distance_m = track.distance_m.front();
    heading_rad = track.heading_rad.front();
    return;
  }
  if (k >= track.t_ns.size()) k = track.t_ns.size() - 1;
  const double t0 = static_cast<double>(track.t_ns[k - 1]), t1 = static_cast<double>(track.t_ns[k]);
  const double a = t1 > t0 ? (static_cast<double>(t_ns) - t0) / (t1 - t0) : 1.0;
  distance_m = track.distance_m[k - 1] + a * (track.distance_m[k] - track.distance_m[k - 1]);
  heading_rad = track.heading_rad[k - 1] + a * (track.heading_rad[k] - track.heading_rad[k - 1]);
}

}  // namespace

BodyAxes parse_body_axes(const std::string& value, const std::string& option) {
  if (value == "camera") return BodyAxes::kCamera;
  if (value == "base") return BodyAxes::kBase;
  throw InputError(option, value, "expected camera (x right, y down, z forward) or base (REP-103: x forward, z up)");
}

PlanarTrack planar_track(const Trajectory& poses, BodyAxes axes) {
  PlanarTrack track;
  if (poses.empty()) return track;
  const Eigen::Vector3d up_b = body_up(axes);
  const Eigen::Vector3d up_w = poses.front().T_w_c.linear() * up_b;
  double distance = 0, heading = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) {
      const Eigen::Vector3d dp = poses[i].T_w_c.translation() - poses[i - 1].T_w_c.translation();
      distance += (dp - dp.dot(up_w) * up_w).norm();
      const Eigen::Matrix3d R_rel = poses[i - 1].T_w_c.linear().transpose() * poses[i].T_w_c.linear();
      heading += twist_angle(R_rel, up_b);
    }
    track.t_ns.push_back(poses[i].t_ns);
    track.distance_m.push_back(distance);
    track.heading_rad.push_back(heading);
  }
  return track;
}

PlanarTrack planar_track(const std::vector<OdometryRate>& rates) {
  PlanarTrack track;
  double distance = 0, heading = 0;
  for (std::size_t i = 0; i < rates.size(); ++i) {
    if (i > 0) {
      const double dt = ns_to_s(rates[i].t_ns - rates[i - 1].t_ns);
      distance += 0.5 * (std::abs(rates[i].speed_mps) + std::abs(rates[i - 1].speed_mps)) * dt;
      heading += 0.5 * (rates[i].yaw_rate_radps + rates[i - 1].yaw_rate_radps) * dt;
    }
    track.t_ns.push_back(rates[i].t_ns);
    track.distance_m.push_back(distance);
    track.heading_rad.push_back(heading);
  }
  return track;
}

OdometryCheckResult check_against_odometry(const Trajectory& trajectory, BodyAxes trajectory_axes,
                                           const PlanarTrack& odometry, const OdometryCheckConfig& config,
                                           const std::string& source) {
  if (odometry.t_ns.size() < 2) throw InputError(source, "", "expected at least 2 odometry samples");
  const PlanarTrack est = planar_track(trajectory, trajectory_axes);
  // The trajectory poses inside the odometry's time span.
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < est.t_ns.size(); ++i) {
    if (est.t_ns[i] >= odometry.t_ns.front() && est.t_ns[i] <= odometry.t_ns.back()) frames.push_back(i);
  }
  if (frames.size() < 2) {
    throw InputError(source, "",
                     "expected odometry covering the trajectory's time stamps (they share " +
                         std::to_string(frames.size()) + " poses)");
  }
  OdometryCheckResult r;
  r.frames_compared = frames.size();
  const int64_t t0 = est.t_ns[frames.front()];
  r.duration_s = ns_to_s(est.t_ns[frames.back()] - t0);

  std::vector<double> odo_d(frames.size()), odo_h(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) sample(odometry, est.t_ns[frames[k]], odo_d[k], odo_h[k]);
  const auto est_d = [&](std::size_t k) { return est.distance_m[frames[k]]; };
  const auto est_h = [&](std::size_t k) { return est.heading_rad[frames[k]]; };
  const std::size_t last = frames.size() - 1;

  r.trajectory_distance_m = est_d(last) - est_d(0);
  r.odometry_distance_m = odo_d[last] - odo_d[0];
  r.distance_ratio = r.odometry_distance_m > 1e-9 ? r.trajectory_distance_m / r.odometry_distance_m
                                                  : std::numeric_limits<double>::quiet_NaN();
  r.distance_within_tolerance = std::isnan(r.distance_ratio)
                                    ? r.trajectory_distance_m < 0.05
                                    : std::abs(r.distance_ratio - 1) <= config.distance_tolerance;
  r.trajectory_heading_change_deg = (est_h(last) - est_h(0)) * kRadToDeg;
  r.odometry_heading_change_deg = (odo_h[last] - odo_h[0]) * kRadToDeg;
  r.heading_difference_deg = r.trajectory_heading_change_deg - r.odometry_heading_change_deg;
  for (std::size_t k = 0; k <= last; ++k) {
    const double diff = ((est_h(k) - est_h(0)) - (odo_h[k] - odo_h[0])) * kRadToDeg;
    r.max_heading_difference_deg = std::max(r.max_heading_difference_deg, std::abs(diff));
  }

  // Windows of at least window_s, back to back.
  const auto window_ns = static_cast<int64_t>(config.window_s * 1e9);
  const double min_yaw_rate = config.min_yaw_rate_degps / kRadToDeg;
  double speed_sq = 0;
  bool open = false;
  for (std::size_t a = 0; a < last;) {
    std::size_t b = a + 1;
    while (b < last && est.t_ns[frames[b]] - est.t_ns[frames[a]] < window_ns) ++b;
    const double dt = ns_to_s(est.t_ns[frames[b]] - est.t_ns[frames[a]]);
    const double d_est = est_d(b) - est_d(a), d_odo = odo_d[b] - odo_d[a];
    const double h_est = est_h(b) - est_h(a), h_odo = odo_h[b] - odo_h[a];
    ++r.windows;
    if (dt > 0) speed_sq += std::pow((d_est - d_odo) / dt, 2);
    bool disagrees = false;
    if (dt > 0 && std::max(d_est, d_odo) / dt >= config.min_speed_mps) {
      disagrees = std::abs(d_est - d_odo) > config.disagreement_ratio * std::max(d_odo, config.min_speed_mps * dt);
    }
    if (dt > 0 && std::max(std::abs(h_est), std::abs(h_odo)) / dt >= min_yaw_rate) {
      disagrees = disagrees ||
                  std::abs(h_est - h_odo) > config.disagreement_ratio * std::max(std::abs(h_odo), min_yaw_rate * dt);
    }
    if (disagrees) {
      ++r.disagreeing_windows;
      if (!open) {
        OdometryDisagreement d;
        d.first_frame = frames[a];
        d.t_first_s = ns_to_s(est.t_ns[frames[a]] - t0);
        r.disagreements.push_back(d);
        open = true;
      }
      OdometryDisagreement& d = r.disagreements.back();
      d.last_frame = frames[b];
      d.t_last_s = ns_to_s(est.t_ns[frames[b]] - t0);
      d.trajectory_m += d_est;
      d.odometry_m += d_odo;
      d.trajectory_heading_deg += h_est * kRadToDeg;
      d.odometry_heading_deg += h_odo * kRadToDeg;
    } else {
      open = false;
    }
    a = b;
  }
  r.speed_rmse_mps = r.windows > 0 ? std::sqrt(speed_sq / static_cast<double>(r.windows)) : 0;
  return r;
}

}  // namespace agvslam::eval
