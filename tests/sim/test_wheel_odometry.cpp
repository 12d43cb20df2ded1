#include <gtest/gtest.h>

#include <cmath>

#include "agvslam/eval/metrics.h"
#include "agvslam/sim/wheel_odometry.h"

namespace agvslam::sim {
namespace {

// A 6 m x 4 m rectangle driven with quarter-circle turns (camera frame: x right, y down, z forward).
Trajectory rectangle_loop() {
  Trajectory traj;
  double yaw = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  int64_t t_ns = 0;
  auto push = [&]() {
    traj.push_back({t_ns, make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), p)});
    t_ns += 50'000'000;
  };
  for (const double side : {6.0, 4.0, 6.0, 4.0}) {
    for (int i = 0; i < static_cast<int>(side / 0.04); ++i) {
      p += 0.04 * Eigen::Vector3d(std::sin(yaw), 0, std::cos(yaw));
      push();
    }
    for (int i = 0; i < 40; ++i) {  // quarter turn of radius 0.5 m: exact arc steps (chord along mid heading)
      const double dyaw = M_PI / 2 / 40;
      const double chord = 2 * 0.5 * std::sin(dyaw / 2);
      p += chord * Eigen::Vector3d(std::sin(yaw + dyaw / 2), 0, std::cos(yaw + dyaw / 2));
      yaw += dyaw;
      push();
    }
  }
  return traj;
}

TEST(WheelOdometry, WithoutErrorsReproducesThePlanarTrajectory) {
  const Trajectory gt = rectangle_loop();
  WheelOdometryConfig perfect;
  perfect.distance_scale_error = perfect.yaw_bias_rad_per_m = 0;
  perfect.distance_noise_m_per_sqrt_m = perfect.yaw_noise_rad_per_sqrt_m = perfect.yaw_noise_rad_per_rad = 0;
  const Trajectory odom = simulate_wheel_odometry(gt, perfect, 1);
  ASSERT_EQ(odom.size(), gt.size());
  double max_err = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    EXPECT_EQ(odom[i].t_ns, gt[i].t_ns);
    max_err = std::max(max_err, (odom[i].T_w_c.translation() - gt[i].T_w_c.translation()).norm());
  }
  // Exact arc steps are integrated exactly by the mid-heading rule: agreement to rounding.
  EXPECT_LT(max_err, 1e-9);
}

TEST(WheelOdometry, ScaleErrorLengthensThePathAndDriftGrowsWithDistance) {
  const Trajectory gt = rectangle_loop();
  WheelOdometryConfig cfg;  // defaults: +1 % distance, 0.004 rad/m heading bias, noise
  const Trajectory odom = simulate_wheel_odometry(gt, cfg, 7);
  std::vector<SE3d> gt_poses, odom_poses;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    gt_poses.push_back(gt[i].T_w_c);
    odom_poses.push_back(odom[i].T_w_c);
  }
  const double len_gt = eval::path_length_m(gt_poses), len_odom = eval::path_length_m(odom_poses);
  EXPECT_NEAR(len_odom / len_gt, 1.01, 0.004);
  // Dead reckoning: the loop does not close; the end error is centimetres to decimetres, not zero.
  const double end_err = (odom.back().T_w_c.translation() - gt.back().T_w_c.translation()).norm();
  const double mid_err = (odom[gt.size() / 4].T_w_c.translation() - gt[gt.size() / 4].T_w_c.translation()).norm();
  EXPECT_GT(end_err, 0.05);
  EXPECT_LT(end_err, 1.5);
  EXPECT_GT(end_err, mid_err);
  // Deterministic for a seed, different across seeds.
  const Trajectory again = simulate_wheel_odometry(gt, cfg, 7);
  EXPECT_EQ(again.back().T_w_c.translation(), odom.back().T_w_c.translation());
  const Trajectory other = simulate_wheel_odometry(gt, cfg, 8);
  EXPECT_NE(other.back().T_w_c.translation(), odom.back().T_w_c.translation());
}

TEST(WheelOdometry, StationaryVehicleDoesNotMove) {
  Trajectory gt(100);
  for (std::size_t i = 0; i < gt.size(); ++i) gt[i].t_ns = static_cast<int64_t>(i);
  const Trajectory odom = simulate_wheel_odometry(gt, WheelOdometryConfig{}, 3);
  EXPECT_LT(odom.back().T_w_c.translation().norm(), 1e-12);
}

}  // namespace
}  // namespace agvslam::sim
