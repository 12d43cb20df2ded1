// Motion-only BA and bundle adjustment on synthetic stereo data with known ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "agvslam/slam/optimizer.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

StereoIntrinsics intrinsics() {
  const PinholeCamera cam = test::test_camera();
  return {cam.fx, cam.fy, cam.cx, cam.cy, cam.fx * 0.12};
}

double translation_error(const SE3d& a, const SE3d& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

double rotation_error_deg(const SE3d& a, const SE3d& b) { return rotation_angle_rad(a * b.inverse()) * 180.0 / M_PI; }

// n observations of random points from T_true, noise_px Gaussian pixel noise, a fraction of gross outliers
// (random image positions); stereo for every second point.
std::vector<PoseObservation> make_observations(const SE3d& T_true, int n, double noise_px, double outlier_fraction,
                                               uint32_t seed, std::vector<uint8_t>& is_outlier) {
  const StereoIntrinsics cam = intrinsics();
  const test::World world = test::make_world(n * 2, seed);
  std::mt19937 rng(seed + 1);
  std::normal_distribution<double> noise(0.0, noise_px);
  std::uniform_real_distribution<double> uu(0, 752), uv(0, 480), unit(0, 1);
  std::vector<PoseObservation> obs;
  is_outlier.clear();
  const SE3d T_w_c = T_true.inverse();
  for (const Eigen::Vector3d& p_c0 : world.points_w) {
    if (static_cast<int>(obs.size()) >= n) break;
    const Eigen::Vector3d p_w = T_w_c * p_c0;  // the world box as seen from the true camera
    const Eigen::Vector3d p_c = T_true * p_w;
    const double u = cam.fx * p_c.x() / p_c.z() + cam.cx, v = cam.fy * p_c.y() / p_c.z() + cam.cy;
    if (u < 0 || u >= 752 || v < 0 || v >= 480) continue;
    PoseObservation o;
    o.p_w = p_w;
    const bool gross = unit(rng) < outlier_fraction;
    if (gross) {
      o.uv_px = {uu(rng), uv(rng)};
    } else {
      o.uv_px = {u + noise(rng), v + noise(rng)};
    }
    if (obs.size() % 2 == 0) o.u_right_px = o.uv_px.x() - cam.bf / p_c.z() + (gross ? 0.0 : noise(rng));
    o.inv_sigma2 = 1.0;
    obs.push_back(o);
    is_outlier.push_back(gross ? 1 : 0);
  }
  return obs;
}

TEST(MotionOnlyBa, RecoversPerturbedPoseWithOutliers) {
  const SE3d T_true = test::path_pose(7);
  std::vector<uint8_t> truth;
  const auto obs = make_observations(T_true, 400, 0.7, 0.2, 11, truth);
  ASSERT_GE(obs.size(), 350u);
  // 8 cm and 3 degrees off.
  SE3d T = se3_exp((Vector6d() << 0.05, -0.03, 0.06, 0.03, -0.04, 0.02).finished()) * T_true;
  ASSERT_GT(translation_error(T, T_true), 0.05);
  std::vector<uint8_t> outlier;
  const MotionOnlyStats stats = optimize_pose(intrinsics(), OptimizerConfig{}, obs, outlier, T);
  EXPECT_LT(translation_error(T, T_true), 0.01);
  EXPECT_LT(rotation_error_deg(T, T_true), 0.1);
  ASSERT_EQ(outlier.size(), obs.size());
  int caught = 0, gross = 0, false_alarms = 0, clean = 0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (truth[i]) {
      ++gross;
      caught += outlier[i];
    } else {
      ++clean;
      false_alarms += outlier[i];
    }
  }
  EXPECT_GE(caught, gross * 95 / 100) << "gross outliers flagged";
  EXPECT_LE(false_alarms, clean / 10) << "inliers flagged (chi-square 95 %: about 5 % expected)";
  EXPECT_EQ(stats.inliers + stats.outliers, static_cast<int>(obs.size()));
  EXPECT_EQ(stats.rounds, 4);
}

TEST(MotionOnlyBa, WithoutRobustLossOutliersPullThePoseAway) {
  // The same problem with plain least squares in every round and no outlier rejection is measurably worse:
  // the robust loss and the chi-square test are what makes the result above.
  const SE3d T_true = test::path_pose(3);
  std::vector<uint8_t> truth;
  const auto obs = make_observations(T_true, 300, 0.7, 0.2, 5, truth);
  OptimizerConfig plain;
  plain.motion_rounds = 1;
  plain.motion_robust_rounds = 0;
  plain.chi2_mono = plain.chi2_stereo = 1e12;
  SE3d T_plain = T_true, T_robust = T_true;
  std::vector<uint8_t> outlier;
  optimize_pose(intrinsics(), plain, obs, outlier, T_plain);
  optimize_pose(intrinsics(), OptimizerConfig{}, obs, outlier, T_robust);
  EXPECT_GT(translation_error(T_plain, T_true), 3 * translation_error(T_robust, T_true));
}

TEST(MotionOnlyBa, TooFewObservationsIsAFailureNotACrash) {
  std::vector<PoseObservation> obs(2);
  obs[0].p_w = {0, 0, 5};
  obs[1].p_w = {1, 0, 5};
  SE3d T = SE3d::Identity();
  std::vector<uint8_t> outlier;
  const MotionOnlyStats stats = optimize_pose(intrinsics(), OptimizerConfig{}, obs, outlier, T);
  EXPECT_EQ(stats.inliers, 0);
  EXPECT_TRUE(is_valid_pose(T));
}

TEST(BundleAdjustment, ReducesAKnownError) {
  const StereoIntrinsics cam = intrinsics();
  const test::World world = test::make_world(400, 3);
  BaProblem problem;
  std::vector<SE3d> poses_true;
  for (int k = 0; k < 6; ++k) {
    poses_true.push_back(test::path_pose(k));
    problem.poses.push_back({poses_true.back(), k < 2});
  }
  std::mt19937 rng(9);
  // Exact observations apart from the gross errors: the ground truth is then the optimum, so what BA must remove
  // is the known perturbation below (with 0.5 px noise, distant points' optimum lies decimetres from the truth).
  std::normal_distribution<double> noise(0.0, 1e-9);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<int> point_index(world.points_w.size(), -1);
  int gross = 0;
  for (std::size_t i = 0; i < world.points_w.size(); ++i) {
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector3d p_c = poses_true[static_cast<std::size_t>(k)] * world.points_w[i];
      if (p_c.z() < 0.5) continue;
      const double u = cam.fx * p_c.x() / p_c.z() + cam.cx, v = cam.fy * p_c.y() / p_c.z() + cam.cy;
      if (u < 0 || u >= 752 || v < 0 || v >= 480) continue;
      if (point_index[i] < 0) {
        point_index[i] = static_cast<int>(problem.points_w.size());
        problem.points_w.push_back(world.points_w[i]);
      }
      BaProblem::Observation o;
      o.pose = k;
      o.point = point_index[i];
      o.uv_px = {u + noise(rng), v + noise(rng)};
      if (i % 3 != 0) o.u_right_px = o.uv_px.x() - cam.bf / p_c.z() + noise(rng);
      if (unit(rng) < 0.03) {  // a few wrong associations
        o.uv_px += Eigen::Vector2d(40, -25);
        ++gross;
      }
      problem.observations.push_back(o);
    }
  }
  ASSERT_GT(problem.observations.size(), 1000u);
  // Perturb the free poses (5 cm, 1 degree) and every point (10 cm).
  for (std::size_t k = 2; k < problem.poses.size(); ++k) {
    problem.poses[k].T_c_w =
        se3_exp((Vector6d() << 0.03, 0.02, -0.04, 0.01, -0.015, 0.01).finished()) * problem.poses[k].T_c_w;
  }
  std::normal_distribution<double> point_noise(0.0, 0.06);
  std::vector<Eigen::Vector3d> points_true = problem.points_w;
  for (auto& p : problem.points_w) p += Eigen::Vector3d(point_noise(rng), point_noise(rng), point_noise(rng));

  auto pose_error = [&]() {
    double e = 0;
    for (std::size_t k = 2; k < problem.poses.size(); ++k)
      e = std::max(e, translation_error(problem.poses[k].T_c_w, poses_true[k]));
    return e;
  };
  auto point_median = [&]() {
    std::vector<double> e;
    for (std::size_t i = 0; i < points_true.size(); ++i) e.push_back((problem.points_w[i] - points_true[i]).norm());
    std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
    return e[e.size() / 2];
  };
  const double pose_before = pose_error(), points_before = point_median();
  const BaStats stats = solve_bundle_adjustment(problem, cam, OptimizerConfig{}, 5, 10);
  EXPECT_LT(stats.final_cost, 0.05 * stats.initial_cost);
  EXPECT_LT(pose_error(), 0.1 * pose_before);
  EXPECT_LT(pose_error(), 0.002);
  EXPECT_LT(point_median(), 0.1 * points_before);
  EXPECT_GE(stats.outliers, gross * 9 / 10);
  EXPECT_FALSE(stats.aborted);
  // Fixed poses do not move.
  EXPECT_LT(translation_error(problem.poses[0].T_c_w, poses_true[0]), 1e-12);
}

TEST(BundleAdjustment, AbortFlagStopsEarly) {
  const StereoIntrinsics cam = intrinsics();
  BaProblem problem;
  problem.poses.push_back({SE3d::Identity(), true});
  problem.poses.push_back({test::path_pose(1), false});
  const test::World world = test::make_world(50, 4);
  for (std::size_t i = 0; i < world.points_w.size(); ++i) {
    problem.points_w.push_back(world.points_w[i] + Eigen::Vector3d(0.05, 0, 0));
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d p_c = problem.poses[static_cast<std::size_t>(k)].T_c_w * world.points_w[i];
      BaProblem::Observation o;
      o.pose = k;
      o.point = static_cast<int>(i);
      o.uv_px = {cam.fx * p_c.x() / p_c.z() + cam.cx, cam.fy * p_c.y() / p_c.z() + cam.cy};
      problem.observations.push_back(o);
    }
  }
  std::atomic<bool> abort{true};
  const BaStats stats = solve_bundle_adjustment(problem, cam, OptimizerConfig{}, 5, 10, &abort);
  EXPECT_TRUE(stats.aborted);
  EXPECT_LE(stats.iterations, 2);
}

TEST(ReprojectionChi2, StereoAndMonocular) {
  const StereoIntrinsics cam = intrinsics();
  const Eigen::Vector3d p_c(0.5, -0.2, 4.0);
  const Eigen::Vector2d uv(cam.fx * 0.5 / 4 + cam.cx, cam.fy * -0.2 / 4 + cam.cy);
  const double ur = uv.x() - cam.bf / 4;
  EXPECT_NEAR(reprojection_chi2(cam, p_c, uv, ur, 1.0), 0.0, 1e-12);
  EXPECT_NEAR(reprojection_chi2(cam, p_c, uv + Eigen::Vector2d(1, 0), -1, 1.0), 1.0, 1e-9);
  EXPECT_NEAR(reprojection_chi2(cam, p_c, uv + Eigen::Vector2d(1, 0), ur, 0.25), 0.25, 1e-9);
  bool in_front = true;
  reprojection_chi2(cam, Eigen::Vector3d(0, 0, -1), uv, -1, 1.0, &in_front);
  EXPECT_FALSE(in_front);
}

}  // namespace
}  // namespace agvslam::slam
