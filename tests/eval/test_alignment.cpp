#include <gtest/gtest.h>

#include <random>

#include "agvslam/core/error.h"
#include "agvslam/eval/alignment.h"

namespace agvslam::eval {
namespace {

Eigen::Matrix3Xd random_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-10, 10);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) p.col(i) = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

TEST(Umeyama, RecoversRigidTransform) {
  const Eigen::Matrix3Xd src = random_points(50, 1);
  const SE3d T = se3_exp((Vector6d() << 1.5, -2.0, 0.3, 0.2, -0.9, 2.5).finished());
  const Eigen::Matrix3Xd dst = (T.linear() * src).colwise() + T.translation();
  const Alignment a = umeyama(src, dst, false);
  EXPECT_NEAR(a.scale, 1.0, 1e-12);
  EXPECT_LT((a.T_dst_src.matrix() - T.matrix()).norm(), 1e-9);
}

TEST(Umeyama, RecoversSimilarity) {
  const Eigen::Matrix3Xd src = random_points(50, 2);
  const SE3d T = se3_exp((Vector6d() << -0.5, 4.0, 1.0, 0.1, 0.4, -0.3).finished());
  const double s = 2.75;
  const Eigen::Matrix3Xd dst = (s * T.linear() * src).colwise() + T.translation();
  const Alignment a = umeyama(src, dst, true);
  EXPECT_NEAR(a.scale, s, 1e-9);
  EXPECT_LT((a.T_dst_src.linear() - T.linear()).norm(), 1e-9);
  for (int i = 0; i < src.cols(); ++i) EXPECT_LT((a.apply(Eigen::Vector3d(src.col(i))) - dst.col(i)).norm(), 1e-9);
}

TEST(Umeyama, ReflectionIsNeverReturned) {
  // A mirrored point set: the best proper rotation must still have det +1.
  Eigen::Matrix3Xd src = random_points(20, 3);
  Eigen::Matrix3Xd dst = src;
  dst.row(0) *= -1.0;
  const Alignment a = umeyama(src, dst, false);
  EXPECT_NEAR(a.T_dst_src.linear().determinant(), 1.0, 1e-9);
}

TEST(AlignMode, ParsesAndRejects) {
  EXPECT_EQ(parse_align_mode("se3"), AlignMode::kSE3);
  EXPECT_EQ(parse_align_mode("sim3"), AlignMode::kSim3);
  EXPECT_EQ(parse_align_mode("none"), AlignMode::kNone);
  try {
    parse_align_mode("affine");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--align"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("affine"), std::string::npos);
  }
}

}  // namespace
}  // namespace agvslam::eval
