#pragma once
// Conversion of what a V4L2 camera delivers into 8-bit grey, without allocation per frame.

#include <cstddef>
#include <cstdint>

#include <string>
#include <vector>

#include <opencv2/core.hpp>

struct v4lconvert_data;

namespace agvslam::drivers::v4l2 {

// Copies a GREY image whose rows are bytes_per_line apart into `grey` (CV_8UC1, width x height).
void grey_to_grey(const uint8_t* src, std::size_t bytes_per_line, cv::Mat& grey);

// Takes the luma bytes of a packed YUYV 4:2:2 image (Y0 U Y1 V ...): exact, no colour maths.
void yuyv_to_grey(const uint8_t* src, std::size_t bytes_per_line, cv::Mat& grey);

// 64-bit FNV-1a over the image's pixels taken as 64-bit words, row by row (stride-independent): used by the tools to
// check that frames arrive pixel-exact.
uint64_t image_hash(const cv::Mat& grey);

// MJPEG to grey with libv4lconvert (libv4l2's conversion library): JPEG -> YUV 4:2:0, whose Y plane is the
// grey image. libv4lconvert requires the size to be a multiple of the JPEG block size (16 for 4:2:0), as every
// UVC camera's MJPEG sizes are.
class MjpegDecoder {
 public:
  // fd: the open device (libv4lconvert queries it); -1: no device (tests, benchmarks). Throws std::runtime_error
  // when libv4lconvert cannot be set up.
  explicit MjpegDecoder(int fd = -1);
  ~MjpegDecoder();
  MjpegDecoder(const MjpegDecoder&) = delete;
  MjpegDecoder& operator=(const MjpegDecoder&) = delete;
  // Decodes one JPEG into `grey`, whose size (CV_8UC1, width x height) must already be set. Returns false for a
  // JPEG libv4lconvert rejects (error() says why).
  bool decode(const uint8_t* jpeg, std::size_t size, cv::Mat& grey);
  std::string error() const;

 private:
  v4lconvert_data* convert_ = nullptr;
  std::vector<uint8_t> yuv420_;
};

}  // namespace agvslam::drivers::v4l2
