#include "agvslam/core/camera.h"

#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace agvslam {

void StereoCalibration::rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect,
                                cv::Mat& right_rect) const {
  if (!needs_rectification) {
    left_rect = left_raw;
    right_rect = right_raw;
    return;
  }
  cv::remap(left_raw, left_rect, map_left_x, map_left_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::remap(right_raw, right_rect, map_right_x, map_right_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

std::string StereoCalibration::summary() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%dx%d fx=%.3f fy=%.3f cx=%.3f cy=%.3f baseline=%.4f m bf=%.3f%s", left.width,
                left.height, left.fx, left.fy, left.cx, left.cy, baseline_m, bf(),
                needs_rectification ? " (rectified from raw)" : "");
  return buf;
}

StereoCalibration rectify_rig(const RawStereoRig& rig) {
  const cv::Size size = rig.cam0.pinhole.size();
  const cv::Mat K0(rig.cam0.pinhole.K()), K1(rig.cam1.pinhole.K());
  const cv::Mat D0(rig.cam0.distortion, true), D1(rig.cam1.distortion, true);
  cv::Mat R_cv, t_cv;
  Eigen::Matrix3d R = rig.T_cam1_cam0.linear();
  Eigen::Vector3d t = rig.T_cam1_cam0.translation();
  R_cv = (cv::Mat_<double>(3, 3) << R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2));
  t_cv = (cv::Mat_<double>(3, 1) << t.x(), t.y(), t.z());
  cv::Mat R0, R1, P0, P1, Q;
  cv::stereoRectify(K0, D0.empty() ? cv::Mat() : D0.reshape(1, 1), K1, D1.empty() ? cv::Mat() : D1.reshape(1, 1), size,
                    R_cv, t_cv, R0, R1, P0, P1, Q, cv::CALIB_ZERO_DISPARITY, 0.0, size);

  StereoCalibration calib;
  calib.left.fx = P0.at<double>(0, 0);
  calib.left.fy = P0.at<double>(1, 1);
  calib.left.cx = P0.at<double>(0, 2);
  calib.left.cy = P0.at<double>(1, 2);
  calib.left.width = size.width;
  calib.left.height = size.height;
  calib.baseline_m = -P1.at<double>(0, 3) / P1.at<double>(0, 0);
  calib.needs_rectification = true;
  cv::initUndistortRectifyMap(K0, D0, R0, P0, size, CV_32FC1, calib.map_left_x, calib.map_left_y);
  cv::initUndistortRectifyMap(K1, D1, R1, P1, size, CV_32FC1, calib.map_right_x, calib.map_right_y);
  // R0 rotates raw cam0 coordinates into the rectified frame: p_rect = R0 * p_cam0.
  Eigen::Matrix3d R_rect_cam0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R_rect_cam0(r, c) = R0.at<double>(r, c);
  calib.T_cam0_rect = make_se3(Eigen::Matrix3d(R_rect_cam0.transpose()), Eigen::Vector3d::Zero());
  return calib;
}

}  // namespace agvslam
