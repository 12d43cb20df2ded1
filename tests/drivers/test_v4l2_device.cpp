// Device errors that can be produced on a host without V4L2 (this build machine's kernel has none). Streaming
// from real devices, loss and reopen are tested in the VM (tests/vm/cases/v4l2_*.sh).
#include <gtest/gtest.h>

#include <cerrno>

#include "agvslam/core/error.h"
#include "agvslam/drivers/v4l2/device.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"

namespace v4l2 = agvslam::drivers::v4l2;

TEST(V4l2Device, NotAV4l2DeviceIsAConfigurationError) {
  v4l2::CaptureRequest r;
  r.width = 752;
  r.height = 480;
  try {
    v4l2::V4l2Device d("/dev/null", r);
    FAIL() << "/dev/null opened as a camera";
  } catch (const v4l2::V4l2Error& e) {
    EXPECT_TRUE(e.configuration());
    EXPECT_EQ(e.device(), "/dev/null");
    EXPECT_NE(std::string(e.what()).find("is not a V4L2 device"), std::string::npos) << e.what();
  }
}

TEST(V4l2Device, MissingNodeIsTransient) {
  v4l2::CaptureRequest r;
  r.width = 752;
  r.height = 480;
  try {
    v4l2::V4l2Device d("/dev/agvslam-no-such-camera", r);
    FAIL();
  } catch (const v4l2::V4l2Error& e) {
    EXPECT_FALSE(e.configuration());
    EXPECT_EQ(e.errno_value(), ENOENT);
    EXPECT_NE(std::string(e.what()).find("/dev/agvslam-no-such-camera"), std::string::npos);
  }
}

TEST(StereoCamera, KeepsRetryingAnAbsentCameraWithoutBlocking) {
  v4l2::V4l2CameraConfig c;
  c.left_device = "/dev/agvslam-no-such-left";
  c.right_device = "/dev/agvslam-no-such-right";
  c.reopen_backoff_initial_ms = 5;
  c.reopen_backoff_max_ms = 20;
  v4l2::StereoCamera cam(c);
  EXPECT_THROW(cam.open(true), v4l2::V4l2Error);
  cam.open(false);
  EXPECT_EQ(cam.stats().state, v4l2::CaptureStats::State::kReopening);
  agvslam::StereoFrame f;
  for (int i = 0; i < 5; ++i) EXPECT_EQ(cam.grab(f, 30), v4l2::StereoCamera::Grab::kNoFrame);
  EXPECT_GE(cam.stats().reopen_attempts, 3u);  // 150 ms of grabbing with a 5..20 ms back-off
  EXPECT_NE(cam.stats().last_error.find("/dev/agvslam-no-such-left"), std::string::npos);
  EXPECT_NE(cam.stats_line().find("reopening"), std::string::npos);
  EXPECT_EQ(cam.stats().frames, 0u);
}

TEST(StereoCamera, RejectsAnInvalidConfiguration) {
  v4l2::V4l2CameraConfig c;
  c.buffers = 0;
  EXPECT_THROW({ v4l2::StereoCamera cam(c); }, agvslam::InputError);
}
