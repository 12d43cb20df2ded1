#pragma once
// Bilinear interpolation of an 8-bit grey image: shared by the stages that warp an earlier image (the photometric
// check, the left-band segmenter).
#include <cstdint>
#include <opencv2/core.hpp>

namespace agvslam::dynamic {

// image: CV_8UC1; (x, y) with 0 <= x < cols - 1 and 0 <= y < rows - 1 (the caller checks).
inline double bilinear_u8(const cv::Mat& image, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const uint8_t* r0 = image.ptr<uint8_t>(y0);
  const uint8_t* r1 = image.ptr<uint8_t>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

}  // namespace agvslam::dynamic
