// params/dynamic.yaml loading: the shipped file, overrides, and errors naming the file and the field.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "common/config_test.h"

namespace agvslam::dynamic {
namespace {
using test::TempYaml;

// expected: the whole "expected ..." text of the error, or "" to check only the file and the field.
void expect_error(const std::string& text, const std::string& field, const std::string& expected = "") {
  test::expect_input_error([](const std::string& path) { load_dynamic_config(path); }, text, field, expected);
}

TEST(DynamicConfig, ShippedParamsFileEqualsTheDefaults) {
  const DynamicDetectorConfig c = load_dynamic_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/dynamic.yaml");
  const DynamicDetectorConfig d;
  // Every stage's description is identical, so every value is (descriptions print all of them).
  EXPECT_EQ(c.describe(), d.describe());
  EXPECT_EQ(c.features.target_count, d.features.target_count);
  EXPECT_EQ(c.slic.incremental, d.slic.incremental);
  EXPECT_EQ(c.regions.mask_mode, d.regions.mask_mode);
  EXPECT_EQ(c.planes.seed, d.planes.seed);
  EXPECT_EQ(c.describe().size(), 22u);
  EXPECT_EQ(c.band.close_px, d.band.close_px);
  EXPECT_EQ(c.motion_carve.block_px, d.motion_carve.block_px);
}

TEST(DynamicConfig, OverridesOnlyTheGivenKeys) {
  TempYaml f(
      "epipolar:\n  a_epi_px: 1.5\n  adaptive: false\nslic:\n  incremental: true\nregions:\n  mask_mode: rectangle\n"
      "roi:\n  scale: 1\nmultiframe:\n  prior_min_inlier_fraction: 0\n");
  const DynamicDetectorConfig c = load_dynamic_config(f.path());
  EXPECT_DOUBLE_EQ(c.epipolar.a_epi_px, 1.5);
  EXPECT_FALSE(c.epipolar.adaptive);
  EXPECT_TRUE(c.slic.incremental);
  EXPECT_EQ(c.regions.mask_mode, MaskMode::kRectangle);
  EXPECT_DOUBLE_EQ(c.roi.scale, 1.0);
  EXPECT_DOUBLE_EQ(c.multiframe.prior_min_inlier_fraction, 0.0);
  EXPECT_EQ(c.features.target_count, QuadtreeFastConfig{}.target_count);
}

TEST(DynamicConfig, BadValuesNameFileAndField) {
  expect_error("epipolar:\n  a_epi_px: -1\n", "epipolar.a_epi_px");
  expect_error("epipolar:\n  a_epi_px: one\n", "epipolar.a_epi_px");
  expect_error("boundaries:\n  lambda_occ: 0.1\n", "boundaries.lambda_occ");  // must exceed lambda_hinge
  expect_error("grouping:\n  min_points: 0\n", "grouping.min_points");
  expect_error("grouping:\n  merge_side_gap_m: -0.1\n", "grouping.merge_side_gap_m");
  expect_error("roi:\n  half_scale_erode_px: 11\n", "roi.half_scale_erode_px");
  expect_error("outline:\n  close_far_m: 3\n", "outline.close_far_m");
  expect_error("multiframe:\n  aperture_ratio: 1\n", "multiframe.aperture_ratio");
  expect_error("outline:\n  left_band_touch_px: -2\n", "outline.left_band_touch_px");
  expect_error("outline:\n  aggregate_ratio: -1\n", "outline.aggregate_ratio");
  expect_error("outline:\n  aggregate_min_px: many\n", "outline.aggregate_min_px");
  expect_error("outline:\n  aggregate_min_tracks: -3\n", "outline.aggregate_min_tracks");
  expect_error("outline:\n  aggregate_multiframe_fraction: 1.5\n", "outline.aggregate_multiframe_fraction");
  expect_error("outline:\n  aggregate_multiframe_min_px: -0.1\n", "outline.aggregate_multiframe_min_px");
  expect_error("objects:\n  coast_max_frames: -1\n", "objects.coast_max_frames");
  expect_error("edge_refine:\n  band_px: 40\n", "edge_refine.band_px");
  expect_error("edge_refine:\n  occlusion_cost: 0\n", "edge_refine.occlusion_cost");
  expect_error("edge_refine:\n  width_px: 3\n", "edge_refine.width_px");  // unknown key
  expect_error("roi:\n  extend_max_rounds: -1\n", "roi.extend_max_rounds");
  expect_error("densify:\n  depth_seed_factor: -1\n", "densify.depth_seed_factor");
  expect_error("roi:\n  row_step: 3\n", "roi.row_step");
  expect_error("confirm:\n  min_box_iou: 1.5\n", "confirm.min_box_iou");
  expect_error("confirm:\n  below_px: -1\n", "confirm.below_px");
  expect_error("confirm:\n  near_min_disparity_px: -2\n", "confirm.near_min_disparity_px");
  expect_error("confirm:\n  near_min_offset_px: fast\n", "confirm.near_min_offset_px");
  expect_error("confirm:\n  near_min_px: -1\n", "confirm.near_min_px");
  expect_error("confirm:\n  near_min_roi_fill: 1.5\n", "confirm.near_min_roi_fill");
  expect_error("objects:\n  growth_max_ratio: 0.5\n", "objects.growth_max_ratio");
  expect_error("objects:\n  growth_margin: -0.1\n", "objects.growth_margin");
  expect_error("static_carve:\n  min_tracks: -1\n", "static_carve.min_tracks");
  expect_error("static_carve:\n  max_offset_px: -0.2\n", "static_carve.max_offset_px");
  expect_error("static_carve:\n  max_multiframe_px: 200\n", "static_carve.max_multiframe_px");
  expect_error("static_carve:\n  min_distance_px: -5\n", "static_carve.min_distance_px");
  expect_error("roi:\n  row_step_min_area_px: -1\n", "roi.row_step_min_area_px");
  expect_error("roi:\n  extend_min_rows: 0\n", "roi.extend_min_rows");
  expect_error("roi:\n  extend_step_m: 0\n", "roi.extend_step_m");
  expect_error("roi:\n  extend_static_guard_px: -1\n", "roi.extend_static_guard_px");
  expect_error("densify:\n  min_seeds: 0\n", "densify.min_seeds");
  expect_error("densify:\n  extra_tracks: -5\n", "densify.extra_tracks");
  expect_error("densify:\n  keep_static: maybe\n", "densify.keep_static");
  expect_error("objects:\n  coast_min_tracks: 0\n", "objects.coast_min_tracks");
  expect_error("objects:\n  coast_min_area_ratio: 1.5\n", "objects.coast_min_area_ratio");
  expect_error("objects:\n  coast_min_detections: 0\n", "objects.coast_min_detections");
  expect_error("photometric:\n  multiframe_min_disparity_px: -2\n", "photometric.multiframe_min_disparity_px");
  expect_error("slic:\n  superpixel_size: 12\n", "slic.superpixel_size");  // unknown key
  expect_error("motion_carve:\n  block_px: 1\n", "motion_carve.block_px");
  expect_error("motion_carve:\n  enabled: sometimes\n", "motion_carve.enabled");
  expect_error("motion_carve:\n  max_static_ratio: 1.5\n", "motion_carve.max_static_ratio");
  expect_error("motion_carve:\n  blocks: 8\n", "motion_carve.blocks");
  expect_error("band:\n  strip_px: 4\n", "band.strip_px");
  expect_error("band:\n  enabled: maybe\n", "band.enabled");
  expect_error("band:\n  max_static_segment_px: 0\n", "band.max_static_segment_px");
  expect_error("band:\n  max_seeds: 1\n", "band.max_seeds");  // below min_seeds (2)
  expect_error("band:\n  evidence_dn: -1\n", "band.evidence_dn");
  expect_error("band:\n  max_object_error_dn: 0\n", "band.max_object_error_dn");
  expect_error("band:\n  close_px: 0\n", "band.close_px");
  expect_error("band:\n  stack_gap_px: -1\n", "band.stack_gap_px");
  expect_error("band:\n  driving_seed_offset_px: -0.5\n", "band.driving_seed_offset_px");
  expect_error("band:\n  width_px: 64\n", "band.width_px");  // unknown key
  // The per-frame depth test takes no motion prior: the key is the multi-frame test's only.
  expect_error("depth_test:\n  prior_min_inlier_fraction: 0.5\n", "depth_test.prior_min_inlier_fraction");
  expect_error("multiframe:\n  prior_min_inlier_fraction: 1.5\n", "multiframe.prior_min_inlier_fraction");
  expect_error("regions:\n  mask_mode: blob\n", "regions.mask_mode");
  expect_error("roi:\n  scale: 0.3\n", "roi.scale");
  expect_error("detector:\n  use_epipolar_test: false\n  use_depth_test: false\n", "detector.use_epipolar_test");
  expect_error("planes:\n  seed: -4\n", "planes.seed");
  // The parts' keys belong to their own sections (objects, densify, ...): under detector they are unknown.
  expect_error("detector:\n  densify: true\n", "detector.densify");
  expect_error("detector:\n  coast_max_frames: 4\n", "detector.coast_max_frames");
  expect_error("objects:\n  track_objects: true\n", "objects.track_objects");
  expect_error("features: 3\n", "features");
  expect_error("superpixels:\n  size: 3\n", "superpixels");
  EXPECT_THROW(load_dynamic_config("/nonexistent/dynamic.yaml"), InputError);
}

TEST(DynamicConfig, ErrorsSayWhatWasExpectedAndWhatWasFound) {
  expect_error("epipolar:\n  a_epi_px: -1\n", "epipolar.a_epi_px", "expected a number in (0, 50] px, got -1");
  expect_error("tracking:\n  window_px: 4.5\n", "tracking.window_px", "expected an integer in [5, 63] px, got '4.5'");
  expect_error("roi:\n  scale: 0.3\n", "roi.scale", "expected a number 1 or 0.5 (of the full resolution), got 0.3");
  expect_error("objects:\n  growth_max_ratio: 0.5\n", "objects.growth_max_ratio",
               "expected a number in [1, 100] or 0 (0: off), got 0.5");
  expect_error("band:\n  min_seeds: 7\n  max_seeds: 6\n", "band.max_seeds", "expected at least min_seeds, got 6");
  expect_error("boundaries:\n  lambda_hinge: 3\n  lambda_occ: 3\n", "boundaries.lambda_occ",
               "expected more than lambda_hinge (eq. 11), got 3");
  expect_error("regions:\n  mask_mode: blob\n", "regions.mask_mode",
               "expected one of rectangle, superpixels, disparity, got 'blob'");
  expect_error("planes:\n  seed: 4294967296\n", "planes.seed", "expected an unsigned 32-bit integer, got '4294967296'");
}

TEST(DynamicConfig, TheSeedTakesEveryUnsigned32BitValue) {
  TempYaml f("planes:\n  seed: 4294967295\n");
  EXPECT_EQ(load_dynamic_config(f.path()).planes.seed, 4294967295u);
}

TEST(DynamicConfig, EverySectionRejectsAnUnknownKey) {
  // The echo has one line per section, "section: key=value ...".
  const std::vector<std::string> lines = DynamicDetectorConfig{}.describe();
  ASSERT_EQ(lines.size(), 22u);
  for (const std::string& line : lines) {
    const std::string section = line.substr(0, line.find(':'));
    SCOPED_TRACE(section);
    expect_error(section + ":\n  no_such_key: 1\n", section + ".no_such_key");
  }
}

TEST(DynamicConfig, DetectorRejectsAnInvalidConfiguration) {
  DynamicDetectorConfig c;
  c.slic.iterations = 0;
  StereoCalibration calib;
  calib.left.fx = calib.left.fy = 400;
  calib.left.width = 640;
  calib.left.height = 480;
  calib.baseline_m = 0.1;
  EXPECT_THROW(DynamicDetector(calib, c), InputError);
  calib.baseline_m = 0;  // the depth test needs a baseline
  EXPECT_THROW(DynamicDetector(calib, DynamicDetectorConfig{}), InputError);
}

}  // namespace
}  // namespace agvslam::dynamic
