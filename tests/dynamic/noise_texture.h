#pragma once
// Fine random texture for the photometric tests (photometric check, motion carving): uniform noise blurred with
// sigma 1.2 px and stretched to 0..255, so that a shift of 1-2 px changes every pixel.
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace agvslam::dynamic::test {

inline cv::Mat noise_texture(int w, int h, uint32_t seed) {
  cv::Mat noise(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat smooth;
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 1.2);
  cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
  return smooth;
}

}  // namespace agvslam::dynamic::test
