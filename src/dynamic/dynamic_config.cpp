// params/dynamic.yaml -> DynamicDetectorConfig.
#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::dynamic {

DynamicDetectorConfig load_dynamic_config(const std::string& path) {
  const stereo::ParamsReader in(path);
  in.check_sections({"features", "tracking", "epipolar", "depth_test", "multiframe", "grouping", "slic", "planes", "boundaries",
                     "regions", "outline", "edge_refine", "photometric", "motion_carve", "band", "detector", "roi", "densify",
                     "objects", "band_carry", "static_carve", "confirm"});
  DynamicDetectorConfig c;
  const char* px = "a number (px)";
  const char* num = "a number";
  const char* integer = "an integer";
  const char* flag = "true or false";

  in.check_keys("features", {"target_count", "cell_size_px", "threshold", "min_threshold", "border_px"});
  in.read("features", "target_count", c.features.target_count, integer);
  in.read("features", "cell_size_px", c.features.cell_size_px, "an integer (px)");
  in.read("features", "threshold", c.features.threshold, "an integer (grey levels)");
  in.read("features", "min_threshold", c.features.min_threshold, "an integer (grey levels)");
  in.read("features", "border_px", c.features.border_px, "an integer (px)");

  in.check_keys("tracking", {"window_px", "levels", "min_levels", "motion_margin", "max_iterations", "epsilon",
                             "fb_max_error_px", "min_eigen_threshold", "persistent", "min_track_distance_px",
                             "max_tracks", "predict_min_px"});
  in.read("tracking", "window_px", c.tracking.window_px, "an integer (px)");
  in.read("tracking", "levels", c.tracking.levels, integer);
  in.read("tracking", "min_levels", c.tracking.min_levels, integer);
  in.read("tracking", "motion_margin", c.tracking.motion_margin, num);
  in.read("tracking", "max_iterations", c.tracking.max_iterations, integer);
  in.read("tracking", "epsilon", c.tracking.epsilon, px);
  in.read("tracking", "fb_max_error_px", c.tracking.fb_max_error_px, px);
  in.read("tracking", "min_eigen_threshold", c.tracking.min_eigen_threshold, num);
  in.read("tracking", "persistent", c.tracking.persistent, flag);
  in.read("tracking", "min_track_distance_px", c.tracking.min_track_distance_px, px);
  in.read("tracking", "max_tracks", c.tracking.max_tracks, integer);
  in.read("tracking", "predict_min_px", c.tracking.predict_min_px, px);

  in.check_keys("epipolar", {"a_epi_px", "b_epi", "ransac_threshold_px", "ransac_confidence", "ransac_max_iterations",
                             "min_tracks", "min_parallax_px", "adaptive", "adaptive_k", "a_epi_max_px"});
  in.read("epipolar", "a_epi_px", c.epipolar.a_epi_px, px);
  in.read("epipolar", "b_epi", c.epipolar.b_epi, num);
  in.read("epipolar", "ransac_threshold_px", c.epipolar.ransac_threshold_px, px);
  in.read("epipolar", "ransac_confidence", c.epipolar.ransac_confidence, num);
  in.read("epipolar", "ransac_max_iterations", c.epipolar.ransac_max_iterations, integer);
  in.read("epipolar", "min_tracks", c.epipolar.min_tracks, integer);
  in.read("epipolar", "min_parallax_px", c.epipolar.min_parallax_px, px);
  in.read("epipolar", "adaptive", c.epipolar.adaptive, flag);
  in.read("epipolar", "adaptive_k", c.epipolar.adaptive_k, num);
  in.read("epipolar", "a_epi_max_px", c.epipolar.a_epi_max_px, px);

  in.check_keys("depth_test", {"min_points", "min_disparity_px", "ransac_reprojection_px", "ransac_iterations",
                               "ransac_confidence", "a_reproj_px", "b_reproj", "a_disp_px", "b_disp", "adaptive",
                               "adaptive_k", "max_scale"});
  DepthTestConfig& d = c.depth_test;
  in.read("depth_test", "min_points", d.min_points, integer);
  in.read("depth_test", "min_disparity_px", d.min_disparity_px, px);
  in.read("depth_test", "ransac_reprojection_px", d.ransac_reprojection_px, px);
  in.read("depth_test", "ransac_iterations", d.ransac_iterations, integer);
  in.read("depth_test", "ransac_confidence", d.ransac_confidence, num);
  in.read("depth_test", "a_reproj_px", d.a_reproj_px, px);
  in.read("depth_test", "b_reproj", d.b_reproj, num);
  in.read("depth_test", "a_disp_px", d.a_disp_px, px);
  in.read("depth_test", "b_disp", d.b_disp, num);
  in.read("depth_test", "adaptive", d.adaptive, flag);
  in.read("depth_test", "adaptive_k", d.adaptive_k, num);
  in.read("depth_test", "max_scale", d.max_scale, num);

  in.check_keys("multiframe", {"enabled", "max_frames", "min_frames", "min_translation_m", "max_rotation_deg",
                               "min_points", "min_disparity_px", "ransac_reprojection_px", "a_reproj_px", "b_reproj",
                               "a_disp_px", "b_disp", "adaptive_k", "max_scale", "verify_levels", "verify_fb_px",
                               "verify_max_shift_px", "edge_check_px", "edge_tolerance_px", "edge_tolerance_rel",
                               "check_half_window", "check_uniqueness_margin", "aperture_ratio", "chain_stereo_only", "chain_stereo_factor",
                               "prior_min_inlier_fraction"});
  MultiFrameTestConfig& m = c.multiframe;
  in.read("multiframe", "enabled", m.enabled, flag);
  in.read("multiframe", "max_frames", m.max_frames, integer);
  in.read("multiframe", "min_frames", m.min_frames, integer);
  in.read("multiframe", "min_translation_m", m.min_translation_m, "a number (m)");
  in.read("multiframe", "max_rotation_deg", m.max_rotation_deg, "a number (deg)");
  in.read("multiframe", "min_points", m.min_points, integer);
  in.read("multiframe", "min_disparity_px", m.min_disparity_px, px);
  in.read("multiframe", "ransac_reprojection_px", m.ransac_reprojection_px, px);
  in.read("multiframe", "a_reproj_px", m.a_reproj_px, px);
  in.read("multiframe", "b_reproj", m.b_reproj, num);
  in.read("multiframe", "a_disp_px", m.a_disp_px, px);
  in.read("multiframe", "b_disp", m.b_disp, num);
  in.read("multiframe", "adaptive_k", m.adaptive_k, num);
  in.read("multiframe", "max_scale", m.max_scale, num);
  in.read("multiframe", "verify_levels", m.verify_levels, integer);
  in.read("multiframe", "verify_fb_px", m.verify_fb_px, px);
  in.read("multiframe", "verify_max_shift_px", m.verify_max_shift_px, px);
  in.read("multiframe", "edge_check_px", m.edge_check_px, "an integer (px)");
  in.read("multiframe", "edge_tolerance_px", m.edge_tolerance_px, px);
  in.read("multiframe", "edge_tolerance_rel", m.edge_tolerance_rel, num);
  in.read("multiframe", "check_half_window", m.check_half_window, integer);
  in.read("multiframe", "check_uniqueness_margin", m.check_uniqueness_margin, num);
  in.read("multiframe", "aperture_ratio", m.aperture_ratio, num);
  in.read("multiframe", "chain_stereo_only", m.chain_stereo_only, flag);
  in.read("multiframe", "chain_stereo_factor", m.chain_stereo_factor, num);
  in.read("multiframe", "prior_min_inlier_fraction", m.prior_min_inlier_fraction, num);

  in.check_keys("grouping", {"a_s_px", "b_s", "t_disp_px", "t_disp_rel", "min_points", "margin_px",
                             "margin_disparity_factor", "merge_overlapping", "merge_side_gap_m"});
  in.read("grouping", "a_s_px", c.grouping.a_s_px, px);
  in.read("grouping", "b_s", c.grouping.b_s, num);
  in.read("grouping", "t_disp_px", c.grouping.t_disp_px, px);
  in.read("grouping", "t_disp_rel", c.grouping.t_disp_rel, num);
  in.read("grouping", "min_points", c.grouping.min_points, integer);
  in.read("grouping", "margin_px", c.grouping.margin_px, "an integer (px)");
  in.read("grouping", "margin_disparity_factor", c.grouping.margin_disparity_factor, num);
  in.read("grouping", "merge_overlapping", c.grouping.merge_overlapping, flag);
  in.read("grouping", "merge_side_gap_m", c.grouping.merge_side_gap_m, "a number (m)");

  in.check_keys("slic", {"superpixel_size_px", "max_superpixels", "max_color_distance", "iterations",
                         "min_change_fraction", "incremental", "min_segment_fraction"});
  in.read("slic", "superpixel_size_px", c.slic.superpixel_size_px, "an integer (px)");
  in.read("slic", "max_superpixels", c.slic.max_superpixels, integer);
  in.read("slic", "max_color_distance", c.slic.max_color_distance, "a number (grey levels)");
  in.read("slic", "iterations", c.slic.iterations, integer);
  in.read("slic", "min_change_fraction", c.slic.min_change_fraction, num);
  in.read("slic", "incremental", c.slic.incremental, flag);
  in.read("slic", "min_segment_fraction", c.slic.min_segment_fraction, num);

  in.check_keys("planes", {"ransac_iterations", "confidence", "inlier_threshold_px", "min_valid_pixels",
                           "min_valid_fraction", "min_inlier_fraction", "max_samples", "seed"});
  in.read("planes", "ransac_iterations", c.planes.ransac_iterations, integer);
  in.read("planes", "confidence", c.planes.confidence, num);
  in.read("planes", "inlier_threshold_px", c.planes.inlier_threshold_px, px);
  in.read("planes", "min_valid_pixels", c.planes.min_valid_pixels, integer);
  in.read("planes", "min_valid_fraction", c.planes.min_valid_fraction, num);
  in.read("planes", "min_inlier_fraction", c.planes.min_inlier_fraction, num);
  in.read("planes", "max_samples", c.planes.max_samples, integer);
  int seed = static_cast<int>(c.planes.seed);
  in.read("planes", "seed", seed, "a non-negative integer");
  if (seed < 0) throw InputError(path, "planes.seed", "expected a non-negative integer");
  c.planes.seed = static_cast<uint32_t>(seed);

  in.check_keys("boundaries", {"lambda_occ", "lambda_hinge", "lambda_pen"});
  in.read("boundaries", "lambda_occ", c.boundaries.lambda_occ, "a number (px^2)");
  in.read("boundaries", "lambda_hinge", c.boundaries.lambda_hinge, "a number (px^2)");
  in.read("boundaries", "lambda_pen", c.boundaries.lambda_pen, "a number (px^2)");

  in.check_keys("regions", {"start_radius_px", "start_tolerance_px", "start_tolerance_rel", "stop_at_unknown",
                            "disparity_band", "band_tolerance_px", "band_tolerance_rel", "local_band", "static_veto", "ground_veto", "ground_tolerance_px", "ground_tolerance_rel",
                            "ground_slope_tolerance", "enclosed_unknown_only", "mask_mode"});
  in.read("regions", "start_radius_px", c.regions.start_radius_px, "an integer (px)");
  in.read("regions", "start_tolerance_px", c.regions.start_tolerance_px, px);
  in.read("regions", "start_tolerance_rel", c.regions.start_tolerance_rel, num);
  in.read("regions", "stop_at_unknown", c.regions.stop_at_unknown, flag);
  in.read("regions", "disparity_band", c.regions.disparity_band, flag);
  in.read("regions", "band_tolerance_px", c.regions.band_tolerance_px, px);
  in.read("regions", "band_tolerance_rel", c.regions.band_tolerance_rel, num);
  in.read("regions", "local_band", c.regions.local_band, flag);
  in.read("regions", "static_veto", c.regions.static_veto, flag);
  in.read("regions", "ground_veto", c.regions.ground_veto, flag);
  in.read("regions", "ground_tolerance_px", c.regions.ground_tolerance_px, px);
  in.read("regions", "ground_tolerance_rel", c.regions.ground_tolerance_rel, num);
  in.read("regions", "ground_slope_tolerance", c.regions.ground_slope_tolerance, num);
  in.read("regions", "enclosed_unknown_only", c.regions.enclosed_unknown_only, flag);
  std::string mode = to_string(c.regions.mask_mode);
  in.read("regions", "mask_mode", mode, "rectangle, superpixels or disparity");
  if (!parse_mask_mode(mode, c.regions.mask_mode)) {
    throw InputError(path, "regions.mask_mode", "expected rectangle, superpixels or disparity");
  }

  in.check_keys("outline", {"seed_radius_px", "seed_tolerance_px", "seed_tolerance_rel", "step_tolerance_px",
                            "step_tolerance_rel", "depth_band_m", "ground_tolerance_px", "ground_tolerance_rel",
                            "static_competition", "max_hole_invalid_fraction", "min_hole_fill_px", "erode_px", "min_pixels",
                            "min_dynamic_fraction", "min_tracked_for_fraction", "aggregate_ratio", "aggregate_min_px", "aggregate_min_tracks", "aggregate_multiframe_fraction",
                            "aggregate_multiframe_min_px", "max_height_m", "close_far_m",
                            "close_max_disparity_px", "left_band_touch_px"});
  OutlineConfig& o = c.outline;
  in.read("outline", "seed_radius_px", o.seed_radius_px, "an integer (px)");
  in.read("outline", "seed_tolerance_px", o.seed_tolerance_px, px);
  in.read("outline", "seed_tolerance_rel", o.seed_tolerance_rel, num);
  in.read("outline", "step_tolerance_px", o.step_tolerance_px, px);
  in.read("outline", "step_tolerance_rel", o.step_tolerance_rel, num);
  in.read("outline", "depth_band_m", o.depth_band_m, "a number (m)");
  in.read("outline", "ground_tolerance_px", o.ground_tolerance_px, px);
  in.read("outline", "ground_tolerance_rel", o.ground_tolerance_rel, num);
  in.read("outline", "static_competition", o.static_competition, flag);
  in.read("outline", "max_hole_invalid_fraction", o.max_hole_invalid_fraction, num);
  in.read("outline", "min_hole_fill_px", o.min_hole_fill_px, integer);
  in.read("outline", "erode_px", o.erode_px, "an integer (px)");
  in.read("outline", "min_pixels", o.min_pixels, "an integer (px)");
  in.read("outline", "min_dynamic_fraction", o.min_dynamic_fraction, num);
  in.read("outline", "min_tracked_for_fraction", o.min_tracked_for_fraction, integer);
  in.read("outline", "aggregate_ratio", o.aggregate_ratio, num);
  in.read("outline", "aggregate_min_px", o.aggregate_min_px, px);
  in.read("outline", "aggregate_min_tracks", o.aggregate_min_tracks, "an integer");
  in.read("outline", "aggregate_multiframe_fraction", o.aggregate_multiframe_fraction, "a number in [0, 1]");
  in.read("outline", "aggregate_multiframe_min_px", o.aggregate_multiframe_min_px, px);
  in.read("outline", "max_height_m", o.max_height_m, "a number (m)");
  in.read("outline", "close_far_m", o.close_far_m, "a number (m)");
  in.read("outline", "left_band_touch_px", o.left_band_touch_px, "an integer (px)");
  in.read("outline", "close_max_disparity_px", o.close_max_disparity_px, "a number (px)");

  in.check_keys("edge_refine", {"band_px", "half_rows", "background_px", "min_disparity_gap_px", "occlusion_cost",
                                "min_gain"});
  EdgeRefineConfig& er = c.edge_refine;
  in.read("edge_refine", "band_px", er.band_px, "an integer (px)");
  in.read("edge_refine", "half_rows", er.half_rows, "an integer (rows)");
  in.read("edge_refine", "background_px", er.background_px, "an integer (px)");
  in.read("edge_refine", "min_disparity_gap_px", er.min_disparity_gap_px, px);
  in.read("edge_refine", "occlusion_cost", er.occlusion_cost, "a number (grey levels)");
  in.read("edge_refine", "min_gain", er.min_gain, "a number (grey levels per px)");

  in.check_keys("photometric", {"enabled", "max_motion_px", "min_gradient", "sample_step_px", "min_samples",
                                "multiframe_max_motion_px", "multiframe_min_disparity_px", "region_inset_px"});
  in.read("photometric", "enabled", c.photometric.enabled, flag);
  in.read("photometric", "max_motion_px", c.photometric.max_motion_px, px);
  in.read("photometric", "min_gradient", c.photometric.min_gradient, "a number (grey levels per px)");
  in.read("photometric", "sample_step_px", c.photometric.sample_step_px, "an integer (px)");
  in.read("photometric", "min_samples", c.photometric.min_samples, "an integer");
  in.read("photometric", "multiframe_max_motion_px", c.photometric.multiframe_max_motion_px, px);
  in.read("photometric", "multiframe_min_disparity_px", c.photometric.multiframe_min_disparity_px, px);
  in.read("photometric", "region_inset_px", c.photometric.region_inset_px, "an integer (px)");

  in.check_keys("motion_carve", {"enabled", "block_px", "sample_step_px", "search_px", "min_gradient", "min_samples",
                                 "max_static_ratio", "min_object_error_dn", "max_static_error_dn", "min_separation_px",
                                 "seed_radius_px"});
  MotionCarveConfig& mc = c.motion_carve;
  in.read("motion_carve", "enabled", mc.enabled, flag);
  in.read("motion_carve", "block_px", mc.block_px, "an integer (px)");
  in.read("motion_carve", "sample_step_px", mc.sample_step_px, "an integer (px)");
  in.read("motion_carve", "search_px", mc.search_px, "an integer (px)");
  in.read("motion_carve", "min_gradient", mc.min_gradient, "a number (grey levels per px)");
  in.read("motion_carve", "min_samples", mc.min_samples, integer);
  in.read("motion_carve", "max_static_ratio", mc.max_static_ratio, num);
  in.read("motion_carve", "min_object_error_dn", mc.min_object_error_dn, "a number (grey levels)");
  in.read("motion_carve", "max_static_error_dn", mc.max_static_error_dn, "a number (grey levels)");
  in.read("motion_carve", "min_separation_px", mc.min_separation_px, px);
  in.read("motion_carve", "seed_radius_px", mc.seed_radius_px, "an integer (px)");

  in.check_keys("band", {"enabled", "strip_px", "max_disparity_px", "max_static_segment_px", "segment_step_px",
                         "border_px", "fast_threshold", "cell_px", "seed_offset_px", "min_seeds", "max_seeds",
                         "nearest_seeds", "evidence_dn", "max_object_error_dn", "edge_fill_px", "reach_px", "close_px", "min_pixels", "min_height_px",
                         "merge_distance_px", "stack_gap_px", "driving_seed_offset_px",
                         "driving_cell_px"});
  BandSegmenterConfig& b = c.band;
  in.read("band", "enabled", b.enabled, flag);
  in.read("band", "strip_px", b.strip_px, "an integer (px)");
  in.read("band", "max_disparity_px", b.max_disparity_px, px);
  in.read("band", "max_static_segment_px", b.max_static_segment_px, px);
  in.read("band", "segment_step_px", b.segment_step_px, px);
  in.read("band", "border_px", b.border_px, "an integer (px)");
  in.read("band", "fast_threshold", b.fast_threshold, "an integer (grey levels)");
  in.read("band", "cell_px", b.cell_px, "an integer (px)");
  in.read("band", "seed_offset_px", b.seed_offset_px, px);
  in.read("band", "min_seeds", b.min_seeds, integer);
  in.read("band", "max_seeds", b.max_seeds, integer);
  in.read("band", "nearest_seeds", b.nearest_seeds, integer);
  in.read("band", "evidence_dn", b.evidence_dn, "a number (grey levels)");
  in.read("band", "max_object_error_dn", b.max_object_error_dn, "a number (grey levels)");
  in.read("band", "edge_fill_px", b.edge_fill_px, "an integer (px)");
  in.read("band", "reach_px", b.reach_px, "an integer (px)");
  in.read("band", "close_px", b.close_px, "an integer (px)");
  in.read("band", "min_pixels", b.min_pixels, "an integer (px)");
  in.read("band", "min_height_px", b.min_height_px, "an integer (px)");
  in.read("band", "merge_distance_px", b.merge_distance_px, "an integer (px)");
  in.read("band", "stack_gap_px", b.stack_gap_px, "an integer (px)");
  in.read("band", "driving_seed_offset_px", b.driving_seed_offset_px, "a number (px)");
  in.read("band", "driving_cell_px", b.driving_cell_px, "an integer (px)");

  in.check_keys("detector", {"use_epipolar_test", "use_depth_test", "full_frame_disparity", "max_rois",
                             "merge_stacked_regions", "split_side_by_side", "mask_dilation_px"});
  in.read("detector", "use_epipolar_test", c.detector.use_epipolar_test, flag);
  in.read("detector", "use_depth_test", c.detector.use_depth_test, flag);
  in.read("detector", "full_frame_disparity", c.detector.full_frame_disparity, flag);
  in.read("detector", "max_rois", c.detector.max_rois, integer);
  in.read("detector", "merge_stacked_regions", c.detector.merge_stacked_regions, flag);
  in.read("detector", "split_side_by_side", c.detector.split_side_by_side, flag);
  in.read("detector", "mask_dilation_px", c.detector.mask_dilation_px, "an integer (px)");

  in.check_keys("roi", {"disparity_margin_px", "scale", "row_step", "row_step_min_area_px", "half_scale_min_area_px",
                        "half_scale_erode_px", "pad_left_border", "speckle_filter", "extend_to_floor",
                        "extend_to_height_m", "extend_max_rounds", "extend_min_rows", "extend_step_m",
                        "extend_static_guard_px"});
  RoiOptions& r = c.roi;
  in.read("roi", "disparity_margin_px", r.disparity_margin_px, px);
  in.read("roi", "scale", r.scale, "1 or 0.5");
  in.read("roi", "row_step", r.row_step, "1 or 2");
  in.read("roi", "row_step_min_area_px", r.row_step_min_area_px, "an integer (px)");
  in.read("roi", "half_scale_min_area_px", r.half_scale_min_area_px, "an integer (px)");
  in.read("roi", "half_scale_erode_px", r.half_scale_erode_px, "an integer (px)");
  in.read("roi", "pad_left_border", r.pad_left_border, flag);
  in.read("roi", "speckle_filter", r.speckle_filter, flag);
  in.read("roi", "extend_to_floor", r.extend_to_floor, flag);
  in.read("roi", "extend_to_height_m", r.extend_to_height_m, "a number (m)");
  in.read("roi", "extend_max_rounds", r.extend_max_rounds, integer);
  in.read("roi", "extend_min_rows", r.extend_min_rows, integer);
  in.read("roi", "extend_step_m", r.extend_step_m, "a number (m)");
  in.read("roi", "extend_static_guard_px", r.extend_static_guard_px, "an integer (px)");

  in.check_keys("densify", {"enabled", "radius_px", "radius_disparity_factor", "max_points", "min_distance_px",
                            "min_seeds", "depth_seed_factor", "extra_tracks", "keep_static", "multiframe_levels",
                            "multiframe_agreement", "multiframe_factor"});
  DensifyOptions& ds = c.densify;
  in.read("densify", "enabled", ds.enabled, flag);
  in.read("densify", "radius_px", ds.radius_px, px);
  in.read("densify", "radius_disparity_factor", ds.radius_disparity_factor, num);
  in.read("densify", "max_points", ds.max_points, integer);
  in.read("densify", "min_distance_px", ds.min_distance_px, px);
  in.read("densify", "min_seeds", ds.min_seeds, integer);
  in.read("densify", "depth_seed_factor", ds.depth_seed_factor, num);
  in.read("densify", "extra_tracks", ds.extra_tracks, integer);
  in.read("densify", "keep_static", ds.keep_static, flag);
  in.read("densify", "multiframe_levels", ds.multiframe_levels, integer);
  in.read("densify", "multiframe_agreement", ds.multiframe_agreement, num);
  in.read("densify", "multiframe_factor", ds.multiframe_factor, num);

  in.check_keys("objects", {"enabled", "continue_min_points", "coast_max_frames", "coast_min_detections",
                            "coast_min_tracks", "coast_min_area_ratio", "growth_max_ratio", "growth_margin"});
  ObjectTrackerOptions& ob = c.objects;
  in.read("objects", "enabled", ob.enabled, flag);
  in.read("objects", "continue_min_points", ob.continue_min_points, integer);
  in.read("objects", "coast_max_frames", ob.coast_max_frames, "an integer (frames)");
  in.read("objects", "coast_min_detections", ob.coast_min_detections, "an integer (frames)");
  in.read("objects", "coast_min_tracks", ob.coast_min_tracks, integer);
  in.read("objects", "coast_min_area_ratio", ob.coast_min_area_ratio, num);
  in.read("objects", "growth_max_ratio", ob.growth_max_ratio, num);
  in.read("objects", "growth_margin", ob.growth_margin, num);

  in.check_keys("band_carry", {"max_frames", "min_tracks", "min_dynamic"});
  in.read("band_carry", "max_frames", c.band_carry.max_frames, "an integer (frames)");
  in.read("band_carry", "min_tracks", c.band_carry.min_tracks, integer);
  in.read("band_carry", "min_dynamic", c.band_carry.min_dynamic, integer);

  in.check_keys("static_carve", {"min_tracks", "max_offset_px", "max_multiframe_px", "min_distance_px"});
  in.read("static_carve", "min_tracks", c.static_carve.min_tracks, integer);
  in.read("static_carve", "max_offset_px", c.static_carve.max_offset_px, px);
  in.read("static_carve", "max_multiframe_px", c.static_carve.max_multiframe_px, px);
  in.read("static_carve", "min_distance_px", c.static_carve.min_distance_px, px);

  in.check_keys("confirm", {"min_box_iou", "below_px", "near_min_disparity_px", "near_min_offset_px", "near_min_px",
                            "near_min_roi_fill"});
  in.read("confirm", "min_box_iou", c.confirm.min_box_iou, num);
  in.read("confirm", "below_px", c.confirm.below_px, "an integer (px)");
  in.read("confirm", "near_min_disparity_px", c.confirm.near_min_disparity_px, px);
  in.read("confirm", "near_min_offset_px", c.confirm.near_min_offset_px, px);
  in.read("confirm", "near_min_px", c.confirm.near_min_px, "an integer (px)");
  in.read("confirm", "near_min_roi_fill", c.confirm.near_min_roi_fill, num);

  c.validate(path);
  return c;
}

}  // namespace agvslam::dynamic
