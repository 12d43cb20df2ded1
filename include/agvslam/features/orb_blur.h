#pragma once
// The descriptor image of the ORB extractor (the blurred pyramid of OrbExtractor): Gaussian 7x7, sigma 2, computed
// exactly as cv::GaussianBlur computes it for a submatrix with a reflected border on this kind of CPU
// (OpenCV's separable float filter with its AVX2 + FMA kernels: a row pass of fused multiply-adds over the 7 taps
// in order, a symmetric column pass, rounding half to even). cv::ORB blurs its pyramid that way, so descriptors
// computed on this image equal cv::ORB::compute's (tests/features/test_orb_blur.cpp compares the images).
#include <opencv2/core.hpp>
#include <vector>

namespace agvslam::features {

class OrbBlur {
 public:
  OrbBlur();
  // src: a view with at least 3 readable pixels on every side (its reflected border); dst: same size, CV_8UC1.
  // Returns false (and does nothing) where this CPU lacks AVX2 and FMA or the image is narrower than 8 px; the
  // caller then uses cv::GaussianBlur on the same view.
  bool blur(const cv::Mat& src, cv::Mat& dst);

 private:
  float kernel_[7];
  std::vector<float> rows_;     // 7 filtered rows (ring)
  std::vector<float> convert_;  // one source row as float
  bool fma_ = false;
};

}  // namespace agvslam::features
