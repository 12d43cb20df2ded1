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

#include "agvslam/core/camera.h"

namespace agvslam::io {

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
