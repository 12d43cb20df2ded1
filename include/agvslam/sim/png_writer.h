#pragma once
// PNG writer for the simulator's outputs: one fixed row filter per image kind, and libdeflate (several times
// faster than zlib at the same level and ratio) for the compressed stream; the PNG chunks around it (signature,
// IHDR, IDAT, IEND with their CRCs) are written here. cv::imwrite with a compression level left libpng trying all
// five filters on every row, which cost more than the deflate itself. The pixels are stored exactly (PNG is
// lossless); only the file bytes depend on the filter and level.
//
// Measured on scene5 frame 300 (level 1): sensor images Paeth 213 kB (SUB 223 kB; libpng's all-filter trial with
// zlib 198 kB at 2.6x the instructions), disparity Paeth 31 kB, masks NONE 1.7 kB.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::sim {

// PNG filter types (the values are the filter-type bytes of the scanlines).
enum class PngFilter : uint8_t { kNone = 0, kSub = 1, kUp = 2, kAverage = 3, kPaeth = 4 };

class PngWriter {
 public:
  // zlib_level 0..9 (0: stored; libdeflate's levels, zlib-like).
  explicit PngWriter(int zlib_level);
  ~PngWriter();
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;

  // Encodes a single-channel CV_8UC1 or CV_16UC1 image into bytes() (a buffer reused from call to call).
  // Throws InputError naming `what` for another type or an empty image.
  const std::vector<uint8_t>& encode(const cv::Mat& image, PngFilter filter, const std::string& what = "image");
  // encode() and write the bytes to `path`; throws InputError naming `option` and the path when it cannot.
  void write(const std::string& path, const cv::Mat& image, PngFilter filter, const std::string& option = "--out");

  const std::vector<uint8_t>& bytes() const { return buffer_; }

 private:
  struct Compressor;  // libdeflate's compressor (RAII)
  std::unique_ptr<Compressor> compressor_;
  std::vector<uint8_t> buffer_;                 // the PNG file
  std::vector<uint8_t> filtered_, prev_, cur_;  // filtered scanlines; raw (big-endian) rows
};

}  // namespace agvslam::sim
