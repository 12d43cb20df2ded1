#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>

namespace agvslam {

// One synchronised, rectified grey stereo pair (CV_8UC1 each, same size).
struct StereoFrame {
  std::size_t index = 0;  // position in its sequence
  int64_t t_ns = 0;       // capture time of the left image
  cv::Mat left, right;
};

}  // namespace agvslam
