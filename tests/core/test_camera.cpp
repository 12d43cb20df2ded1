#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "agvslam/core/camera.h"

namespace agvslam {
namespace {

TEST(PinholeCamera, ProjectUnprojectRoundTrip) {
  PinholeCamera cam{460, 460, 376, 240, 752, 480};
  const Eigen::Vector3d p(0.4, -0.2, 3.5);
  const Eigen::Vector2d uv = cam.project(p);
  EXPECT_LT((cam.unproject(uv, p.z()) - p).norm(), 1e-12);
}

TEST(StereoCalibration, DisparityDepth) {
  StereoCalibration c;
  c.left = {460, 460, 376, 240, 752, 480};
  c.baseline_m = 0.12;
  EXPECT_NEAR(c.bf(), 55.2, 1e-12);
  EXPECT_NEAR(c.disparity_from_depth(2.0), 27.6, 1e-12);
  EXPECT_NEAR(c.depth_from_disparity(27.6), 2.0, 1e-12);
}

// A rig whose right camera is rotated slightly and shifted: after rectify_rig a 3-D point must project to
// the same row in both rectified images and its disparity must give back its depth.
TEST(StereoCalibration, RectifyRigAlignsRows) {
  RawStereoRig rig;
  rig.cam0.pinhole = {450, 452, 370, 245, 752, 480};
  rig.cam1.pinhole = {455, 454, 368, 250, 752, 480};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.01, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  rig.T_cam1_cam0 = make_se3(R, Eigen::Vector3d(-0.11, 0.002, 0.001));
  const StereoCalibration calib = rectify_rig(rig);
  ASSERT_TRUE(calib.needs_rectification);
  EXPECT_NEAR(calib.baseline_m, rig.T_cam1_cam0.translation().norm(), 1e-6);

  const Eigen::Vector3d p_cam0(0.3, -0.2, 4.0);
  const Eigen::Vector3d p_rect = calib.T_cam0_rect.inverse() * p_cam0;
  const Eigen::Vector2d uv_l = calib.left.project(p_rect);
  const Eigen::Vector2d uv_r = calib.left.project(p_rect - Eigen::Vector3d(calib.baseline_m, 0, 0));
  EXPECT_NEAR(uv_l.y(), uv_r.y(), 1e-9);
  EXPECT_NEAR(calib.depth_from_disparity(uv_l.x() - uv_r.x()), p_rect.z(), 1e-9);

  // The map of the left image sends the rectified pixel back to where the raw cam0 sees the point.
  const Eigen::Vector2d uv_raw = rig.cam0.pinhole.project(p_cam0);
  const int u = static_cast<int>(std::lround(uv_l.x())), v = static_cast<int>(std::lround(uv_l.y()));
  const float mx = calib.map_left_x.at<float>(v, u), my = calib.map_left_y.at<float>(v, u);
  EXPECT_NEAR(mx, uv_raw.x(), 1.0);
  EXPECT_NEAR(my, uv_raw.y(), 1.0);
}

}  // namespace
}  // namespace agvslam
