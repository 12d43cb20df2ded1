#pragma once
// Bilinear downscaling bit-exact with cv::resize(..., INTER_LINEAR_EXACT) for 8-bit grey images (used for the
// features module's pyramids): the same fixed-point weights (8 fractional bits, from OpenCV's formula in double
// precision) and the same single rounding of the exact integer sum. cv::resize spends ~17 instructions per output pixel
// at these sizes; this one shuffles eight pixels at a time (SSSE3) and blends rows with SSE2, and it allocates nothing
// once its tables are built for a size.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace agvslam::features {

class LinearExactResizer {
 public:
  // Resizes src (CV_8UC1) into dst (CV_8UC1, already of the wanted size). Each src row must stay readable 16
  // bytes past its width (a border or a padded buffer). Falls back to cv::resize where this scheme does not apply
  // (upscaling, more than 2x, exact halving, which OpenCV does by area averaging).
  void resize(const cv::Mat& src, cv::Mat& dst);

  // Whether the fast path served the last call (for tests).
  bool last_was_fast() const { return last_fast_; }

 private:
  void prepare(cv::Size src, cv::Size dst);
  void horizontal(const uint8_t* src_row, uint16_t* out) const;

  cv::Size src_size_, dst_size_;
  bool usable_ = false, last_fast_ = false, ssse3_ = false;
  std::vector<int> x_ofs_;             // per output column: left source column
  std::vector<uint16_t> x_c0_, x_c1_;  // weights of x_ofs and x_ofs + 1 (sum 256)
  std::vector<int> y_ofs_;             // per output row: upper source row
  std::vector<uint16_t> y_c0_, y_c1_;
  std::vector<int> block_base_;         // per 8 output columns: first source column they read
  std::vector<uint8_t> block_shuffle_;  // per block: 16-byte shuffles for x_ofs and x_ofs + 1
  std::vector<uint16_t> rows_[2];       // horizontally resized source rows (8 fractional bits)
  int row_id_[2] = {-1, -1};
};

}  // namespace agvslam::features
