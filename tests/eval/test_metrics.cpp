#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "agvslam/eval/metrics.h"

namespace agvslam::eval {
namespace {

// A wandering ground-vehicle trajectory in a KITTI-like camera frame (x right, y down, z forward).
Trajectory make_trajectory(int n, double step_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> turn(0.0, 0.02);
  Trajectory traj;
  double yaw = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    StampedPose sp;
    sp.t_ns = static_cast<int64_t>(i) * 50'000'000;
    sp.T_w_c = make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, -Eigen::Vector3d::UnitY())), p);
    traj.push_back(sp);
    yaw += turn(rng);
    p += step_m * Eigen::Vector3d(std::sin(yaw), 0, std::cos(yaw));
  }
  return traj;
}

TEST(Stats, KnownValues) {
  const ErrorStats s = compute_stats({3, 1, 4, 1, 5});
  EXPECT_EQ(s.count, 5u);
  EXPECT_DOUBLE_EQ(s.mean, 2.8);
  EXPECT_DOUBLE_EQ(s.median, 3.0);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  EXPECT_NEAR(s.rmse, std::sqrt(52.0 / 5.0), 1e-12);
  EXPECT_NEAR(s.std, std::sqrt(52.0 / 5.0 - 2.8 * 2.8), 1e-12);
  EXPECT_DOUBLE_EQ(compute_stats({1, 2, 3, 4}).median, 2.5);
}

TEST(Ate, RigidOffsetGivesZeroAfterSe3Alignment) {
  const Trajectory gt = make_trajectory(300, 0.1, 7);
  const SE3d T_est_gt = se3_exp((Vector6d() << 3.0, -1.0, 7.0, 0.3, 1.2, -0.4).finished());
  Trajectory est = gt;
  for (auto& sp : est) sp.T_w_c = T_est_gt * sp.T_w_c;
  const PosePairs pairs = associate_by_index(gt, est);

  const AteResult aligned = compute_ate(pairs, AlignMode::kSE3);
  EXPECT_LT(aligned.translation_m.rmse, 1e-9);
  EXPECT_LT((aligned.alignment.T_dst_src.matrix() - T_est_gt.inverse().matrix()).norm(), 1e-9);
  EXPECT_GT(compute_ate(pairs, AlignMode::kNone).translation_m.rmse, 1.0);
  // Relative errors do not depend on the world frame.
  const RpeResult rpe = compute_rpe(pairs);
  EXPECT_LT(rpe.translation_m.max, 1e-9);
  EXPECT_LT(rpe.rotation_deg.max, 1e-6);
}

TEST(Ate, ScaledEstimateNeedsSim3) {
  const Trajectory gt = make_trajectory(200, 0.1, 8);
  Trajectory est = gt;
  for (auto& sp : est) sp.T_w_c.translation() *= 0.5;
  const PosePairs pairs = associate_by_index(gt, est);
  const AteResult sim3 = compute_ate(pairs, AlignMode::kSim3);
  EXPECT_NEAR(sim3.alignment.scale, 2.0, 1e-9);
  EXPECT_LT(sim3.translation_m.rmse, 1e-9);
  EXPECT_GT(compute_ate(pairs, AlignMode::kSE3).translation_m.rmse, 0.1);
}

TEST(Ate, IsotropicNoiseOfKnownSizeGivesExpectedRmse) {
  const Trajectory gt = make_trajectory(4000, 0.05, 9);
  std::mt19937 rng(10);
  const double sigma_m = 0.03;
  std::normal_distribution<double> noise(0.0, sigma_m);
  Trajectory est = gt;
  for (auto& sp : est) sp.T_w_c.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const AteResult ate = compute_ate(associate_by_index(gt, est), AlignMode::kSE3);
  // E[|n|^2] = 3 sigma^2 for 3-D isotropic noise.
  EXPECT_NEAR(ate.translation_m.rmse, sigma_m * std::sqrt(3.0), 0.03 * sigma_m * std::sqrt(3.0));
  // The mean of a Maxwell distribution: 2 sigma sqrt(2/pi).
  EXPECT_NEAR(ate.translation_m.mean, 2.0 * sigma_m * std::sqrt(2.0 / M_PI), 0.03 * sigma_m);
}

TEST(Rpe, KnownPerFrameDrift) {
  // The estimate moves 1 cm further each frame than the truth, straight ahead.
  Trajectory gt, est;
  for (int i = 0; i < 100; ++i) {
    StampedPose a, b;
    a.t_ns = b.t_ns = i;
    a.T_w_c.translation() = Eigen::Vector3d(0, 0, 0.10 * i);
    b.T_w_c.translation() = Eigen::Vector3d(0, 0, 0.11 * i);
    gt.push_back(a);
    est.push_back(b);
  }
  const RpeResult rpe = compute_rpe(associate_by_index(gt, est));
  EXPECT_EQ(rpe.translation_m.count, 99u);
  EXPECT_NEAR(rpe.translation_m.rmse, 0.01, 1e-12);
  EXPECT_NEAR(rpe.translation_m.std, 0.0, 1e-9);
  const RpeResult rpe5 = compute_rpe(associate_by_index(gt, est), 5);
  EXPECT_NEAR(rpe5.translation_m.mean, 0.05, 1e-12);
}

TEST(Kitti, ScaleErrorOfOnePercentGivesOnePercentTrel) {
  const Trajectory gt = make_trajectory(2000, 1.0, 11);  // 2 km
  Trajectory est = gt;
  for (auto& sp : est) sp.T_w_c.translation() *= 1.01;
  const auto k = compute_kitti_relative(associate_by_index(gt, est));
  ASSERT_TRUE(k.has_value());
  EXPECT_EQ(k->per_length.size(), 8u);
  EXPECT_NEAR(k->t_rel_pct, 1.0, 0.02);
  EXPECT_NEAR(k->r_rel_deg_per_100m, 0.0, 1e-6);
}

TEST(Kitti, YawDriftGivesKnownRrel) {
  // A straight 1 km drive; the estimate's heading turns 0.01 deg every metre: 1 deg/100 m.
  Trajectory gt, est;
  const double drift_rad_per_m = 0.01 * M_PI / 180.0;
  double yaw = 0;
  Eigen::Vector3d p_est = Eigen::Vector3d::Zero();
  for (int i = 0; i <= 1000; ++i) {
    StampedPose g, e;
    g.T_w_c.translation() = Eigen::Vector3d(0, 0, i);
    e.T_w_c = make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), p_est);
    gt.push_back(g);
    est.push_back(e);
    p_est += e.T_w_c.linear() * Eigen::Vector3d(0, 0, 1);
    yaw += drift_rad_per_m;
  }
  const auto k = compute_kitti_relative(associate_by_index(gt, est));
  ASSERT_TRUE(k.has_value());
  EXPECT_NEAR(k->r_rel_deg_per_100m, 1.0, 1e-6);
}

TEST(Kitti, ShortTrajectoryHasNoSegments) {
  const Trajectory gt = make_trajectory(100, 0.5, 12);  // 50 m
  EXPECT_FALSE(compute_kitti_relative(associate_by_index(gt, gt)).has_value());
}

TEST(Association, NearestTimestampWithinTolerance) {
  Trajectory gt, est;
  for (int i = 0; i < 100; ++i) {
    StampedPose g;
    g.t_ns = 1'000'000'000LL + i * 50'000'000LL;
    g.T_w_c.translation() = Eigen::Vector3d(i, 0, 0);
    gt.push_back(g);
  }
  // Estimates 3 ms late, every other one, in reverse order, plus one far from any ground truth.
  for (int i = 98; i >= 0; i -= 2) {
    StampedPose e;
    e.t_ns = gt[static_cast<std::size_t>(i)].t_ns + 3'000'000;
    e.T_w_c.translation() = Eigen::Vector3d(i, 0, 0);
    est.push_back(e);
  }
  StampedPose stray;
  stray.t_ns = 99'000'000'000LL;
  est.push_back(stray);
  const PosePairs pairs = associate_by_timestamp(gt, est, 10'000'000);
  ASSERT_EQ(pairs.size(), 50u);
  for (std::size_t k = 0; k < pairs.size(); ++k)
    EXPECT_EQ(pairs.T_w_c_gt[k].translation().x(), pairs.T_w_c_est[k].translation().x());
  EXPECT_EQ(associate_by_timestamp(gt, est, 1'000'000).size(), 0u);
}

}  // namespace
}  // namespace agvslam::eval
