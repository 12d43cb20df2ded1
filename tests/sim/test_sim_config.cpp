// Settings of the simulator (params/sim.yaml) and its scenario catalogue / option checks.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "agvslam/core/error.h"
#include "agvslam/sim/scenario.h"
#include "agvslam/sim/sim_config.h"
#include "common/test_data.h"

namespace agvslam::sim {
namespace {

std::string write_temp_yaml(const std::string& name, const std::string& text) {
  const std::string dir = test::make_temp_dir("agvslam-sim-config");
  const std::string path = (std::filesystem::path(dir) / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(SimConfig, DefaultsDescribeTheSpecifiedCamera) {
  const SimConfig c;
  EXPECT_NO_THROW(c.validate("defaults"));
  const StereoCalibration calib = c.calibration();
  EXPECT_EQ(calib.left.width, 752);
  EXPECT_EQ(calib.left.height, 480);
  EXPECT_DOUBLE_EQ(calib.left.fx, 460.0);
  EXPECT_DOUBLE_EQ(calib.left.fy, 460.0);
  EXPECT_DOUBLE_EQ(calib.left.cx, 375.5);
  EXPECT_DOUBLE_EQ(calib.left.cy, 239.5);
  EXPECT_DOUBLE_EQ(calib.baseline_m, 0.12);
  EXPECT_DOUBLE_EQ(c.camera_height_m, 0.5);
  EXPECT_DOUBLE_EQ(c.rate_hz, 20.0);
  EXPECT_EQ(c.describe().size(), 4u);
}

TEST(SimConfig, ShippedParamsFileLoadsToTheDefaults) {
  const std::string path = std::string(AGVSLAM_SOURCE_DIR) + "/params/sim.yaml";
  const SimConfig c = load_sim_config(path);
  const SimConfig d;
  EXPECT_EQ(c.width, d.width);
  EXPECT_EQ(c.height, d.height);
  EXPECT_DOUBLE_EQ(c.fx, d.fx);
  EXPECT_DOUBLE_EQ(c.fy_px(), d.fy_px());
  EXPECT_DOUBLE_EQ(c.cx_px(), d.cx_px());
  EXPECT_DOUBLE_EQ(c.baseline_m, d.baseline_m);
  EXPECT_DOUBLE_EQ(c.camera_height_m, d.camera_height_m);
  EXPECT_DOUBLE_EQ(c.noise_sigma_dn, d.noise_sigma_dn);
  EXPECT_DOUBLE_EQ(c.exposure_variation, d.exposure_variation);
  EXPECT_EQ(c.antialias_edges, d.antialias_edges);
}

TEST(SimConfig, PartialFileOverridesOnlyItsKeys) {
  const std::string path =
      write_temp_yaml("sim.yaml", "camera:\n  width: 376\n  fx: 230\nsensor:\n  noise_sigma_dn: 0\n");
  const SimConfig c = load_sim_config(path);
  EXPECT_EQ(c.width, 376);
  EXPECT_EQ(c.height, 480);
  EXPECT_DOUBLE_EQ(c.fx, 230.0);
  EXPECT_DOUBLE_EQ(c.cx_px(), 187.5);
  EXPECT_DOUBLE_EQ(c.noise_sigma_dn, 0.0);
  EXPECT_DOUBLE_EQ(c.baseline_m, 0.12);
}

TEST(SimConfig, BadFilesNameTheFileAndTheKey) {
  {
    const std::string path = write_temp_yaml("unknown.yaml", "camera:\n  focal: 400\n");
    try {
      load_sim_config(path);
      FAIL() << "an unknown key must be rejected";
    } catch (const InputError& e) {
      EXPECT_EQ(e.source(), path);
      EXPECT_EQ(e.where(), "camera.focal");
      EXPECT_NE(e.expected().find("fx"), std::string::npos) << e.what();
    }
  }
  {
    const std::string path = write_temp_yaml("type.yaml", "camera:\n  width: wide\n");
    try {
      load_sim_config(path);
      FAIL() << "a non-integer width must be rejected";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "camera.width");
    }
  }
  {
    const std::string path = write_temp_yaml("range.yaml", "camera:\n  baseline_m: -0.1\n");
    try {
      load_sim_config(path);
      FAIL() << "a negative baseline must be rejected";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "camera.baseline_m");
    }
  }
  EXPECT_THROW(load_sim_config("/nonexistent/agvslam/sim.yaml"), InputError);
}

TEST(SimConfig, ScaledKeepsTheFieldOfView) {
  const SimConfig c = SimConfig{}.scaled(0.5);
  EXPECT_EQ(c.width, 376);
  EXPECT_EQ(c.height, 240);
  EXPECT_DOUBLE_EQ(c.fx, 230.0);
  EXPECT_DOUBLE_EQ(c.cx_px(), 187.5);
  EXPECT_NEAR(c.width / c.fx, 752 / 460.0, 1e-12);
}

TEST(ScenarioCatalogue, ListsTheScenariosWithRealisticDefaults) {
  const auto& cat = scenario_catalogue();
  const char* names[] = {"static", "scene1", "scene2", "scene3", "scene4",  "scene5",
                         "scene6", "follow", "crowd",  "pallet", "oncoming"};
  ASSERT_EQ(cat.size(), std::size(names));
  for (std::size_t i = 0; i < cat.size(); ++i) {
    EXPECT_EQ(cat[i].name, names[i]);
    // 20-60 s: long enough for what happens, short enough to render a few seeds.
    EXPECT_GE(cat[i].nominal_duration_s, 20.0) << names[i];
    EXPECT_LE(cat[i].nominal_duration_s, 60.0) << names[i];
  }
}

TEST(ScenarioOptions, RejectBadValuesNamingTheOption) {
  try {
    find_scenario("scene9");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--scenario");
    EXPECT_NE(std::string(e.what()).find("scene5"), std::string::npos) << e.what();
  }
  const WarehouseLayout layout;
  ScenarioOptions o;
  o.name = "scene2";
  o.frames = -3;
  try {
    o.validate(layout);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--frames");
  }
  o.frames = 0;
  o.squeeze_to_frames = -1;
  try {
    o.validate(layout);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--squeeze-to");
  }
  o.squeeze_to_frames = 0;
  o.start_offset_m = 7.0;  // beyond the aisle
  try {
    o.validate(layout);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--start-offset");
  }
  o.name = "scene4";  // the loop wraps: any offset is fine
  EXPECT_NO_THROW(o.validate(layout));
}

}  // namespace
}  // namespace agvslam::sim
