// Two-view triangulation, parallax and the fundamental matrix from poses.
#include <gtest/gtest.h>

#include <random>

#include "agvslam/slam/triangulation.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

Eigen::Vector2d normalised(const SE3d& T_c_w, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d p_c = T_c_w * p_w;
  return p_c.head<2>() / p_c.z();
}

TEST(Triangulation, ExactPointsAreRecovered) {
  const SE3d T1 = test::path_pose(0), T2 = test::path_pose(4);
  const test::World world = test::make_world(200, 1);
  for (const Eigen::Vector3d& p : world.points_w) {
    Eigen::Vector3d q;
    ASSERT_TRUE(triangulate_linear(normalised(T1, p), normalised(T2, p), T1, T2, q));
    EXPECT_LT((q - p).norm(), 1e-6 * p.norm());
  }
}

TEST(Triangulation, NoisyPointsErrorGrowsWithDepthOverBaseline) {
  const SE3d T1 = SE3d::Identity();
  const SE3d T2 = make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.5, 0, 0));  // 0.5 m to the right
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.5 / 460.0);  // 0.5 px
  double err_near = 0, err_far = 0;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d near(0.3, 0.1, 3.0 + 0.01 * i), far(0.3, 0.1, 30.0 + 0.1 * i);
    Eigen::Vector3d q;
    const Eigen::Vector2d n2(noise(rng), noise(rng));
    ASSERT_TRUE(triangulate_linear(normalised(T1, near) + n2, normalised(T2, near), T1, T2, q));
    err_near += (q - near).norm();
    ASSERT_TRUE(triangulate_linear(normalised(T1, far) + n2, normalised(T2, far), T1, T2, q));
    err_far += (q - far).norm();
  }
  EXPECT_LT(err_near / 100, 0.04);  // z^2 / (f b) * 0.5 px = 2 cm per pixel coordinate
  EXPECT_GT(err_far, 20 * err_near);
}

TEST(Triangulation, ParallelRaysHaveNoFiniteSolutionOrParallaxOne) {
  const SE3d T1 = SE3d::Identity();
  const SE3d T2 = make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.5, 0, 0));
  // The same normalised coordinate in both views of a sideways baseline: a point at infinity.
  Eigen::Vector3d q;
  const bool ok = triangulate_linear({0.1, 0.0}, {0.1, 0.0}, T1, T2, q);
  EXPECT_TRUE(!ok || q.norm() > 1e6);
  EXPECT_NEAR(parallax_cos(Eigen::Vector3d(0, 0, 1e9), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.5, 0, 0)), 1.0,
              1e-12);
  EXPECT_NEAR(parallax_cos(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(1, 0, 0)), 0.0, 1e-12);
}

TEST(Triangulation, FundamentalMatrixSatisfiesTheEpipolarConstraint) {
  const SE3d T1 = test::path_pose(1), T2 = test::path_pose(6);
  const PinholeCamera cam = test::test_camera();
  Eigen::Matrix3d K;
  K << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1;
  const Eigen::Matrix3d F12 = fundamental_from_poses(T1, T2, K);
  const test::World world = test::make_world(50, 3);
  for (const Eigen::Vector3d& p : world.points_w) {
    const Eigen::Vector3d p1 = T1 * p, p2 = T2 * p;
    if (p1.z() <= 0 || p2.z() <= 0) continue;
    const Eigen::Vector3d x1 = K * (p1 / p1.z()), x2 = K * (p2 / p2.z());
    // Line in image 2: l = x1^T F12; distance of x2 to it in pixels.
    const Eigen::Vector3d l = F12.transpose() * x1;
    EXPECT_LT(std::fabs(l.dot(x2)) / l.head<2>().norm(), 1e-6);
  }
}

}  // namespace
}  // namespace agvslam::slam
