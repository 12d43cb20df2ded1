#include "agvslam/drivers/v4l2/device.h"

#include <fcntl.h>
#include <libv4l2.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <sstream>

#include <spdlog/spdlog.h>

#include "agvslam/drivers/v4l2/pixel_convert.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"

namespace agvslam::drivers::v4l2 {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = v4l2_ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

std::string errno_text(int e) { return std::string(std::strerror(e)) + " (errno " + std::to_string(e) + ")"; }

}  // namespace

V4l2Error::V4l2Error(const std::string& device, const std::string& what, bool configuration, int errno_value)
    : std::runtime_error(device + ": " + what), device_(device), configuration_(configuration), errno_(errno_value) {}

void V4l2Device::fail(const std::string& op, bool configuration) const {
  const int e = errno;
  throw V4l2Error(path_, op + " failed: " + errno_text(e), configuration, e);
}

V4l2Device::V4l2Device(const std::string& path, const CaptureRequest& request) : path_(path) {
  try {
    const int raw = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (raw < 0) {
      const int e = errno;
      throw V4l2Error(path_,
                      "cannot open: " + errno_text(e) + (e == ENOENT ? "; expected a V4L2 capture device node" : ""),
                      false, e);
    }
    // Native formats only: GREY and YUYV are used as delivered, MJPEG is decoded with libv4lconvert below.
    fd_ = v4l2_fd_open(raw, V4L2_DISABLE_CONVERSION);
    if (fd_ < 0) {
      const int e = errno;
      ::close(raw);
      throw V4l2Error(
          path_,
          (e == ENOTTY ? "is not a V4L2 device (libv4l2: " + errno_text(e) + "); expected a V4L2 capture device node"
                       : "libv4l2 cannot take the device: " + errno_text(e) +
                             (e == EINVAL ? " (it has no current format: a v4l2loopback device without a writer, or a "
                                            "camera still starting)"
                                          : "")),
          e == ENOTTY, e);
    }
    v4l2_capability cap{};
    if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) {
      if (errno == ENOTTY || errno == EINVAL)
        throw V4l2Error(path_, "is not a V4L2 device (VIDIOC_QUERYCAP: " + errno_text(errno) + ")", true, errno);
      fail("VIDIOC_QUERYCAP");
    }
    card_ = reinterpret_cast<const char*>(cap.card);
    const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
      std::ostringstream s;
      s << "is not a video capture device ('" << card_ << "', capabilities 0x" << std::hex << caps
        << "); expected V4L2_CAP_VIDEO_CAPTURE (single-planar)";
      throw V4l2Error(path_, s.str(), true);
    }
    if (!(caps & V4L2_CAP_STREAMING))
      throw V4l2Error(path_, "does not support streaming I/O ('" + card_ + "'); expected V4L2_CAP_STREAMING", true);
    set_format(request);
    set_rate(request.fps);
    if (pix_ == V4L2_PIX_FMT_MJPEG) {
      if (width_ % 16 != 0 || height_ % 8 != 0)  // 4:2:2 JPEG blocks are 16x8, 4:2:0 16x16
        throw V4l2Error(path_,
                        "MJPEG at " + std::to_string(width_) + "x" + std::to_string(height_) +
                            ": libv4lconvert decodes only widths that are multiples of 16 and heights of 8 "
                            "(16 for 4:2:0)",
                        true);
      try {
        mjpeg_ = std::make_unique<MjpegDecoder>(fd_);
      } catch (const std::runtime_error& e) {
        throw V4l2Error(path_, e.what());
      }
    }
    start_streaming(request.buffers);
  } catch (...) {
    release();
    throw;
  }
}

V4l2Device::~V4l2Device() { release(); }

void V4l2Device::release() noexcept {
  if (fd_ >= 0 && streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);  // may fail on a vanished device; nothing to do about it
    streaming_ = false;
  }
  for (auto& b : buffers_)
    if (b.start) v4l2_munmap(b.start, b.length);
  buffers_.clear();
  mjpeg_.reset();
  if (fd_ >= 0) {
    v4l2_close(fd_);
    fd_ = -1;
  }
}

std::string V4l2Device::offered_formats() {
  std::string list;
  for (uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_ENUM_FMT, &d) < 0) break;
    if (!list.empty()) list += ", ";
    list += fourcc_to_string(d.pixelformat);
  }
  return list;
}

void V4l2Device::set_format(const CaptureRequest& r) {
  const uint32_t want = fourcc(r.pixel_format);
  const std::string offered = offered_formats();
  if (offered.empty())  // v4l2loopback before its writer starts; a camera still initialising
    throw V4l2Error(path_, "offers no capture format yet (VIDIOC_ENUM_FMT lists none)", false, EAGAIN);
  if (offered.find(fourcc_to_string(want)) == std::string::npos)
    throw V4l2Error(path_,
                    "does not offer pixel format " + fourcc_to_string(want) + " (" + to_string(r.pixel_format) +
                        "); it offers " + offered,
                    true);
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  f.fmt.pix.width = static_cast<uint32_t>(r.width);
  f.fmt.pix.height = static_cast<uint32_t>(r.height);
  f.fmt.pix.pixelformat = want;
  f.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &f) < 0) {
    const int e = errno;
    if (e == EBUSY || e == ENODEV || e == EIO) fail("VIDIOC_S_FMT " + fourcc_to_string(want));
    // Report what the device is delivering now, to say what it accepts.
    v4l2_format cur{};
    cur.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    std::string now;
    if (xioctl(fd_, VIDIOC_G_FMT, &cur) == 0)
      now = "; it delivers " + fourcc_to_string(cur.fmt.pix.pixelformat) + " " + std::to_string(cur.fmt.pix.width) +
            "x" + std::to_string(cur.fmt.pix.height);
    throw V4l2Error(path_,
                    "refused format " + fourcc_to_string(want) + " " + std::to_string(r.width) + "x" +
                        std::to_string(r.height) + " (VIDIOC_S_FMT: " + errno_text(e) + ")" + now,
                    true, e);
  }
  if (f.fmt.pix.pixelformat != want)
    throw V4l2Error(path_,
                    "was asked for " + fourcc_to_string(want) + " but chose " +
                        fourcc_to_string(f.fmt.pix.pixelformat) + "; it offers " + offered,
                    true);
  if (static_cast<int>(f.fmt.pix.width) != r.width || static_cast<int>(f.fmt.pix.height) != r.height)
    throw V4l2Error(path_,
                    "refused size " + std::to_string(r.width) + "x" + std::to_string(r.height) + " for " +
                        fourcc_to_string(want) + ": it delivers " + std::to_string(f.fmt.pix.width) + "x" +
                        std::to_string(f.fmt.pix.height) +
                        " (check camera.width/height; side by side: width is one eye)",
                    true);
  pix_ = want;
  width_ = r.width;
  height_ = r.height;
  bytes_per_line_ = f.fmt.pix.bytesperline;
  const std::size_t min_bpl = static_cast<std::size_t>(r.width) * (want == V4L2_PIX_FMT_YUYV ? 2 : 1);
  if (want != V4L2_PIX_FMT_MJPEG && bytes_per_line_ < min_bpl) bytes_per_line_ = min_bpl;
  size_image_ = f.fmt.pix.sizeimage;
}

void V4l2Device::set_rate(double fps) {
  v4l2_streamparm p{};
  p.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (fps > 0) {
    p.parm.capture.timeperframe.numerator = 1000;
    p.parm.capture.timeperframe.denominator = static_cast<uint32_t>(std::lround(fps * 1000.0));
    if (xioctl(fd_, VIDIOC_S_PARM, &p) < 0)
      spdlog::warn("{}: cannot set {} frames/s (VIDIOC_S_PARM: {}); using the device's rate", path_, fps,
                   errno_text(errno));
  }
  v4l2_streamparm g{};
  g.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_G_PARM, &g) == 0 && g.parm.capture.timeperframe.numerator > 0)
    actual_fps_ = static_cast<double>(g.parm.capture.timeperframe.denominator) / g.parm.capture.timeperframe.numerator;
}

void V4l2Device::start_streaming(int count) {
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) fail("VIDIOC_REQBUFS (mmap)", errno == EINVAL);
  if (req.count < 2)
    throw V4l2Error(path_, "granted " + std::to_string(req.count) + " buffers; expected at least 2", true);
  buffers_.resize(req.count);
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) fail("VIDIOC_QUERYBUF");
    void* p = v4l2_mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) fail("mmap of buffer " + std::to_string(i));
    buffers_[i] = {p, b.length};
    timestamp_monotonic_ = (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) fail("VIDIOC_QBUF");
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) fail("VIDIOC_STREAMON");
  streaming_ = true;
}

bool V4l2Device::dequeue(cv::Mat& grey, CapturedImage& info) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    if (errno == EAGAIN) return false;
    fail("VIDIOC_DQBUF");
  }
  const int64_t now = monotonic_now_ns();
  info.t_ns =
      static_cast<int64_t>(b.timestamp.tv_sec) * 1000000000LL + static_cast<int64_t>(b.timestamp.tv_usec) * 1000LL;
  // A driver that does not say its stamps are monotonic: keep them only when they look like CLOCK_MONOTONIC.
  if (!timestamp_monotonic_ && (info.t_ns <= 0 || info.t_ns > now || now - info.t_ns > 1000000000LL)) info.t_ns = now;
  info.sequence = b.sequence;
  info.error_flag = (b.flags & V4L2_BUF_FLAG_ERROR) != 0;
  if (b.index >= buffers_.size())
    throw V4l2Error(path_, "VIDIOC_DQBUF returned buffer index " + std::to_string(b.index) + " of " +
                               std::to_string(buffers_.size()));
  const auto* data = static_cast<const uint8_t*>(buffers_[b.index].start);
  const std::size_t used = b.bytesused ? b.bytesused : buffers_[b.index].length;
  if (!info.error_flag) {
    grey.create(height_, width_, CV_8UC1);
    if (pix_ == V4L2_PIX_FMT_GREY || pix_ == V4L2_PIX_FMT_YUYV) {
      const std::size_t row = static_cast<std::size_t>(width_) * (pix_ == V4L2_PIX_FMT_YUYV ? 2 : 1);
      if (used < bytes_per_line_ * static_cast<std::size_t>(height_ - 1) + row) {
        info.error_flag = true;  // a short frame
      } else if (pix_ == V4L2_PIX_FMT_GREY) {
        grey_to_grey(data, bytes_per_line_, grey);
      } else {
        yuyv_to_grey(data, bytes_per_line_, grey);
      }
    } else if (!mjpeg_->decode(data, used, grey)) {
      info.error_flag = true;  // a damaged JPEG: dropped and counted as corrupt
      if (decode_failures_++ % 100 == 0)
        spdlog::warn("{}: MJPEG frame of {} bytes not decoded ({} so far): {}", path_, used, decode_failures_,
                     mjpeg_->error());
    }
  }
  if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) fail("VIDIOC_QBUF");
  return true;
}

V4l2Output::V4l2Output(const std::string& path, int width, int height, Mode mode, PixelFormat format)
    : path_(path), width_(width), height_(height), mode_(mode), format_(format) {
  if (format != PixelFormat::kGrey && format != PixelFormat::kMjpeg)
    throw V4l2Error(path, "output: expected grey or mjpeg", true);
  const uint32_t pix = fourcc(format);
  const std::string pix_name = fourcc_to_string(pix);
  fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw V4l2Error(path_, "cannot open for output: " + errno_text(errno), false, errno);
  auto fail_out = [&](const std::string& what, bool configuration) {
    const int e = errno;
    release();
    throw V4l2Error(path_, what + ": " + errno_text(e), configuration, e);
  };
  v4l2_capability cap{};
  if (::ioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) fail_out("VIDIOC_QUERYCAP (expected a V4L2 output device)", true);
  const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_OUTPUT)) {
    errno = EINVAL;
    fail_out("is not a video output device (expected v4l2loopback or another V4L2_CAP_VIDEO_OUTPUT device)", true);
  }
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  f.fmt.pix.width = static_cast<uint32_t>(width);
  f.fmt.pix.height = static_cast<uint32_t>(height);
  f.fmt.pix.pixelformat = pix;
  f.fmt.pix.field = V4L2_FIELD_NONE;
  f.fmt.pix.bytesperline = format == PixelFormat::kGrey ? static_cast<uint32_t>(width) : 0;
  f.fmt.pix.sizeimage = static_cast<uint32_t>(width * height);  // MJPEG: the largest JPEG accepted
  if (::ioctl(fd_, VIDIOC_S_FMT, &f) < 0)
    fail_out("VIDIOC_S_FMT " + pix_name + " " + std::to_string(width) + "x" + std::to_string(height), true);
  if (f.fmt.pix.pixelformat != pix || static_cast<int>(f.fmt.pix.width) != width ||
      static_cast<int>(f.fmt.pix.height) != height) {
    errno = EINVAL;
    fail_out("refused " + pix_name + " " + std::to_string(width) + "x" + std::to_string(height) + " (got " +
                 fourcc_to_string(f.fmt.pix.pixelformat) + " " + std::to_string(f.fmt.pix.width) + "x" +
                 std::to_string(f.fmt.pix.height) + ")",
             true);
  }
  if (mode_ == Mode::kQueue) {
    v4l2_requestbuffers req{};
    req.count = 4;
    req.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    req.memory = V4L2_MEMORY_MMAP;
    if (::ioctl(fd_, VIDIOC_REQBUFS, &req) < 0 || req.count < 1) fail_out("VIDIOC_REQBUFS (output, mmap)", false);
    for (uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (::ioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) fail_out("VIDIOC_QUERYBUF (output)", false);
      void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (p == MAP_FAILED) fail_out("mmap of output buffer " + std::to_string(i), false);
      buffers_.push_back({p, b.length});
      if (b.length < static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
        errno = EINVAL;
        fail_out("output buffer of " + std::to_string(b.length) + " bytes is smaller than a frame", false);
      }
    }
  }
}

void V4l2Output::release() noexcept {
  for (auto& b : buffers_) ::munmap(b.start, b.length);
  buffers_.clear();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

V4l2Output::~V4l2Output() { release(); }

void V4l2Output::announce() {
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  if (::ioctl(fd_, VIDIOC_STREAMON, &type) < 0)
    throw V4l2Error(path_, "VIDIOC_STREAMON (output) failed: " + errno_text(errno), false, errno);
}

void V4l2Output::write(const cv::Mat& grey, int64_t t_ns) {
  if (format_ != PixelFormat::kGrey || grey.type() != CV_8UC1 || grey.cols != width_ || grey.rows != height_ ||
      !grey.isContinuous())
    throw V4l2Error(path_, "write: expected a continuous CV_8UC1 image of " + std::to_string(width_) + "x" +
                               std::to_string(height_) + " for a GREY output");
  write_bytes(grey.data, grey.total(), t_ns);
}

void V4l2Output::write_bytes(const uint8_t* data, std::size_t n, int64_t t_ns) {
  if (mode_ == Mode::kQueue) {
    // v4l2loopback hands a queued output buffer to its readers at once and never blocks the writer: the buffers
    // are used round robin without VIDIOC_DQBUF.
    const Buffer& buf = buffers_[next_];
    if (n > buf.length)
      throw V4l2Error(path_, "frame of " + std::to_string(n) + " bytes does not fit a " + std::to_string(buf.length) +
                                 "-byte buffer");
    std::memcpy(buf.start, data, n);
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = static_cast<uint32_t>(next_);
    b.bytesused = static_cast<uint32_t>(n);
    b.field = V4L2_FIELD_NONE;
    b.timestamp.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
    b.timestamp.tv_usec = static_cast<suseconds_t>((t_ns % 1000000000LL) / 1000);
    if (::ioctl(fd_, VIDIOC_QBUF, &b) < 0)
      throw V4l2Error(path_, "VIDIOC_QBUF (output) failed: " + errno_text(errno), false, errno);
    next_ = (next_ + 1) % buffers_.size();
    return;
  }
  const ssize_t w = ::write(fd_, data, n);
  if (w < 0) throw V4l2Error(path_, "write failed: " + errno_text(errno), false, errno);
  if (static_cast<std::size_t>(w) != n)
    throw V4l2Error(path_, "short write: " + std::to_string(w) + " of " + std::to_string(n) + " bytes");
}

}  // namespace agvslam::drivers::v4l2
