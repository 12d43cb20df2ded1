#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "agvslam/core/error.h"
#include "agvslam/drivers/v4l2/camera_config.h"
#include "common/test_data.h"

namespace v4l2 = agvslam::drivers::v4l2;

namespace {
std::string field_of_error(const v4l2::V4l2CameraConfig& c) {
  try {
    c.validate("test");
  } catch (const agvslam::InputError& e) {
    return e.where();
  }
  return "";
}
}  // namespace

TEST(V4l2CameraConfig, DefaultsAreValidAndDescribed) {
  v4l2::V4l2CameraConfig c;
  EXPECT_NO_THROW(c.validate("defaults"));
  EXPECT_NE(c.describe().find("left_device=/dev/video0"), std::string::npos) << c.describe();
  EXPECT_EQ(c.devices().size(), 2u);
  c.side_by_side = true;
  EXPECT_EQ(c.devices().size(), 1u);
  EXPECT_EQ(c.device_width(), 2 * c.width);
  EXPECT_NE(c.describe().find("side_by_side=true"), std::string::npos) << c.describe();
}

TEST(V4l2CameraConfig, ValidateNamesTheField) {
  v4l2::V4l2CameraConfig c;
  c.right_device = c.left_device;
  EXPECT_EQ(field_of_error(c), "camera.right_device");
  c = {};
  c.pair_tolerance_ms = 30;  // >= half of 50 ms at 20 fps
  EXPECT_EQ(field_of_error(c), "camera.pair_tolerance_ms");
  c = {};
  c.buffers = 1;
  EXPECT_EQ(field_of_error(c), "camera.buffers");
  c = {};
  c.pixel_format = v4l2::PixelFormat::kYuyv;
  c.width = 751;
  EXPECT_EQ(field_of_error(c), "camera.width");
  c = {};
  c.reopen_backoff_max_ms = 10;
  EXPECT_EQ(field_of_error(c), "camera.reopen_backoff_max_ms");
}

TEST(V4l2CameraConfig, LoadsYamlAndRejectsTypos) {
  const std::string dir = agvslam::test::make_temp_dir("v4l2cfg");
  const std::string good = dir + "/good.yaml", bad = dir + "/bad.yaml", fmt = dir + "/fmt.yaml";
  std::ofstream(good) << "camera:\n  left_device: /dev/v4l/by-id/cam\n  side_by_side: true\n  width: 640\n"
                         "  height: 400\n  pixel_format: mjpeg\n  fps: 30\n  pair_tolerance_ms: 2\n";
  std::ofstream(bad) << "camera:\n  left_devise: /dev/video3\n";
  std::ofstream(fmt) << "camera:\n  pixel_format: rgb24\n";
  const auto c = v4l2::load_v4l2_camera_config(good);
  EXPECT_EQ(c.left_device, "/dev/v4l/by-id/cam");
  EXPECT_TRUE(c.side_by_side);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.pixel_format, v4l2::PixelFormat::kMjpeg);
  EXPECT_DOUBLE_EQ(c.fps, 30.0);
  try {
    v4l2::load_v4l2_camera_config(bad);
    FAIL() << "a misspelt key must be an error";
  } catch (const agvslam::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("left_devise"), std::string::npos) << e.what();
  }
  try {
    v4l2::load_v4l2_camera_config(fmt);
    FAIL() << "an unknown pixel format must be an error";
  } catch (const agvslam::InputError& e) {
    EXPECT_EQ(e.where(), "camera.pixel_format");
  }
  EXPECT_EQ(v4l2::fourcc_to_string(v4l2::fourcc(v4l2::PixelFormat::kYuyv)), "YUYV");
  std::filesystem::remove_all(dir);
}

TEST(V4l2CameraConfig, ShippedExampleLoads) {
  const auto c = v4l2::load_v4l2_camera_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/camera_v4l2.yaml");
  EXPECT_NO_THROW(c.validate("params/camera_v4l2.yaml"));
}
