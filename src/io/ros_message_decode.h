#pragma once
// Private to the io module: the ROS 2 messages a rosbag2 dataset reads, decoded from their CDR bytes (cdr.h).
// Declared here rather than inside rosbag_dataset.cpp so that tests/fuzz feeds them arbitrary messages.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/io/rosbag_dataset.h"
#include "cdr.h"

namespace agvslam::io::detail {

// The fields of a sensor_msgs/msg/CameraInfo that the dataset uses.
struct CameraInfo {
  std::string topic;
  int width = 0, height = 0;
  std::string distortion_model;
  std::vector<double> d, k, r, p;
};

// Each throws InputError naming the message and field (via the reader) for a message that ends early or holds a
// value the dataset cannot use.
CameraInfo decode_camera_info(CdrReader& in, const std::string& topic);
BagOdometrySample decode_odometry(CdrReader& in);
// Grey 8-bit image of a sensor_msgs/msg/Image message.
cv::Mat decode_raw_image(CdrReader& in, const std::string& source, const std::string& context);
// Grey 8-bit image of a sensor_msgs/msg/CompressedImage message (png / jpeg).
cv::Mat decode_compressed_image(CdrReader& in, const std::string& source, const std::string& context);

}  // namespace agvslam::io::detail
