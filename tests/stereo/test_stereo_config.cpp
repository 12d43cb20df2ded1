// params/stereo.yaml loading: defaults, overrides, and errors that name the file and the field.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/stereo/stereo_config.h"
#include "common/config_test.h"

namespace agvslam::stereo {
namespace {
using test::TempYaml;

void expect_error(const std::string& text, const std::string& field) {
  test::expect_input_error([](const std::string& path) { load_stereo_config(path); }, text, field);
}

TEST(StereoConfig, ShippedParamsFileLoadsAndMatchesTheDefaults) {
  const StereoConfig c = load_stereo_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/stereo.yaml");
  const StereoConfig d;
  EXPECT_EQ(c.sgbm.num_disparities, d.sgbm.num_disparities);
  EXPECT_EQ(c.sgbm.block_size, d.sgbm.block_size);
  EXPECT_EQ(c.sgbm.mode, d.sgbm.mode);
  EXPECT_EQ(c.sgbm.roi_margin_px, d.sgbm.roi_margin_px);
  EXPECT_EQ(c.sparse.half_window, d.sparse.half_window);
  EXPECT_DOUBLE_EQ(c.sparse.max_mean_cost, d.sparse.max_mean_cost);
  EXPECT_EQ(c.sparse.num_disparities, d.sparse.num_disparities);
  const auto lines = c.describe();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("sgbm_3way"), std::string::npos);
  EXPECT_NE(lines[1].find("9x9"), std::string::npos);
}

TEST(StereoConfig, OverridesOnlyTheGivenKeys) {
  TempYaml f("sgbm:\n  num_disparities: 128\n  mode: hh\nsparse:\n  half_window: 3\n  subpixel: false\n");
  const StereoConfig c = load_stereo_config(f.path());
  EXPECT_EQ(c.sgbm.num_disparities, 128);
  EXPECT_EQ(c.sgbm.mode, SgbmMode::kHh);
  EXPECT_EQ(c.sgbm.block_size, SgbmConfig{}.block_size);
  EXPECT_EQ(c.sparse.half_window, 3);
  EXPECT_FALSE(c.sparse.subpixel);
}

TEST(StereoConfig, BadValuesNameFileAndField) {
  expect_error("sgbm:\n  num_disparities: 60\n", "sgbm.num_disparities");
  expect_error("sgbm:\n  block_size: 4\n", "sgbm.block_size");
  expect_error("sgbm:\n  mode: fancy\n", "sgbm.mode");
  expect_error("sgbm:\n  block_size: five\n", "sgbm.block_size");
  expect_error("sgbm:\n  blocksize: 5\n", "sgbm.blocksize");
  expect_error("sparse:\n  max_mean_cost: -1\n", "sparse.max_mean_cost");
  expect_error("sparse:\n  max_mean_cost: .nan\n", "sparse.max_mean_cost");
  expect_error("stereo:\n  x: 1\n", "stereo");
  expect_error("sgbm: [1, 2\n", "line 2");
}

TEST(StereoConfig, MissingFileIsAnInputError) {
  EXPECT_THROW(load_stereo_config("/nonexistent/stereo.yaml"), InputError);
}

}  // namespace
}  // namespace agvslam::stereo
