#include "agvslam/drivers/v4l2/camera_config.h"

#include <linux/videodev2.h>

#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::drivers::v4l2 {

const char* to_string(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey: return "grey";
    case PixelFormat::kYuyv: return "yuyv";
    case PixelFormat::kMjpeg: return "mjpeg";
  }
  return "?";
}

bool parse_pixel_format(const std::string& s, PixelFormat& out) {
  if (s == "grey" || s == "GREY" || s == "gray") {
    out = PixelFormat::kGrey;
  } else if (s == "yuyv" || s == "YUYV") {
    out = PixelFormat::kYuyv;
  } else if (s == "mjpeg" || s == "MJPG" || s == "mjpg") {
    out = PixelFormat::kMjpeg;
  } else {
    return false;
  }
  return true;
}

uint32_t fourcc(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey: return V4L2_PIX_FMT_GREY;
    case PixelFormat::kYuyv: return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kMjpeg: return V4L2_PIX_FMT_MJPEG;
  }
  return 0;
}

std::string fourcc_to_string(uint32_t f) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((f >> (8 * i)) & 0xff);
    s[static_cast<std::size_t>(i)] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

void V4l2CameraConfig::validate(const std::string& source) const {
  auto bad = [&](const char* key, const std::string& expected) { throw InputError(source, std::string("camera.") + key, expected); };
  if (left_device.empty()) bad("left_device", "expected a device path such as /dev/video0");
  if (!side_by_side) {
    if (right_device.empty()) bad("right_device", "expected a device path (or side_by_side: true)");
    if (right_device == left_device) bad("right_device", "expected a device other than left_device (or side_by_side: true)");
  }
  if (width <= 0 || width > 8192) bad("width", "expected 1..8192 px (one eye)");
  if (height <= 0 || height > 8192) bad("height", "expected 1..8192 px");
  if (pixel_format == PixelFormat::kYuyv && (width % 2) != 0) bad("width", "expected an even width for yuyv");
  if (!(fps >= 0 && fps <= 1000)) bad("fps", "expected 0 (device default) .. 1000 frames/s");
  if (buffers < 2 || buffers > 32) bad("buffers", "expected 2..32");
  if (!(pair_tolerance_ms >= 0)) bad("pair_tolerance_ms", "expected >= 0 ms");
  if (fps > 0 && pair_tolerance_ms >= 500.0 / fps)
    bad("pair_tolerance_ms", "expected less than half the frame period (" + std::to_string(500.0 / fps) + " ms at " +
                                 std::to_string(fps) + " frames/s)");
  if (max_pending < 1 || max_pending > 64) bad("max_pending", "expected 1..64 frames");
  if (stall_timeout_ms < 100) bad("stall_timeout_ms", "expected >= 100 ms");
  if (reopen_backoff_initial_ms < 1) bad("reopen_backoff_initial_ms", "expected >= 1 ms");
  if (reopen_backoff_max_ms < reopen_backoff_initial_ms)
    bad("reopen_backoff_max_ms", "expected >= reopen_backoff_initial_ms");
}

std::vector<std::string> V4l2CameraConfig::devices() const {
  if (side_by_side) return {left_device};
  return {left_device, right_device};
}

std::string V4l2CameraConfig::describe() const {
  std::ostringstream s;
  s << "camera: ";
  if (side_by_side) {
    s << "side-by-side " << left_device << " " << 2 * width << "x" << height << " -> 2 x " << width << "x" << height;
  } else {
    s << "left " << left_device << " right " << right_device << " " << width << "x" << height << ", pair within "
      << pair_tolerance_ms << " ms, max_pending " << max_pending;
  }
  s << ", " << to_string(pixel_format) << ", " << fps << " fps requested, " << buffers << " buffers, stall after "
    << stall_timeout_ms << " ms, reopen back-off " << reopen_backoff_initial_ms << ".." << reopen_backoff_max_ms
    << " ms";
  return s.str();
}

V4l2CameraConfig load_v4l2_camera_config(const std::string& path, const std::string& section) {
  const stereo::ParamsReader in(path);
  V4l2CameraConfig c;
  if (!in.has_section(section)) throw InputError(path, section, "expected a '" + section + ":' section");
  in.check_keys(section, {"left_device", "right_device", "side_by_side", "width", "height", "pixel_format", "fps",
                          "buffers", "pair_tolerance_ms", "max_pending", "stall_timeout_ms",
                          "reopen_backoff_initial_ms", "reopen_backoff_max_ms"});
  in.read(section, "left_device", c.left_device, "a device path");
  in.read(section, "right_device", c.right_device, "a device path");
  in.read(section, "side_by_side", c.side_by_side, "true or false");
  in.read(section, "width", c.width, "an integer (px, one eye)");
  in.read(section, "height", c.height, "an integer (px)");
  std::string pf = to_string(c.pixel_format);
  in.read(section, "pixel_format", pf, "one of grey, yuyv, mjpeg");
  if (!parse_pixel_format(pf, c.pixel_format))
    throw InputError(path, section + ".pixel_format", "expected one of grey, yuyv, mjpeg, found '" + pf + "'");
  in.read(section, "fps", c.fps, "a number (frames/s, 0 = device default)");
  in.read(section, "buffers", c.buffers, "an integer");
  in.read(section, "pair_tolerance_ms", c.pair_tolerance_ms, "a number (ms)");
  in.read(section, "max_pending", c.max_pending, "an integer (frames)");
  in.read(section, "stall_timeout_ms", c.stall_timeout_ms, "an integer (ms)");
  in.read(section, "reopen_backoff_initial_ms", c.reopen_backoff_initial_ms, "an integer (ms)");
  in.read(section, "reopen_backoff_max_ms", c.reopen_backoff_max_ms, "an integer (ms)");
  c.validate(path);
  return c;
}

}  // namespace agvslam::drivers::v4l2
