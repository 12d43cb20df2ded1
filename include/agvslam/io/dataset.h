#pragma once
// Stereo sequences on disk. Every dataset yields rectified grey pairs with one StereoCalibration.
//
//   KITTI odometry layout (also what agvslam-sim writes):
//     image_0/ + image_1/ (or image_l/ + image_r/), NNNNNN.png; calib.txt; times.txt (optional: 10 Hz
//     assumed without it); poses.txt (optional ground truth, T_w_cam0). Simulator extras: disp_0/ (16-bit,
//     disparity*256, 0 = none), mask_0/ (8-bit, 255 = moving object), instance_0/ (8-bit, object id per
//     pixel, 0 = none), objects.txt.
//   EuRoC ASL layout: mav0/cam0|cam1/data.csv + data/ + sensor.yaml. Left and right are paired by time
//     stamp; a frame listed in a CSV whose image is missing, or that has no partner, is skipped with a
//     warning. Images are rectified with maps computed from the two sensor.yaml files.
//   rosbag2 recordings (metadata.yaml + .db3): rosbag_dataset.h.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/core/trajectory.h"

namespace agvslam::io {

class StereoDataset {
 public:
  virtual ~StereoDataset() = default;

  virtual std::string kind() const = 0;  // "kitti", "euroc" or "rosbag2"
  virtual const std::string& root() const = 0;
  virtual std::size_t size() const = 0;
  virtual double rate_hz() const = 0;
  virtual const StereoCalibration& calibration() const = 0;
  virtual int64_t timestamp_ns(std::size_t i) const = 0;

  // Loads frame i (0 <= i < size()), rectified, CV_8UC1. Throws InputError for an unreadable image.
  virtual StereoFrame frame(std::size_t i) const = 0;

  // Ground truth of the rectified left camera, one pose per frame where known (may be shorter).
  virtual std::optional<Trajectory> ground_truth() const { return std::nullopt; }
  // Simulator ground truth: empty Mat when the dataset has none.
  virtual cv::Mat ground_truth_mask(std::size_t /*i*/) const { return {}; }
  // CV_8UC1, the id (objects.txt) of the object seen at each pixel, 0 = none; empty Mat when the dataset has none.
  virtual cv::Mat ground_truth_instances(std::size_t /*i*/) const { return {}; }
  virtual cv::Mat ground_truth_disparity_px(std::size_t /*i*/) const { return {}; }  // CV_32FC1, 0 = none
  // Wheel odometry recorded with the images (a rosbag2 nav_msgs/msg/Odometry topic), by time; empty when the
  // dataset has none.
  virtual std::vector<OdometryRate> wheel_odometry() const { return {}; }
};

class KittiDataset final : public StereoDataset {
 public:
  // calib_override: a calibration file in any supported format instead of <root>/calib.txt.
  explicit KittiDataset(const std::string& root, const std::string& calib_override = "");

  std::string kind() const override { return "kitti"; }
  const std::string& root() const override { return root_; }
  std::size_t size() const override { return times_ns_.size(); }
  double rate_hz() const override { return rate_hz_; }
  const StereoCalibration& calibration() const override { return calib_; }
  int64_t timestamp_ns(std::size_t i) const override { return times_ns_.at(i); }
  StereoFrame frame(std::size_t i) const override;
  std::optional<Trajectory> ground_truth() const override;
  cv::Mat ground_truth_mask(std::size_t i) const override;
  cv::Mat ground_truth_instances(std::size_t i) const override;
  cv::Mat ground_truth_disparity_px(std::size_t i) const override;

  const std::string& left_dir() const { return left_dir_; }
  const std::string& right_dir() const { return right_dir_; }
  // Paths of the images of frame i (sorted .png names of the left and right folders).
  std::string left_path(std::size_t i) const;
  std::string right_path(std::size_t i) const;

 private:
  cv::Mat ground_truth_u8(const char* folder, std::size_t i, const char* content) const;

  std::string root_, left_dir_, right_dir_;
  std::vector<std::string> left_names_, right_names_;  // file names, sorted
  std::vector<int64_t> times_ns_;
  cv::Size image_size_;  // size of the images on disk (from the first left image)
  double rate_hz_ = 10.0;
  StereoCalibration calib_;
};

class EurocDataset final : public StereoDataset {
 public:
  explicit EurocDataset(const std::string& root, const std::string& calib_override = "");

  std::string kind() const override { return "euroc"; }
  const std::string& root() const override { return root_; }
  std::size_t size() const override { return pairs_.size(); }
  double rate_hz() const override { return rate_hz_; }
  const StereoCalibration& calibration() const override { return calib_; }
  int64_t timestamp_ns(std::size_t i) const override { return pairs_.at(i).t_ns; }
  StereoFrame frame(std::size_t i) const override;
  // From mav0/state_groundtruth_estimate0/data.csv (body poses) when present, converted to the
  // rectified left camera with cam0's T_BS and the rectification rotation.
  std::optional<Trajectory> ground_truth() const override;

  // Frames skipped while pairing (listed without an image, or without a partner within 1 ms).
  std::size_t skipped_frames() const { return skipped_; }
  // cam0's pose in the EuRoC body frame (T_BS of mav0/cam0/sensor.yaml; identity with a calibration override
  // when that file is absent).
  const SE3d& T_B_cam0() const { return T_B_cam0_; }
  const std::string& left_path(std::size_t i) const { return pairs_.at(i).left_path; }
  const std::string& right_path(std::size_t i) const { return pairs_.at(i).right_path; }

 private:
  struct Pair {
    int64_t t_ns;
    std::string left_path, right_path;
  };
  std::string root_;
  std::vector<Pair> pairs_;
  double rate_hz_ = 20.0;
  cv::Size image_size_;  // raw image size (sensor.yaml resolution)
  StereoCalibration calib_;
  SE3d T_B_cam0_ = SE3d::Identity();
  std::size_t skipped_ = 0;
};

// Detects the layout (metadata.yaml -> rosbag2, mav0/ -> EuRoC, image_0|image_l -> KITTI) and opens it. A
// rosbag2 folder may carry its topic choice as a query: BAG?left=TOPIC&right=TOPIC&odom=TOPIC (rosbag_dataset.h).
// Throws InputError naming the folder and what was expected when none is found.
std::unique_ptr<StereoDataset> open_dataset(const std::string& root, const std::string& calib_override = "");

// "A:B" (inclusive, either side may be empty) -> [first, last] clipped to `size` frames; throws
// InputError(source, field, ...) for a malformed or empty range (agvslam-run / agvslam-dynamic --frames,
// agvslamd source.frames).
void parse_frame_range(const std::string& text, std::size_t size, const std::string& source, const std::string& field,
                       std::size_t& first, std::size_t& last);

}  // namespace agvslam::io
