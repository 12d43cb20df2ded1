// params/features.yaml loading: defaults, overrides, and errors that name the file and the field.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/features/features_config.h"
#include "common/config_test.h"

namespace agvslam::features {
namespace {
using test::TempYaml;

void expect_error(const std::string& text, const std::string& field) {
  test::expect_input_error([](const std::string& path) { load_features_config(path); }, text, field);
}

TEST(FeaturesConfig, ShippedParamsFileLoadsAndMatchesTheDefaults) {
  const FeaturesConfig c = load_features_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/features.yaml");
  const FeaturesConfig d;
  EXPECT_EQ(c.orb.n_features, d.orb.n_features);
  EXPECT_DOUBLE_EQ(c.orb.scale_factor, d.orb.scale_factor);
  EXPECT_EQ(c.orb.n_levels, d.orb.n_levels);
  EXPECT_EQ(c.orb.ini_fast_threshold, d.orb.ini_fast_threshold);
  EXPECT_EQ(c.orb.min_fast_threshold, d.orb.min_fast_threshold);
  EXPECT_EQ(c.orb.mask_dilation_px, d.orb.mask_dilation_px);
  EXPECT_EQ(c.orb.cell_size_px, d.orb.cell_size_px);
  EXPECT_EQ(c.orb.level_allocation, d.orb.level_allocation);
  EXPECT_EQ(c.stereo_matching.method, d.stereo_matching.method);
  EXPECT_DOUBLE_EQ(c.stereo_matching.min_depth_m, d.stereo_matching.min_depth_m);
  EXPECT_DOUBLE_EQ(c.stereo_matching.max_depth_m, d.stereo_matching.max_depth_m);
  EXPECT_EQ(c.stereo_matching.sad_half_window, d.stereo_matching.sad_half_window);
  EXPECT_EQ(c.stereo_matching.sad_search_px, d.stereo_matching.sad_search_px);
  EXPECT_EQ(c.stereo_matching.max_descriptor_distance, d.stereo_matching.max_descriptor_distance);
  EXPECT_DOUBLE_EQ(c.stereo_matching.uniqueness_ratio, d.stereo_matching.uniqueness_ratio);
  EXPECT_DOUBLE_EQ(c.stereo_matching.min_curvature, d.stereo_matching.min_curvature);
  EXPECT_DOUBLE_EQ(c.stereo_matching.outlier_factor, d.stereo_matching.outlier_factor);
  const auto lines = c.describe();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("n_features=1200 per image"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("388 269"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("block_matching"), std::string::npos) << lines[1];
}

TEST(FeaturesConfig, OverridesKeepTheOtherDefaults) {
  TempYaml f(
      "orb:\n  n_features: 2000\n  level_allocation: side\nstereo_matching:\n  method: descriptor\n"
      "  max_depth_m: 20\n");
  const FeaturesConfig c = load_features_config(f.path());
  EXPECT_EQ(c.orb.n_features, 2000);
  EXPECT_EQ(c.orb.level_allocation, LevelAllocation::kSide);
  EXPECT_EQ(c.orb.n_levels, 8);
  EXPECT_EQ(c.stereo_matching.method, StereoMethod::kDescriptor);
  EXPECT_DOUBLE_EQ(c.stereo_matching.max_depth_m, 20.0);
  EXPECT_DOUBLE_EQ(c.stereo_matching.min_depth_m, 0.3);
}

TEST(FeaturesConfig, ErrorsNameTheFileAndTheField) {
  expect_error("orb:\n  n_featurs: 1000\n", "orb.n_featurs");    // typo
  expect_error("orbs:\n  n_features: 1000\n", "orbs");           // unknown section
  expect_error("orb:\n  n_features: many\n", "orb.n_features");  // wrong type
  expect_error("orb:\n  n_features: 0\n", "orb.n_features");     // out of range
  expect_error("orb:\n  scale_factor: 1.0\n", "orb.scale_factor");
  expect_error("orb:\n  n_levels: 0\n", "orb.n_levels");
  expect_error("orb:\n  min_fast_threshold: 30\n", "orb.min_fast_threshold");  // above ini_fast_threshold
  expect_error("orb:\n  mask_dilation_px: -1\n", "orb.mask_dilation_px");
  expect_error("orb:\n  cell_size_px: 2\n", "orb.cell_size_px");
  expect_error("orb:\n  level_allocation: volume\n", "orb.level_allocation");
  expect_error("stereo_matching:\n  method: sgbm\n", "stereo_matching.method");
  expect_error("stereo_matching:\n  min_depth_m: 0\n", "stereo_matching.min_depth_m");
  expect_error("stereo_matching:\n  max_depth_m: 0.2\n", "stereo_matching.max_depth_m");  // below min_depth_m
  expect_error("stereo_matching:\n  sad_half_window: 9\n", "stereo_matching.sad_half_window");
  expect_error("stereo_matching:\n  uniqueness_ratio: 1.5\n", "stereo_matching.uniqueness_ratio");
  expect_error("stereo_matching:\n  outlier_factor: 0.5\n", "stereo_matching.outlier_factor");
  expect_error("stereo_matching:\n  min_curvature: -1\n", "stereo_matching.min_curvature");
  expect_error("stereo_matching:\n  max_descriptor_distance: 300\n", "stereo_matching.max_descriptor_distance");
  expect_error("stereo_matching:\n  sad_search: 5\n", "stereo_matching.sad_search");
}

TEST(FeaturesConfig, MissingFileIsAnInputError) {
  EXPECT_THROW(load_features_config("/nonexistent/features.yaml"), InputError);
}

}  // namespace
}  // namespace agvslam::features
