#pragma once
// PNG writer for the simulator's outputs (libpng), with one fixed row filter per image kind instead of the
// per-row trial of all five filters that cv::imwrite leaves to libpng when a compression level is given (that
// trial cost more than the deflate itself: ~60 % of the time spent writing a frame). The pixels are stored
// exactly (PNG is lossless); only the file bytes depend on the filter.
//
// Measured on scene5 frame 300 (zlib level 1, run-length strategy): sensor images SUB 212 kB (all filters:
// 198 kB, Paeth 200 kB at +30 % time: branchy on noise), disparity Paeth 28 kB (the same as all filters; SUB
// 91 kB), masks NONE 1.3 kB.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::sim {

enum class PngFilter : uint8_t { kNone, kSub, kUp, kAverage, kPaeth };

class PngWriter {
 public:
  // zlib_level 0..9 (0: stored), zlib's run-length strategy.
  explicit PngWriter(int zlib_level);

  // Encodes a single-channel CV_8UC1 or CV_16UC1 image into bytes() (a buffer reused from call to call).
  // Throws InputError naming `what` for another type or an empty image, std::runtime_error if libpng fails.
  const std::vector<uint8_t>& encode(const cv::Mat& image, PngFilter filter, const std::string& what = "image");
  // encode() and write the bytes to `path`; throws InputError naming `option` and the path when it cannot.
  void write(const std::string& path, const cv::Mat& image, PngFilter filter, const std::string& option = "--out");

  const std::vector<uint8_t>& bytes() const { return buffer_; }

 private:
  int zlib_level_;
  std::vector<uint8_t> buffer_;
  std::vector<const uint8_t*> rows_;
};

}  // namespace agvslam::sim
