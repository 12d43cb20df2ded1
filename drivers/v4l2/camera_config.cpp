#include "agvslam/drivers/v4l2/camera_config.h"

#include <linux/videodev2.h>

namespace agvslam::drivers::v4l2 {

namespace {

using params::Range;

const params::EnumNames<PixelFormat>& pixel_format_names() {
  static const params::EnumNames<PixelFormat> names{{"grey", PixelFormat::kGrey},   {"yuyv", PixelFormat::kYuyv},
                                                    {"mjpeg", PixelFormat::kMjpeg}, {"GREY", PixelFormat::kGrey},
                                                    {"gray", PixelFormat::kGrey},   {"YUYV", PixelFormat::kYuyv},
                                                    {"MJPG", PixelFormat::kMjpeg},  {"mjpg", PixelFormat::kMjpeg}};
  return names;
}

}  // namespace

const params::Table<V4l2CameraConfig>& camera_params() {
  using C = V4l2CameraConfig;
  static const params::Table<C> table =
      params::Table<C>(
          "camera",
          {
              {"left_device", &C::left_device, params::Text::non_empty(), "a device path such as /dev/video0"},
              {"right_device", &C::right_device, params::Text::any(), "ignored when side_by_side"},
              {"side_by_side", &C::side_by_side},
              {"width", &C::width, Range::closed(1, 8192), "px", "one eye"},
              {"height", &C::height, Range::closed(1, 8192), "px"},
              {"pixel_format", &C::pixel_format, pixel_format_names()},
              {"fps", &C::fps, Range::closed(0, 1000), "frames/s", "0: the device's own rate"},
              {"buffers", &C::buffers, Range::closed(2, 32), "per device"},
              {"pair_tolerance_ms", &C::pair_tolerance_ms, Range::at_least(0), "ms"},
              {"max_pending", &C::max_pending, Range::closed(1, 64), "frames"},
              {"stall_timeout_ms", &C::stall_timeout_ms, Range::at_least(100), "ms"},
              {"reopen_backoff_initial_ms", &C::reopen_backoff_initial_ms, Range::at_least(1), "ms"},
              {"reopen_backoff_max_ms", &C::reopen_backoff_max_ms, Range::any(), "ms"},
          })
          .check(
              "right_device", [](const C& c) { return c.side_by_side || !c.right_device.empty(); },
              "a device path (or side_by_side: true)")
          .check(
              "right_device", [](const C& c) { return c.side_by_side || c.right_device != c.left_device; },
              "a device other than left_device (or side_by_side: true)")
          .check(
              "width", [](const C& c) { return c.pixel_format != PixelFormat::kYuyv || c.width % 2 == 0; },
              "an even width for yuyv (two pixels share their chroma)")
          .check(
              "pair_tolerance_ms", [](const C& c) { return !(c.fps > 0) || c.pair_tolerance_ms < 500.0 / c.fps; },
              [](const C& c) {
                return "less than half the frame period (" + std::to_string(500.0 / c.fps) + " ms at " +
                       std::to_string(c.fps) + " frames/s), or a frame could pair with its neighbour's partner";
              })
          .check(
              "reopen_backoff_max_ms",
              [](const C& c) { return c.reopen_backoff_max_ms >= c.reopen_backoff_initial_ms; },
              "at least reopen_backoff_initial_ms");
  return table;
}

const char* to_string(PixelFormat f) { return pixel_format_names().name(f); }

bool parse_pixel_format(const std::string& s, PixelFormat& out) { return pixel_format_names().parse(s, out); }

uint32_t fourcc(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey:
      return V4L2_PIX_FMT_GREY;
    case PixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
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

void V4l2CameraConfig::validate(const std::string& source) const { camera_params().validate(source, *this); }

std::vector<std::string> V4l2CameraConfig::devices() const {
  if (side_by_side) return {left_device};
  return {left_device, right_device};
}

std::string V4l2CameraConfig::describe() const { return camera_params().describe(*this); }

V4l2CameraConfig load_v4l2_camera_config(const std::string& path, const std::string& section) {
  const params::File in(path);
  in.require_section(section);
  V4l2CameraConfig c;
  camera_params().read(in, section, c);
  c.validate(path);
  return c;
}

}  // namespace agvslam::drivers::v4l2
