// params/dynamic.yaml -> DynamicDetectorConfig: one table per section (agvslam/core/param_table.h) reads, validates
// and echoes each part's options. Tables list the keys in the file's order.
#include "agvslam/core/param_table.h"
#include "agvslam/dynamic/detector.h"

namespace agvslam::dynamic {
namespace {

using params::Range;
using params::Table;

const params::EnumNames<MaskMode>& mask_mode_names() {
  static const params::EnumNames<MaskMode> names{{"rectangle", MaskMode::kRectangle},
                                                 {"superpixels", MaskMode::kSuperpixels},
                                                 {"disparity", MaskMode::kDisparity}};
  return names;
}

const Table<QuadtreeFastConfig>& features_params() {
  using C = QuadtreeFastConfig;
  static const Table<C> table = Table<C>("features",
                                         {
                                             {"target_count", &C::target_count, Range::closed(8, 20000)},
                                             {"cell_size_px", &C::cell_size_px, Range::closed(8, 512), "px"},
                                             {"threshold", &C::threshold, Range::closed(1, 255), "grey levels"},
                                             {"min_threshold", &C::min_threshold, Range::at_least(1), "grey levels"},
                                             {"border_px", &C::border_px, Range::closed(3, 256), "px"},
                                         })
                                    .check(
                                        "min_threshold", [](const C& f) { return f.min_threshold <= f.threshold; },
                                        "at most threshold (the fallback for cells without a corner)");
  return table;
}

const Table<LkTrackerConfig>& tracking_params() {
  using C = LkTrackerConfig;
  static const Table<C> table(
      "tracking",
      {
          {"window_px", &C::window_px, Range::closed(5, 63), "px"},
          {"levels", &C::levels, Range::closed(0, 6), "", "pyramid levels above the image"},
          {"min_levels", &C::min_levels, Range::closed(0, 6), "", "above levels: as many as levels"},
          {"motion_margin", &C::motion_margin, Range::closed(1, 10), "", "x the last frame's largest track motion"},
          {"max_iterations", &C::max_iterations, Range::closed(1, 200)},
          {"epsilon", &C::epsilon, Range::left_open(0, 1), "px"},
          {"fb_max_error_px", &C::fb_max_error_px, Range::left_open(0, 20), "px"},
          {"min_eigen_threshold", &C::min_eigen_threshold, Range::closed(0, 1)},
          {"persistent", &C::persistent},
          {"min_track_distance_px", &C::min_track_distance_px, Range::closed(0, 200), "px"},
          {"max_tracks", &C::max_tracks, Range::closed(1, 100000)},
          {"predict_min_px", &C::predict_min_px, Range::closed(0, 1000), "px", "0: searches start at the old position"},
      });
  return table;
}

const Table<EpipolarTestConfig>& epipolar_params() {
  using C = EpipolarTestConfig;
  static const Table<C> table =
      Table<C>("epipolar",
               {
                   {"a_epi_px", &C::a_epi_px, Range::left_open(0, 50), "px"},
                   {"b_epi", &C::b_epi, Range::closed(0, 1), "", "px per px of disparity"},
                   {"ransac_threshold_px", &C::ransac_threshold_px, Range::left_open(0, 20), "px"},
                   {"ransac_confidence", &C::ransac_confidence, Range::open(0.5, 1)},
                   {"ransac_max_iterations", &C::ransac_max_iterations, Range::closed(10, 100000)},
                   {"min_tracks", &C::min_tracks, Range::closed(8, 10000), "", "the 8-point algorithm's minimum"},
                   {"min_parallax_px", &C::min_parallax_px, Range::closed(0, 20), "px"},
                   {"adaptive", &C::adaptive},
                   {"adaptive_k", &C::adaptive_k, Range::left_open(0, 20)},
                   {"a_epi_max_px", &C::a_epi_max_px, Range::at_most(100), "px"},
               })
          .check(
              "a_epi_max_px", [](const C& e) { return e.a_epi_max_px >= e.a_epi_px; },
              "at least a_epi_px (the adaptive constant lies between them)");
  return table;
}

const Table<DepthTestConfig>& depth_test_params() {
  using C = DepthTestConfig;
  static const Table<C> table =
      Table<C>(
          "depth_test",
          {
              {"min_points", &C::min_points, Range::closed(6, 10000)},
              {"min_disparity_px", &C::min_disparity_px, Range::left_open(0, 100), "px"},
              {"ransac_reprojection_px", &C::ransac_reprojection_px, Range::left_open(0, 20), "px"},
              {"ransac_iterations", &C::ransac_iterations, Range::closed(10, 100000)},
              {"ransac_confidence", &C::ransac_confidence, Range::open(0.5, 1)},
              {"a_reproj_px", &C::a_reproj_px, Range::left_open(0, 50), "px"},
              {"b_reproj", &C::b_reproj, Range::closed(0, 1), "", "px per px of disparity"},
              {"a_disp_px", &C::a_disp_px, Range::left_open(0, 50), "px"},
              {"b_disp", &C::b_disp, Range::closed(0, 1), "", "px per px of disparity"},
              {"disparity_slack_px", &C::disparity_slack_px, Range::closed(0, 20), "px"},
              {"disparity_slack_rel", &C::disparity_slack_rel, Range::closed(0, 0.5), "", "fraction of the disparity"},
              {"leaving_margin_px", &C::leaving_margin_px, Range::closed(-1, 1000), "px", "-1: off"},
              {"slip_min_px", &C::slip_min_px, Range::closed(0, 1000), "px", "0: off"},
              {"slip_min_zncc", &C::slip_min_zncc, Range::closed(-1, 1)},
              {"slip_half_window", &C::slip_half_window, Range::closed(1, 30), "px"},
              {"adaptive", &C::adaptive},
              {"adaptive_k", &C::adaptive_k, Range::left_open(0, 20)},
              {"max_scale", &C::max_scale, Range::closed(1, 100)},
          })
          // Not a key of this section: the multi-frame test sets it from multiframe.prior_min_inlier_fraction.
          .check(
              "prior_min_inlier_fraction",
              [](const C& d) { return Range::closed(0, 1).contains(d.prior_min_inlier_fraction); },
              "a fraction in [0, 1] (0: always RANSAC)");
  return table;
}

const Table<MultiFrameTestConfig>& multiframe_params() {
  using C = MultiFrameTestConfig;
  static const Table<C> table =
      Table<C>(
          "multiframe",
          {
              {"enabled", &C::enabled},
              {"max_frames", &C::max_frames, Range::closed(2, 120), "frames"},
              {"min_frames", &C::min_frames, Range::at_least(1), "frames"},
              {"min_translation_m", &C::min_translation_m, Range::closed(0, 10), "m"},
              {"max_rotation_deg", &C::max_rotation_deg, Range::left_open(0, 90), "deg"},
              {"min_points", &C::min_points, Range::closed(6, 10000)},
              {"min_disparity_px", &C::min_disparity_px, Range::left_open(0, 100), "px"},
              {"ransac_reprojection_px", &C::ransac_reprojection_px, Range::left_open(0, 20), "px"},
              {"a_reproj_px", &C::a_reproj_px, Range::left_open(0, 50), "px"},
              {"b_reproj", &C::b_reproj, Range::closed(0, 1), "", "px per px of disparity"},
              {"a_disp_px", &C::a_disp_px, Range::left_open(0, 50), "px"},
              {"b_disp", &C::b_disp, Range::closed(0, 1), "", "px per px of disparity"},
              {"adaptive_k", &C::adaptive_k, Range::left_open(0, 20)},
              {"max_scale", &C::max_scale, Range::closed(1, 100)},
              {"verify_levels", &C::verify_levels, Range::closed(0, 6)},
              {"verify_fb_px", &C::verify_fb_px, Range::left_open(0, 20), "px"},
              {"verify_max_shift_px", &C::verify_max_shift_px, Range::closed(0, 20), "px"},
              {"edge_check_px", &C::edge_check_px, Range::closed(0, 50), "px", "0: off"},
              {"edge_tolerance_px", &C::edge_tolerance_px, Range::closed(0, 100), "px"},
              {"edge_tolerance_rel", &C::edge_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
              {"check_half_window", &C::check_half_window, Range::closed(0, 20), "px", "0: off"},
              {"check_uniqueness_margin", &C::check_uniqueness_margin, Range::closed(0, 10)},
              {"aperture_ratio", &C::aperture_ratio, Range::right_open(0, 1), "", "0: off"},
              {"chain_stereo_only", &C::chain_stereo_only},
              {"chain_stereo_factor", &C::chain_stereo_factor, Range::closed(1, 20), "", "x the thresholds"},
              {"prior_min_inlier_fraction", &C::prior_min_inlier_fraction, Range::closed(0, 1), "", "0: always RANSAC"},
          })
          .check(
              "min_frames", [](const MultiFrameTestConfig& m) { return m.min_frames <= m.max_frames; },
              "at most max_frames");
  return table;
}

const Table<RoiGroupingConfig>& grouping_params() {
  using C = RoiGroupingConfig;
  static const Table<C> table(
      "grouping",
      {
          {"a_s_px", &C::a_s_px, Range::left_open(0, 2000), "px"},
          {"b_s", &C::b_s, Range::closed(0, 100), "", "px per px of disparity"},
          {"t_disp_px", &C::t_disp_px, Range::closed(0, 500), "px"},
          {"t_disp_rel", &C::t_disp_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"min_points", &C::min_points, Range::closed(1, 1000)},
          {"margin_px", &C::margin_px, Range::closed(0, 1000), "px"},
          {"margin_disparity_factor", &C::margin_disparity_factor, Range::closed(0, 100), "", "px per px of disparity"},
          {"merge_overlapping", &C::merge_overlapping},
          {"merge_side_gap_m", &C::merge_side_gap_m, Range::closed(0, 5), "m", "0: off"},
      });
  return table;
}

const Table<SlicConfig>& slic_params() {
  using C = SlicConfig;
  static const Table<C> table(
      "slic", {
                  {"superpixel_size_px", &C::superpixel_size_px, Range::closed(3, 200), "px"},
                  {"max_superpixels", &C::max_superpixels, Range::closed(1, 100000), "per ROI"},
                  {"max_color_distance", &C::max_color_distance, Range::left_open(0, 255), "grey levels"},
                  {"iterations", &C::iterations, Range::closed(1, 100)},
                  {"min_change_fraction", &C::min_change_fraction, Range::right_open(0, 1)},
                  {"incremental", &C::incremental},
                  {"min_segment_fraction", &C::min_segment_fraction, Range::closed(0, 1), "", "of S^2"},
              });
  return table;
}

const Table<PlaneFitConfig>& planes_params() {
  using C = PlaneFitConfig;
  static const Table<C> table(
      "planes", {
                    {"ransac_iterations", &C::ransac_iterations, Range::closed(1, 10000)},
                    {"confidence", &C::confidence, Range::open(0, 1)},
                    {"inlier_threshold_px", &C::inlier_threshold_px, Range::left_open(0, 20), "px"},
                    {"min_valid_pixels", &C::min_valid_pixels, Range::closed(3, 100000), "px", "a plane needs 3"},
                    {"min_valid_fraction", &C::min_valid_fraction, Range::closed(0, 1)},
                    {"min_inlier_fraction", &C::min_inlier_fraction, Range::closed(0, 1)},
                    {"max_samples", &C::max_samples, Range::closed(10, 1000000)},
                    {"seed", &C::seed, Range::any()},
                });
  return table;
}

const Table<BoundaryConfig>& boundaries_params() {
  using C = BoundaryConfig;
  static const Table<C> table = Table<C>("boundaries",
                                         {
                                             {"lambda_occ", &C::lambda_occ, Range::at_most(1e4), "px^2"},
                                             {"lambda_hinge", &C::lambda_hinge, Range::left_open(0, 1e4), "px^2"},
                                             {"lambda_pen", &C::lambda_pen, Range::left_open(0, 1e6), "px^2"},
                                         })
                                    .check(
                                        "lambda_occ", [](const C& b) { return b.lambda_occ > b.lambda_hinge; },
                                        "more than lambda_hinge (eq. 11)");
  return table;
}

const Table<RegionSearchConfig>& regions_params() {
  using C = RegionSearchConfig;
  static const Table<C> table(
      "regions",
      {
          {"start_radius_px", &C::start_radius_px, Range::closed(0, 50), "px"},
          {"start_tolerance_px", &C::start_tolerance_px, Range::left_open(0, 100), "px"},
          {"start_tolerance_rel", &C::start_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"stop_at_unknown", &C::stop_at_unknown},
          {"disparity_band", &C::disparity_band},
          {"band_tolerance_px", &C::band_tolerance_px, Range::closed(0, 100), "px"},
          {"band_tolerance_rel", &C::band_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"local_band", &C::local_band},
          {"static_veto", &C::static_veto},
          {"ground_veto", &C::ground_veto},
          {"ground_tolerance_px", &C::ground_tolerance_px, Range::closed(0, 100), "px"},
          {"ground_tolerance_rel", &C::ground_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"ground_slope_tolerance", &C::ground_slope_tolerance, Range::closed(0, 10), "",
           "of the ground plane's slope"},
          {"enclosed_unknown_only", &C::enclosed_unknown_only},
          {"mask_mode", &C::mask_mode, mask_mode_names()},
      });
  return table;
}

const Table<OutlineConfig>& outline_params() {
  using C = OutlineConfig;
  static const Table<C> table(
      "outline",
      {
          {"seed_radius_px", &C::seed_radius_px, Range::closed(0, 50), "px"},
          {"seed_tolerance_px", &C::seed_tolerance_px, Range::left_open(0, 100), "px"},
          {"seed_tolerance_rel", &C::seed_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"step_tolerance_px", &C::step_tolerance_px, Range::left_open(0, 100), "px"},
          {"step_tolerance_rel", &C::step_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"depth_band_m", &C::depth_band_m, Range::left_open(0, 100), "m"},
          {"ground_tolerance_px", &C::ground_tolerance_px, Range::closed(0, 100), "px"},
          {"ground_tolerance_rel", &C::ground_tolerance_rel, Range::closed(0, 10), "", "px per px of disparity"},
          {"static_competition", &C::static_competition},
          {"max_hole_invalid_fraction", &C::max_hole_invalid_fraction, Range::closed(0, 1)},
          {"min_hole_fill_px", &C::min_hole_fill_px, Range::closed(0, 1000000), "px"},
          {"weak_texture_dn", &C::weak_texture_dn, Range::closed(0, 255), "grey levels per px", "0: off"},
          {"erode_px", &C::erode_px, Range::closed(0, 10), "px"},
          {"min_pixels", &C::min_pixels, Range::closed(0, 1000000), "px"},
          {"min_dynamic_fraction", &C::min_dynamic_fraction, Range::closed(0, 1)},
          {"min_tracked_for_fraction", &C::min_tracked_for_fraction, Range::closed(1, 100000)},
          {"aggregate_ratio", &C::aggregate_ratio, Range::closed(0, 1000), "", "0: off"},
          {"aggregate_min_px", &C::aggregate_min_px, Range::closed(0, 100), "px"},
          {"aggregate_min_tracks", &C::aggregate_min_tracks, Range::closed(0, 10000), "", "0: off"},
          {"aggregate_multiframe_fraction", &C::aggregate_multiframe_fraction, Range::closed(0, 1), "", "0: off"},
          {"aggregate_multiframe_min_px", &C::aggregate_multiframe_min_px, Range::closed(0, 100), "px"},
          {"max_height_m", &C::max_height_m, Range::closed(0, 100), "m", "0: no limit"},
          {"close_far_m", &C::close_far_m, Range::closed(0, 2), "m", "0: off"},
          {"left_band_touch_px", &C::left_band_touch_px, Range::closed(-1, 100), "px", "-1: off"},
          {"close_max_disparity_px", &C::close_max_disparity_px, Range::closed(0, 500), "px"},
      });
  return table;
}

const Table<EdgeRefineConfig>& edge_refine_params() {
  using C = EdgeRefineConfig;
  static const Table<C> table("edge_refine",
                              {
                                  {"band_px", &C::band_px, Range::closed(0, 32), "px", "0: off"},
                                  {"half_rows", &C::half_rows, Range::closed(0, 16), "rows"},
                                  {"background_px", &C::background_px, Range::closed(1, 64), "px"},
                                  {"min_disparity_gap_px", &C::min_disparity_gap_px, Range::closed(0, 100), "px"},
                                  {"occlusion_cost", &C::occlusion_cost, Range::left_open(0, 255), "grey levels"},
                                  {"min_gain", &C::min_gain, Range::closed(0, 255), "grey levels per px"},
                              });
  return table;
}

const Table<PhotometricCheckConfig>& photometric_params() {
  using C = PhotometricCheckConfig;
  static const Table<C> table(
      "photometric",
      {
          {"enabled", &C::enabled},
          {"max_motion_px", &C::max_motion_px, Range::left_open(0, 20), "px"},
          {"min_gradient", &C::min_gradient, Range::closed(0, 255), "grey levels per px"},
          {"sample_step_px", &C::sample_step_px, Range::closed(1, 16), "px"},
          {"min_samples", &C::min_samples, Range::closed(3, 100000)},
          {"multiframe_max_motion_px", &C::multiframe_max_motion_px, Range::left_open(0, 20), "px"},
          {"multiframe_min_disparity_px", &C::multiframe_min_disparity_px, Range::closed(0, 1000), "px", "0: any"},
          {"far_multiframe_tracks", &C::far_multiframe_tracks},
          {"region_inset_px", &C::region_inset_px, Range::closed(0, 20), "px"},
      });
  return table;
}

const Table<MotionCarveConfig>& motion_carve_params() {
  using C = MotionCarveConfig;
  static const Table<C> table =
      Table<C>("motion_carve",
               {
                   {"enabled", &C::enabled},
                   {"block_px", &C::block_px, Range::closed(2, 64), "px"},
                   {"sample_step_px", &C::sample_step_px, Range::at_least(1), "px"},
                   {"search_px", &C::search_px, Range::closed(0, 8), "px"},
                   {"min_gradient", &C::min_gradient, Range::closed(0, 255), "grey levels per px"},
                   {"min_samples", &C::min_samples, Range::closed(2, 4096), "per block"},
                   {"max_static_ratio", &C::max_static_ratio, Range::left_open(0, 1), "", "of the object's error"},
                   {"min_object_error_dn", &C::min_object_error_dn, Range::closed(0, 255), "grey levels"},
                   {"max_static_error_dn", &C::max_static_error_dn, Range::left_open(0, 255), "grey levels"},
                   {"min_separation_px", &C::min_separation_px, Range::closed(0, 100), "px"},
                   {"seed_radius_px", &C::seed_radius_px, Range::closed(0, 32), "px"},
               })
          .check(
              "sample_step_px", [](const C& m) { return m.sample_step_px <= m.block_px; },
              "at most block_px (a block holds a sample)");
  return table;
}

const Table<BandSegmenterConfig>& band_params() {
  using C = BandSegmenterConfig;
  static const Table<C> table =
      Table<C>("band",
               {
                   {"enabled", &C::enabled},
                   {"strip_px", &C::strip_px, Range::closed(8, 512), "px"},
                   {"max_disparity_px", &C::max_disparity_px, Range::left_open(0, 1024), "px"},
                   {"max_static_segment_px", &C::max_static_segment_px, Range::left_open(0, 64), "px"},
                   {"segment_step_px", &C::segment_step_px, Range::closed(0.05, 8), "px"},
                   {"border_px", &C::border_px, Range::closed(2, 64), "px"},
                   {"fast_threshold", &C::fast_threshold, Range::closed(1, 255), "grey levels"},
                   {"cell_px", &C::cell_px, Range::closed(2, 128), "px"},
                   {"seed_offset_px", &C::seed_offset_px, Range::left_open(0, 50), "px"},
                   {"min_seeds", &C::min_seeds, Range::closed(1, 1000)},
                   {"max_seeds", &C::max_seeds, Range::at_most(1000)},
                   {"nearest_seeds", &C::nearest_seeds, Range::closed(1, 16)},
                   {"evidence_dn", &C::evidence_dn, Range::left_open(0, 255), "grey levels"},
                   {"max_object_error_dn", &C::max_object_error_dn, Range::left_open(0, 255), "grey levels"},
                   {"edge_fill_px", &C::edge_fill_px, Range::closed(0, 64), "px"},
                   {"reach_px", &C::reach_px, Range::closed(1, 1000), "px"},
                   {"close_px", &C::close_px, Range::closed(1, 63), "px"},
                   {"min_pixels", &C::min_pixels, Range::closed(1, 10000000), "px"},
                   {"min_height_px", &C::min_height_px, Range::closed(1, 10000), "px"},
                   {"merge_distance_px", &C::merge_distance_px, Range::closed(0, 64), "px"},
                   {"stack_gap_px", &C::stack_gap_px, Range::closed(0, 1000), "px", "0: only touching"},
                   {"driving_seed_offset_px", &C::driving_seed_offset_px, Range::closed(0, 50), "px", "0: off"},
                   {"driving_cell_px", &C::driving_cell_px, Range::closed(2, 128), "px"},
               })
          .check(
              "max_seeds", [](const C& b) { return b.max_seeds >= b.min_seeds; }, "at least min_seeds");
  return table;
}

const Table<DetectorOptions>& detector_params() {
  using C = DetectorOptions;
  static const Table<C> table =
      Table<C>("detector",
               {
                   {"use_epipolar_test", &C::use_epipolar_test},
                   {"use_depth_test", &C::use_depth_test},
                   {"full_frame_disparity", &C::full_frame_disparity},
                   {"max_rois", &C::max_rois, Range::closed(0, 256), "per frame"},
                   {"merge_stacked_regions", &C::merge_stacked_regions},
                   {"split_side_by_side", &C::split_side_by_side},
                   {"mask_dilation_px", &C::mask_dilation_px, Range::closed(0, 64), "px"},
               })
          .check(
              "use_epipolar_test", [](const C& d) { return d.use_epipolar_test || d.use_depth_test; },
              "true when use_depth_test is false (a point needs a test)");
  return table;
}

const Table<RoiOptions>& roi_params() {
  using C = RoiOptions;
  static const Table<C> table(
      "roi", {
                 {"disparity_margin_px", &C::disparity_margin_px, Range::closed(0, 1024), "px",
                  "a large value searches the whole configured range"},
                 {"scale", &C::scale, Range::value(1) | Range::value(0.5), "", "of the full resolution"},
                 {"row_step", &C::row_step, Range::value(1) | Range::value(2), "", "rows per matched row"},
                 {"row_step_min_area_px", &C::row_step_min_area_px, Range::at_least(0), "px", "0: every ROI"},
                 {"half_scale_min_area_px", &C::half_scale_min_area_px, Range::at_least(0), "px", "0: never"},
                 {"half_scale_erode_px", &C::half_scale_erode_px, Range::closed(0, 10), "px"},
                 {"pad_left_border", &C::pad_left_border},
                 {"speckle_filter", &C::speckle_filter},
                 {"extend_to_floor", &C::extend_to_floor},
                 {"extend_to_height_m", &C::extend_to_height_m, Range::closed(0, 20), "m", "0: not"},
                 {"extend_max_rounds", &C::extend_max_rounds, Range::closed(0, 100), "", "0: off"},
                 {"extend_min_rows", &C::extend_min_rows, Range::closed(1, 10000), "rows"},
                 {"extend_step_m", &C::extend_step_m, Range::left_open(0, 100), "m"},
                 {"extend_static_guard_px", &C::extend_static_guard_px, Range::closed(0, 10000), "px", "0: off"},
             });
  return table;
}

const Table<DensifyOptions>& densify_params() {
  using C = DensifyOptions;
  static const Table<C> table(
      "densify",
      {
          {"enabled", &C::enabled},
          {"radius_px", &C::radius_px, Range::closed(0, 500), "px"},
          {"radius_disparity_factor", &C::radius_disparity_factor, Range::closed(0, 50), "", "px per px of disparity"},
          {"max_points", &C::max_points, Range::closed(0, 1000), "per group"},
          {"min_distance_px", &C::min_distance_px, Range::closed(0, 100), "px"},
          {"min_seeds", &C::min_seeds, Range::closed(1, 100)},
          {"depth_seed_factor", &C::depth_seed_factor, Range::closed(0, 100), "",
           "x the depth test's threshold; 0: depth-test points alone never seed"},
          {"extra_tracks", &C::extra_tracks, Range::closed(0, 10000)},
          {"keep_static", &C::keep_static},
          {"multiframe_levels", &C::multiframe_levels, Range::closed(-1, 5), "", "-1: off"},
          {"multiframe_agreement", &C::multiframe_agreement, Range::left_open(0, 2)},
          {"multiframe_factor", &C::multiframe_factor, Range::closed(1, 20), "", "x the multi-frame threshold"},
      });
  return table;
}

const Table<ObjectTrackerOptions>& objects_params() {
  using C = ObjectTrackerOptions;
  static const Table<C> table(
      "objects",
      {
          {"enabled", &C::enabled},
          {"continue_min_points", &C::continue_min_points, Range::closed(1, 1000)},
          {"coast_max_frames", &C::coast_max_frames, Range::closed(0, 100), "frames", "0: off"},
          {"coast_min_detections", &C::coast_min_detections, Range::closed(1, 1000), "frames"},
          {"coast_min_tracks", &C::coast_min_tracks, Range::closed(1, 1000)},
          {"coast_min_area_ratio", &C::coast_min_area_ratio, Range::closed(0, 1)},
          {"growth_max_ratio", &C::growth_max_ratio, Range::closed(1, 100) | Range::value(0), "", "0: off"},
          {"growth_margin", &C::growth_margin, Range::closed(0, 2), "", "of the object's last width / height"},
      });
  return table;
}

const Table<BandCarryOptions>& band_carry_params() {
  using C = BandCarryOptions;
  static const Table<C> table("band_carry",
                              {
                                  {"max_frames", &C::max_frames, Range::closed(0, 100), "frames", "0: off"},
                                  {"min_tracks", &C::min_tracks, Range::closed(1, 1000)},
                                  {"min_dynamic", &C::min_dynamic, Range::closed(0, 1000)},
                              });
  return table;
}

const Table<StaticCarveOptions>& static_carve_params() {
  using C = StaticCarveOptions;
  static const Table<C> table("static_carve",
                              {
                                  {"min_tracks", &C::min_tracks, Range::closed(0, 1000), "", "0: off"},
                                  {"max_offset_px", &C::max_offset_px, Range::closed(0, 100), "px"},
                                  {"max_multiframe_px", &C::max_multiframe_px, Range::closed(0, 100), "px"},
                                  {"min_distance_px", &C::min_distance_px, Range::closed(0, 1000), "px"},
                              });
  return table;
}

const Table<ConfirmOptions>& confirm_params() {
  using C = ConfirmOptions;
  static const Table<C> table("confirm",
                              {
                                  {"min_box_iou", &C::min_box_iou, Range::closed(0, 1), "", "0: off"},
                                  {"below_px", &C::below_px, Range::at_least(0), "px", "0: every object waits"},
                                  {"near_min_disparity_px", &C::near_min_disparity_px, Range::closed(0, 1024), "px"},
                                  {"near_min_offset_px", &C::near_min_offset_px, Range::closed(0, 1000), "px"},
                                  {"near_min_px", &C::near_min_px, Range::at_least(0), "px", "0: off"},
                                  {"near_min_roi_fill", &C::near_min_roi_fill, Range::closed(0, 1), "", "of the ROI"},
                              });
  return table;
}

// Every section of params/dynamic.yaml in the file's order, as visit(table, the member it fills): the one list that
// loading, validation and the echo go through.
template <class Config, class Visit>
void for_each_section(Config& c, Visit&& visit) {
  visit(features_params(), c.features);
  visit(tracking_params(), c.tracking);
  visit(epipolar_params(), c.epipolar);
  visit(depth_test_params(), c.depth_test);
  visit(multiframe_params(), c.multiframe);
  visit(grouping_params(), c.grouping);
  visit(slic_params(), c.slic);
  visit(planes_params(), c.planes);
  visit(boundaries_params(), c.boundaries);
  visit(regions_params(), c.regions);
  visit(outline_params(), c.outline);
  visit(edge_refine_params(), c.edge_refine);
  visit(photometric_params(), c.photometric);
  visit(motion_carve_params(), c.motion_carve);
  visit(band_params(), c.band);
  visit(detector_params(), c.detector);
  visit(roi_params(), c.roi);
  visit(densify_params(), c.densify);
  visit(objects_params(), c.objects);
  visit(band_carry_params(), c.band_carry);
  visit(static_carve_params(), c.static_carve);
  visit(confirm_params(), c.confirm);
}

}  // namespace

std::string to_string(MaskMode mode) { return mask_mode_names().name(mode); }
bool parse_mask_mode(const std::string& text, MaskMode& mode) { return mask_mode_names().parse(text, mode); }

void QuadtreeFastConfig::validate(const std::string& source) const { features_params().validate(source, *this); }
std::string QuadtreeFastConfig::describe() const { return features_params().describe(*this); }
void LkTrackerConfig::validate(const std::string& source) const { tracking_params().validate(source, *this); }
std::string LkTrackerConfig::describe() const { return tracking_params().describe(*this); }
void EpipolarTestConfig::validate(const std::string& source) const { epipolar_params().validate(source, *this); }
std::string EpipolarTestConfig::describe() const { return epipolar_params().describe(*this); }
void DepthTestConfig::validate(const std::string& source) const { depth_test_params().validate(source, *this); }
std::string DepthTestConfig::describe() const { return depth_test_params().describe(*this); }
void MultiFrameTestConfig::validate(const std::string& source) const { multiframe_params().validate(source, *this); }
std::string MultiFrameTestConfig::describe() const { return multiframe_params().describe(*this); }
void RoiGroupingConfig::validate(const std::string& source) const { grouping_params().validate(source, *this); }
std::string RoiGroupingConfig::describe() const { return grouping_params().describe(*this); }
void SlicConfig::validate(const std::string& source) const { slic_params().validate(source, *this); }
std::string SlicConfig::describe() const { return slic_params().describe(*this); }
void PlaneFitConfig::validate(const std::string& source) const { planes_params().validate(source, *this); }
std::string PlaneFitConfig::describe() const { return planes_params().describe(*this); }
void BoundaryConfig::validate(const std::string& source) const { boundaries_params().validate(source, *this); }
std::string BoundaryConfig::describe() const { return boundaries_params().describe(*this); }
void RegionSearchConfig::validate(const std::string& source) const { regions_params().validate(source, *this); }
std::string RegionSearchConfig::describe() const { return regions_params().describe(*this); }
void OutlineConfig::validate(const std::string& source) const { outline_params().validate(source, *this); }
std::string OutlineConfig::describe() const { return outline_params().describe(*this); }
void EdgeRefineConfig::validate(const std::string& source) const { edge_refine_params().validate(source, *this); }
std::string EdgeRefineConfig::describe() const { return edge_refine_params().describe(*this); }
void PhotometricCheckConfig::validate(const std::string& source) const { photometric_params().validate(source, *this); }
std::string PhotometricCheckConfig::describe() const { return photometric_params().describe(*this); }
void MotionCarveConfig::validate(const std::string& source) const { motion_carve_params().validate(source, *this); }
std::string MotionCarveConfig::describe() const { return motion_carve_params().describe(*this); }
void BandSegmenterConfig::validate(const std::string& source) const { band_params().validate(source, *this); }
std::string BandSegmenterConfig::describe() const { return band_params().describe(*this); }
void DetectorOptions::validate(const std::string& source) const { detector_params().validate(source, *this); }
std::string DetectorOptions::describe() const { return detector_params().describe(*this); }
void RoiOptions::validate(const std::string& source) const { roi_params().validate(source, *this); }
std::string RoiOptions::describe() const { return roi_params().describe(*this); }
void DensifyOptions::validate(const std::string& source) const { densify_params().validate(source, *this); }
std::string DensifyOptions::describe() const { return densify_params().describe(*this); }
void ObjectTrackerOptions::validate(const std::string& source) const { objects_params().validate(source, *this); }
std::string ObjectTrackerOptions::describe() const { return objects_params().describe(*this); }
void BandCarryOptions::validate(const std::string& source) const { band_carry_params().validate(source, *this); }
std::string BandCarryOptions::describe() const { return band_carry_params().describe(*this); }
void StaticCarveOptions::validate(const std::string& source) const { static_carve_params().validate(source, *this); }
std::string StaticCarveOptions::describe() const { return static_carve_params().describe(*this); }
void ConfirmOptions::validate(const std::string& source) const { confirm_params().validate(source, *this); }
std::string ConfirmOptions::describe() const { return confirm_params().describe(*this); }

void DynamicDetectorConfig::validate(const std::string& source) const {
  for_each_section(*this, [&](const auto& table, const auto& options) { table.validate(source, options); });
}

std::vector<std::string> DynamicDetectorConfig::describe() const {
  std::vector<std::string> lines;
  for_each_section(*this, [&](const auto& table, const auto& options) { lines.push_back(table.describe(options)); });
  return lines;
}

DynamicDetectorConfig load_dynamic_config(const std::string& path) {
  DynamicDetectorConfig c;
  std::vector<params::SectionReader> sections;
  for_each_section(c, [&](const auto& table, auto& options) { sections.push_back(table.reader(options)); });
  params::read_sections(params::File(path), sections);
  c.validate(path);
  return c;
}

}  // namespace agvslam::dynamic
