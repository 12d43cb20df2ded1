#pragma once
// One V4L2 capture device opened through libv4l2, streaming into mmap buffers (RAII: the destructor stops the
// stream, unmaps the buffers and closes the fd). And the output side used by the test feeder (a v4l2loopback
// device written with write()).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "agvslam/drivers/v4l2/camera_config.h"
#include "agvslam/drivers/v4l2/pixel_convert.h"

namespace agvslam::drivers::v4l2 {

// A device error. The message names the device, the operation and what was expected or what the system said.
// configuration() is true when the device works but cannot deliver what was asked (not a capture device, format
// not offered, size refused): retrying will not help. Everything else (ENODEV, EIO, ENOENT, EBUSY, a stalled
// stream) may go away when the device comes back.
class V4l2Error : public std::runtime_error {
 public:
  V4l2Error(const std::string& device, const std::string& what, bool configuration = false, int errno_value = 0);
  const std::string& device() const noexcept { return device_; }
  bool configuration() const noexcept { return configuration_; }
  int errno_value() const noexcept { return errno_; }

 private:
  std::string device_;
  bool configuration_;
  int errno_;
};

struct CaptureRequest {
  int width = 0, height = 0;  // the device's image size (side by side: both eyes)
  PixelFormat pixel_format = PixelFormat::kGrey;
  double fps = 0;  // 0 = keep the device's rate
  int buffers = 4;
};

// A dequeued buffer converted to grey.
struct CapturedImage {
  int64_t t_ns = 0;         // buffer time stamp, CLOCK_MONOTONIC ns (see V4l2Device::timestamp_source)
  uint32_t sequence = 0;    // V4L2 buffer sequence number
  bool error_flag = false;  // V4L2_BUF_FLAG_ERROR: the driver says the data may be corrupt
};

class V4l2Device {
 public:
  // Opens `path`, checks it is a streaming capture device, sets format, size and frame rate, maps the buffers,
  // queues them and starts streaming. Throws V4l2Error.
  V4l2Device(const std::string& path, const CaptureRequest& request);
  ~V4l2Device();
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;

  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  std::string card() const { return card_; }         // VIDIOC_QUERYCAP card name
  double actual_fps() const { return actual_fps_; }  // what VIDIOC_G_PARM reports, 0 when unknown
  // "monotonic" when the driver flags its time stamps V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, else "unknown" (then
  // a time stamp far from CLOCK_MONOTONIC's now is replaced by the dequeue time).
  const char* timestamp_source() const { return timestamp_monotonic_ ? "monotonic" : "unknown"; }

  // Dequeues one filled buffer (call when poll() says the fd is readable), converts it into `grey` (CV_8UC1,
  // reusing its buffer when the size matches) and requeues the buffer. Returns false when no buffer was ready
  // (EAGAIN). Throws V4l2Error for ENODEV, EIO and other failures.
  bool dequeue(cv::Mat& grey, CapturedImage& info);

 private:
  void fail(const std::string& op, bool configuration = false) const;  // throws with errno
  std::string offered_formats();
  void set_format(const CaptureRequest& r);
  void set_rate(double fps);
  void start_streaming(int buffers);
  void release() noexcept;

  std::string path_, card_;
  int fd_ = -1;
  bool streaming_ = false;
  bool timestamp_monotonic_ = false;
  uint32_t pix_ = 0;
  int width_ = 0, height_ = 0;
  std::size_t bytes_per_line_ = 0, size_image_ = 0;
  double actual_fps_ = 0;
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  std::vector<Buffer> buffers_;
  std::unique_ptr<MjpegDecoder> mjpeg_;  // MJPEG only
  uint64_t decode_failures_ = 0;
};

// A V4L2 output device (e.g. a v4l2loopback node) that takes GREY frames, or MJPEG frames (one JPEG per buffer,
// bytesused = its size, as a UVC camera delivers them). Used by agvslam-v4l2-feed. Two ways:
//   kQueue  mmap output buffers queued with VIDIOC_QBUF carrying the caller's time stamp (CLOCK_MONOTONIC), so
//           both eyes of a pair can carry one capture time, as from a hardware-triggered stereo camera
//   kWrite  write(): the receiving driver stamps each frame when it is written and numbers it (v4l2loopback sets
//           the buffer sequence only on this path), as two free-running cameras
class V4l2Output {
 public:
  enum class Mode { kQueue, kWrite };
  // format: PixelFormat::kGrey or kMjpeg. Throws V4l2Error.
  V4l2Output(const std::string& path, int width, int height, Mode mode = Mode::kQueue,
             PixelFormat format = PixelFormat::kGrey);
  ~V4l2Output();
  V4l2Output(const V4l2Output&) = delete;
  V4l2Output& operator=(const V4l2Output&) = delete;
  // Announces the format to readers without writing a frame (v4l2loopback: VIDIOC_STREAMON on the output).
  void announce();
  // One frame, CV_8UC1 of the configured size; t_ns is its capture time (kQueue; kWrite ignores it).
  void write(const cv::Mat& grey, int64_t t_ns);
  // One frame as bytes (a JPEG for kMjpeg; width * height bytes for kGrey).
  void write_bytes(const uint8_t* data, std::size_t size, int64_t t_ns);
  const std::string& path() const { return path_; }

 private:
  void release() noexcept;
  std::string path_;
  int fd_ = -1;
  int width_, height_;
  Mode mode_;
  PixelFormat format_;
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  std::vector<Buffer> buffers_;
  std::size_t next_ = 0;
};

}  // namespace agvslam::drivers::v4l2
