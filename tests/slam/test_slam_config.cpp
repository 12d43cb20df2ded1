// params/slam.yaml loading: defaults, the shipped file, unknown keys and out-of-range values.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "agvslam/core/error.h"
#include "agvslam/slam/slam_config.h"
#include "common/test_data.h"

namespace agvslam::slam {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string dir = agvslam::test::make_temp_dir("slam_config");
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(SlamConfig, ShippedFileEqualsTheDefaults) {
  const SlamConfig c = load_slam_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/slam.yaml");
  const SlamConfig d;
  EXPECT_EQ(c.describe(), d.describe());
  EXPECT_DOUBLE_EQ(c.tracking.close_depth_baselines, 40.0);
  EXPECT_EQ(c.mapping.queue_capacity, 3);
  EXPECT_EQ(c.optimizer.motion_rounds, 4);
}

TEST(SlamConfig, ValuesOverrideDefaults) {
  const SlamConfig c =
      load_slam_config(write_temp("a.yaml", "tracking:\n  min_init_features: 300\nmapping:\n  max_keyframes: 50\n"));
  EXPECT_EQ(c.tracking.min_init_features, 300);
  EXPECT_EQ(c.mapping.max_keyframes, 50);
  EXPECT_EQ(c.optimizer.motion_iterations, 10);
}

TEST(SlamConfig, UnknownKeyNamesTheField) {
  try {
    load_slam_config(write_temp("b.yaml", "tracking:\n  min_init_featurs: 300\n"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("min_init_featurs"), std::string::npos) << e.what();
  }
}

TEST(SlamConfig, OutOfRangeNamesTheFieldAndTheRange) {
  try {
    load_slam_config(write_temp("c.yaml", "optimizer:\n  motion_robust_rounds: 7\n"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "optimizer.motion_robust_rounds");
    EXPECT_NE(std::string(e.what()).find("expected at most motion_rounds, got 7"), std::string::npos) << e.what();
  }
  try {
    load_slam_config(write_temp("e.yaml", "mapping:\n  max_keyframes: 5\n"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "mapping.max_keyframes");
    EXPECT_NE(std::string(e.what()).find("expected an integer >= 10 or 0 (0: no cap), got 5"), std::string::npos)
        << e.what();
  }
  try {
    load_slam_config(write_temp("d.yaml", "mapping:\n  keyframe_redundancy: two\n"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "mapping.keyframe_redundancy");
  }
  EXPECT_THROW(load_slam_config("/nonexistent/slam.yaml"), InputError);
}

}  // namespace
}  // namespace agvslam::slam
