#pragma once
// Camera models. Every image the SLAM sees is a rectified pinhole pair: the right camera sits at
// +baseline_m along the x axis of the left camera, with identical intrinsics and rows aligned.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/core/se3.h"

namespace agvslam {

struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;

  Eigen::Vector2d project(const Eigen::Vector3d& p_c) const {
    return {fx * p_c.x() / p_c.z() + cx, fy * p_c.y() / p_c.z() + cy};
  }
  Eigen::Vector3d unproject(const Eigen::Vector2d& uv_px, double depth_m) const {
    return {(uv_px.x() - cx) / fx * depth_m, (uv_px.y() - cy) / fy * depth_m, depth_m};
  }
  cv::Matx33d K() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
  cv::Size size() const { return {width, height}; }
  bool valid() const { return fx > 0 && fy > 0 && width > 0 && height > 0; }
};

// A camera before rectification: pinhole with radial-tangential distortion (k1, k2, p1, p2[, k3]).
struct RawCamera {
  PinholeCamera pinhole;
  std::vector<double> distortion;  // OpenCV order: k1 k2 p1 p2 [k3 ...]; empty = none
};

// Two raw cameras and their relative pose (T_cam1_cam0 maps points in cam0 into cam1).
struct RawStereoRig {
  RawCamera cam0, cam1;
  SE3d T_cam1_cam0 = SE3d::Identity();
};

struct StereoCalibration {
  PinholeCamera left;     // rectified left camera; the right one shares these intrinsics
  double baseline_m = 0;  // distance between the optical centres, > 0

  // Set when the source images are raw (EuRoC, a raw V4L2 camera): remap tables from raw to rectified.
  bool needs_rectification = false;
  cv::Mat map_left_x, map_left_y, map_right_x, map_right_y;  // CV_32FC1, rectified size
  SE3d T_cam0_rect = SE3d::Identity();                       // rectified left frame expressed in the raw cam0 frame

  double bf() const { return left.fx * baseline_m; }
  double depth_from_disparity(double disparity_px) const { return bf() / disparity_px; }
  double disparity_from_depth(double depth_m) const { return bf() / depth_m; }

  // Produces the rectified pair (copies when no rectification is needed).
  void rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect, cv::Mat& right_rect) const;

  // Human-readable one-line summary for start-up logs.
  std::string summary() const;
};

// Rectifies a raw rig (OpenCV stereoRectify, alpha = 0: only valid pixels, same size as the input).
StereoCalibration rectify_rig(const RawStereoRig& rig);

}  // namespace agvslam
