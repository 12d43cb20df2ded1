#pragma once
// Configuration of the V4L2 stereo camera (drivers/v4l2): which device(s), what size and pixel format the camera
// is asked for, how left and right images are paired, and how a lost device is reopened.
//
// Two layouts:
//   two devices  (left_device + right_device): each delivers one eye; pairs are formed from the V4L2 buffer time
//                stamps (CLOCK_MONOTONIC) when they differ by at most pair_tolerance_ms.
//   side by side (side_by_side: true, left_device only): one device delivers both eyes in one image of
//                (2 * width) x height, left eye in the left half (ZED, ELP and most USB stereo modules).
// width and height are always the size of ONE eye's image.

#include <cstdint>
#include <string>
#include <vector>

#include "agvslam/core/param_table.h"

namespace agvslam::drivers::v4l2 {

// What the camera is asked to send. Every format ends up as 8-bit grey (CV_8UC1):
//   grey   native V4L2_PIX_FMT_GREY, copied as is
//   yuyv   native V4L2_PIX_FMT_YUYV, the luma bytes taken (exact, no colour conversion)
//   mjpeg  native V4L2_PIX_FMT_MJPEG, decoded by libv4lconvert (libv4l2's conversion library) to YUV 4:2:0,
//          whose Y plane is the grey image
enum class PixelFormat { kGrey, kYuyv, kMjpeg };
const char* to_string(PixelFormat f);
bool parse_pixel_format(const std::string& s, PixelFormat& out);
uint32_t fourcc(PixelFormat f);                 // V4L2_PIX_FMT_*
std::string fourcc_to_string(uint32_t fourcc);  // "GREY", "YUYV", ...

struct V4l2CameraConfig {
  std::string left_device = "/dev/video0";
  std::string right_device = "/dev/video1";  // ignored (may be empty) when side_by_side
  bool side_by_side = false;
  int width = 752;   // px, one eye
  int height = 480;  // px
  PixelFormat pixel_format = PixelFormat::kGrey;
  double fps = 20.0;  // requested frame rate (VIDIOC_S_PARM); 0 = leave the device's own rate
  int buffers = 4;    // mmap buffers per device (2..32)
  // Two devices: largest |t_left - t_right| accepted as one pair. Hardware-triggered cameras stamp both eyes
  // within ~1 ms; free-running ones up to half a frame period apart. Must stay below half the frame period, or
  // a frame could pair with its neighbour's partner.
  double pair_tolerance_ms = 10.0;
  int max_pending = 4;  // frames one side may be ahead of the other before the oldest is dropped as unpaired
  // A device that delivers nothing for this long (while streaming) counts as lost and is reopened.
  int stall_timeout_ms = 2000;
  // Reopen back-off: the first retry after this delay, doubling up to the maximum.
  int reopen_backoff_initial_ms = 100;
  int reopen_backoff_max_ms = 2000;

  // Throws InputError(source, "camera.<field>", "expected ...") for an invalid value.
  void validate(const std::string& source) const;
  std::string describe() const;              // one line for start-up logs
  std::vector<std::string> devices() const;  // the device paths in use (one or two)
  int device_width() const { return side_by_side ? 2 * width : width; }
};

// The settings of section `camera` (the daemon's file and params/camera_v4l2.yaml): keys named like the fields
// above, pixel_format as grey|yuyv|mjpeg.
const params::Table<V4l2CameraConfig>& camera_params();

// Reads section `section` (default "camera") of a params YAML file; a missing section, an unknown key or a bad value
// is an InputError naming "section.key". Other sections of the file are not looked at.
V4l2CameraConfig load_v4l2_camera_config(const std::string& path, const std::string& section = "camera");

}  // namespace agvslam::drivers::v4l2
