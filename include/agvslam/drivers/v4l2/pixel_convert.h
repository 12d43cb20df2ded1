#pragma once
// Conversion of what a V4L2 camera delivers into 8-bit grey, without allocation per frame.

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace agvslam::drivers::v4l2 {

// Copies a GREY image whose rows are bytes_per_line apart into `grey` (CV_8UC1, width x height).
void grey_to_grey(const uint8_t* src, std::size_t bytes_per_line, cv::Mat& grey);

// Takes the luma bytes of a packed YUYV 4:2:2 image (Y0 U Y1 V ...): exact, no colour maths.
void yuyv_to_grey(const uint8_t* src, std::size_t bytes_per_line, cv::Mat& grey);

// 64-bit FNV-1a over the image's pixels taken as 64-bit words, row by row (stride-independent): used by the tools to check that
// frames arrive pixel-exact.
uint64_t image_hash(const cv::Mat& grey);

}  // namespace agvslam::drivers::v4l2
