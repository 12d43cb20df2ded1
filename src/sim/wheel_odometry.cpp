#include "agvslam/sim/wheel_odometry.h"

#include <cmath>
#include <random>

namespace agvslam::sim {
namespace {

// Heading (yaw about the up axis -y) of a camera whose optical axis is near-horizontal.
double heading_rad(const SE3d& T_w_c) {
  const Eigen::Vector3d forward = T_w_c.linear() * Eigen::Vector3d::UnitZ();
  return std::atan2(forward.x(), forward.z());
}

double wrap_pi(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

Trajectory simulate_wheel_odometry(const Trajectory& gt, const WheelOdometryConfig& config, uint64_t seed) {
  Trajectory odom;
  if (gt.empty()) return odom;
  std::mt19937_64 rng(seed ^ 0x0d0e7e1e5ULL);
  std::normal_distribution<double> unit(0.0, 1.0);

  double x = gt.front().T_w_c.translation().x(), z = gt.front().T_w_c.translation().z();
  double yaw = heading_rad(gt.front().T_w_c);
  const double camera_y = gt.front().T_w_c.translation().y();
  for (std::size_t i = 0; i < gt.size(); ++i) {
    if (i > 0) {
      const SE3d& a = gt[i - 1].T_w_c;
      const SE3d& b = gt[i].T_w_c;
      const Eigen::Vector3d dp = b.translation() - a.translation();
      const double yaw_a = heading_rad(a);
      const double dyaw = wrap_pi(heading_rad(b) - yaw_a);
      // A constant-curvature step moves along its chord, which points along the mid-step heading. Signed
      // distance along that chord (a vehicle that reverses reads negative distance).
      const double yaw_mid = yaw_a + 0.5 * dyaw;
      const double ds = dp.x() * std::sin(yaw_mid) + dp.z() * std::cos(yaw_mid);
      const double dist = std::abs(ds);
      const double ds_odom =
          ds * (1.0 + config.distance_scale_error) + config.distance_noise_m_per_sqrt_m * std::sqrt(dist) * unit(rng);
      const double dyaw_odom = dyaw + config.yaw_bias_rad_per_m * dist +
                               config.yaw_noise_rad_per_sqrt_m * std::sqrt(dist) * unit(rng) +
                               config.yaw_noise_rad_per_rad * std::abs(dyaw) * unit(rng);
      const double mid = yaw + 0.5 * dyaw_odom;
      x += ds_odom * std::sin(mid);
      z += ds_odom * std::cos(mid);
      yaw += dyaw_odom;
    }
    StampedPose sp;
    sp.t_ns = gt[i].t_ns;
    // Rotation about the up axis (-y): forward (z) turns towards x for positive yaw.
    sp.T_w_c =
        make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), Eigen::Vector3d(x, camera_y, z));
    odom.push_back(sp);
  }
  return odom;
}

}  // namespace agvslam::sim
