#pragma once
// A rosbag2 recording as a stereo dataset, so users replay their own recordings (agvslam-run --dataset BAG,
// agvslamd source.dataset: BAG; io::open_dataset picks it when the folder holds metadata.yaml).
//
//   Layout (`ros2 bag record`, Humble and later, sqlite3 storage): BAG/metadata.yaml with
//     rosbag2_bagfile_information: storage_identifier (sqlite3), relative_file_paths (the .db3 files, in
//     order), topics_with_message_count (topic_metadata: name, type, serialization_format), compression_format
//     (empty: compressed bags are not read).
//   Each .db3: topics(id, name, type, serialization_format, ...) and messages(id, topic_id, timestamp, data),
//     data = the CDR-serialised message (XCDR1, either byte order). MCAP storage is refused with the way out
//     (`ros2 bag convert` to sqlite3): no maintained MCAP reader is packaged in Debian.
//
//   Messages read:
//     sensor_msgs/msg/Image            mono8 / 8UC1, mono16 / 16UC1 (top 8 bits kept), bgr8, rgb8, bgra8, rgba8
//                                      (converted to grey); other encodings raise InputError naming the topic.
//     sensor_msgs/msg/CompressedImage  png or jpeg, decoded to grey.
//     sensor_msgs/msg/CameraInfo       <namespace>/camera_info beside each image topic (/cam/left/image_raw and
//                                      /cam/left/image_raw/compressed -> /cam/left/camera_info). With both sides
//                                      and no calibration file given, the first message of each is the
//                                      calibration: rectified intrinsics from P, baseline = -P_right[3] / fx;
//                                      images with distortion (d not all zero) or a rotation r not identity are
//                                      rectified with maps from k, d, r, p (as ROS image_proc does). Otherwise a
//                                      calibration file is required.
//     nav_msgs/msg/Odometry            wheel odometry (odometry(), wheel_odometry()).
//   Time stamps are the messages' header stamps (not the recording time).
//
//   Topics: the left and right image topics are found when the bag has exactly one image topic whose name has a
//   path element containing "left" and one containing "right" (/stereo/left/image_rect, /cam_right/image_raw/
//   compressed), or exactly two image topics (then the first by name is the left one: cam0 / cam1, infra1 /
//   infra2); a CompressedImage topic T/compressed recorded beside its Image topic T is left aside (T is lossless).
//   The odometry topic is the bag's only nav_msgs/msg/Odometry topic. Choose them explicitly by appending
//   a query to the folder: BAG?left=/cam/left/image_raw&right=/cam/right/image_raw&odom=/wheel/odom (quote it in
//   the shell; any subset of the keys).
//   Left and right images are paired by header stamp (closest partner within half a frame period); unpaired ones
//   are skipped, counted and logged. Frames are held as references into the .db3 files and loaded on demand.

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "agvslam/io/dataset.h"

namespace agvslam::io {

// Topic choices of a bag (empty = found automatically).
struct RosbagTopics {
  std::string left, right, odometry;
};

// "left=/a&right=/b&odom=/c" -> topics; throws InputError(source, ...) for an unknown key or a malformed pair.
RosbagTopics parse_rosbag_topics(const std::string& query, const std::string& source);

// One nav_msgs/msg/Odometry message.
struct BagOdometrySample {
  int64_t t_ns = 0;                                         // header stamp
  std::string frame_id, child_frame_id;                     // usually odom, base_link
  SE3d T_frame_child = SE3d::Identity();                    // pose.pose: the child frame in frame_id, metres
  Eigen::Vector3d linear_mps = Eigen::Vector3d::Zero();     // twist.twist.linear, in child_frame_id
  Eigen::Vector3d angular_radps = Eigen::Vector3d::Zero();  // twist.twist.angular, in child_frame_id
};

class RosbagDataset final : public StereoDataset {
 public:
  // bag_dir: the folder holding metadata.yaml. calib_override: a calibration file (any format load_calibration
  // reads) used instead of the bag's camera_info.
  explicit RosbagDataset(const std::string& bag_dir, const std::string& calib_override = "",
                         const RosbagTopics& topics = {});
  ~RosbagDataset() override;
  RosbagDataset(const RosbagDataset&) = delete;
  RosbagDataset& operator=(const RosbagDataset&) = delete;

  std::string kind() const override { return "rosbag2"; }
  const std::string& root() const override { return root_; }
  std::size_t size() const override { return pairs_.size(); }
  double rate_hz() const override { return rate_hz_; }
  const StereoCalibration& calibration() const override { return calib_; }
  int64_t timestamp_ns(std::size_t i) const override { return pairs_.at(i).t_ns; }
  // Reads and decodes both messages of frame i. Throws InputError naming the .db3 file, the topic and the field
  // for a truncated message, an unknown encoding or an image of another size than the first frame's.
  StereoFrame frame(std::size_t i) const override;
  std::vector<OdometryRate> wheel_odometry() const override;

  const std::string& left_topic() const { return left_topic_; }
  const std::string& right_topic() const { return right_topic_; }
  const std::string& odometry_topic() const { return odometry_topic_; }  // empty when the bag has none
  // True when the calibration came from the bag's camera_info messages.
  bool calibration_from_camera_info() const { return calib_from_bag_; }
  // Image messages not paired with one of the other side (and ones whose header could not be read).
  std::size_t skipped_images() const { return skipped_; }
  // All messages of the odometry topic, by header stamp.
  const std::vector<BagOdometrySample>& odometry() const { return odometry_; }

  struct Storage;  // the open .db3 files (sqlite3), private to the implementation

 private:
  struct MessageRef {
    std::size_t file = 0;  // index into the .db3 files
    int64_t row_id = 0;    // messages.id
  };
  struct Pair {
    int64_t t_ns = 0;
    MessageRef left, right;
  };
  cv::Mat read_image(const MessageRef& ref, const std::string& topic, bool compressed) const;

  std::string root_;
  std::string left_topic_, right_topic_, odometry_topic_;
  bool left_compressed_ = false, right_compressed_ = false;
  std::unique_ptr<Storage> storage_;
  mutable std::mutex storage_mutex_;  // one reader of the sqlite handles at a time
  std::vector<Pair> pairs_;
  std::vector<BagOdometrySample> odometry_;
  std::size_t skipped_ = 0;
  double rate_hz_ = 10.0;
  cv::Size image_size_;  // of the first frame's left image
  StereoCalibration calib_;
  bool calib_from_bag_ = false;
};

}  // namespace agvslam::io
