#pragma once
// Calibration loaders. All of them produce one StereoCalibration (rectified pinhole + baseline, plus
// rectification maps when the images are raw).
//
//   KITTI calib.txt   "P0: 12 numbers" / "P1: ..." lines, or the same lines without the labels (first two
//                     lines = P0, P1). Baseline = -P1[0,3] / P1[0,0]. Already rectified.
//   ORB-SLAM YAML     OpenCV FileStorage: Camera.fx/fy/cx/cy, Camera.bf, Camera.width/height; optional
//                     LEFT.K/D/R/P, RIGHT.K/D/R/P (+ LEFT.width/height) for raw images.
//   Kalibr camchain   cam0/cam1 with intrinsics [fu fv pu pv], distortion_model radtan, distortion_coeffs,
//                     resolution [w h], cam1.T_cn_cnm1 (4x4).
//   EuRoC sensor.yaml two files (cam0, cam1): intrinsics, distortion_coefficients, resolution, T_BS.
// A missing field, a wrong count, a NaN or a non-positive focal length/baseline raises InputError naming the
// file and the field.

#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"

namespace agvslam::io {

// A rectified pair from its left and right 3x4 projection matrices (12 values, row-major: KITTI's P0/P1, a ROS
// CameraInfo's p): the left camera's fx, fy, cx, cy and the baseline from P[0,3] = -fx * x of each camera. InputError
// naming `source` and `left_field` / `right_field` for a value that is not finite, a focal length or baseline that
// is not positive, or a right matrix of another rectification (other fx or cy).
StereoCalibration calibration_from_projections(const std::vector<double>& P_left, const std::vector<double>& P_right,
                                               cv::Size image_size, const std::string& source,
                                               const std::string& left_field, const std::string& right_field);

// image_size: the size of the images the file belongs to (KITTI calib.txt does not say).
StereoCalibration load_kitti_calib(const std::string& path, cv::Size image_size);
// Writes labelled "P0: ..", "P1: .." lines (P1[0,3] = -fx * baseline).
void write_kitti_calib(const std::string& path, const StereoCalibration& calib);

StereoCalibration load_orbslam_yaml(const std::string& path);
RawStereoRig load_kalibr_camchain_rig(const std::string& path);
StereoCalibration load_kalibr_camchain(const std::string& path);
// One EuRoC sensor.yaml (a single camera): the raw camera and T_BS (= T_B_cam, the camera in the body frame).
struct EurocCameraSensor {
  RawCamera camera;
  SE3d T_B_S = SE3d::Identity();
};
EurocCameraSensor load_euroc_sensor(const std::string& sensor_yaml);

RawStereoRig load_euroc_rig(const std::string& cam0_sensor_yaml, const std::string& cam1_sensor_yaml);
StereoCalibration load_euroc_calibration(const std::string& cam0_sensor_yaml, const std::string& cam1_sensor_yaml);

// Detects the format from the file's content (KITTI text, ORB-SLAM YAML, Kalibr camchain).
// image_size is needed only for KITTI calib.txt.
StereoCalibration load_calibration(const std::string& path, std::optional<cv::Size> image_size = std::nullopt);

}  // namespace agvslam::io
