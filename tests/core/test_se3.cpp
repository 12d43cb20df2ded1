#include <gtest/gtest.h>

#include "agvslam/core/se3.h"

namespace agvslam {
namespace {

TEST(Se3, ExpLogRoundTrip) {
  Vector6d xi;
  xi << 0.3, -1.2, 2.0, 0.4, -0.7, 1.1;
  const SE3d T = se3_exp(xi);
  EXPECT_TRUE(is_valid_pose(T));
  EXPECT_LT((se3_log(T) - xi).norm(), 1e-9);
}

TEST(Se3, ExpOfSmallTangentIsNearIdentity) {
  Vector6d xi = Vector6d::Zero();
  xi(0) = 1e-12;
  EXPECT_LT((se3_exp(xi).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-9);
}

TEST(Se3, RotationAngle) {
  const SE3d T =
      make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY())), Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR(rotation_angle_rad(T), 0.5, 1e-12);
}

TEST(Se3, OrthonormalizeRepairsNoise) {
  Eigen::Matrix3d R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Matrix3d noisy = R;
  noisy(0, 1) += 1e-4;
  const Eigen::Matrix3d fixed = orthonormalize(noisy);
  EXPECT_LT((fixed * fixed.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((fixed - R).norm(), 1e-3);
}

TEST(Se3, InvalidPoseDetected) {
  SE3d T = SE3d::Identity();
  T.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(is_valid_pose(T));
  SE3d S = SE3d::Identity();
  S.linear() *= 2.0;
  EXPECT_FALSE(is_valid_pose(S));
}

}  // namespace
}  // namespace agvslam
