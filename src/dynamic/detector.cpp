#include "agvslam/dynamic/detector.h"
#include "agvslam/dynamic/median.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "agvslam/core/error.h"

namespace agvslam::dynamic {

namespace {
using Clock = std::chrono::steady_clock;
// Median of v (reordered); -1 for an empty vector.
double median_of(std::vector<float>& v) { return median_in_place(v, -1.0f); }
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

void DetectorOptions::validate(const std::string& source) const {
  auto require = [&](bool ok, const char* field, const char* expected) {
    if (!ok) throw InputError(source, std::string("detector.") + field, expected);
  };
  require(use_epipolar_test || use_depth_test, "use_epipolar_test", "expected at least one of the two tests enabled");
  require(max_rois >= 0 && max_rois <= 256, "max_rois", "expected an integer in [0, 256]");
  require(mask_dilation_px >= 0 && mask_dilation_px <= 64, "mask_dilation_px", "expected an integer in [0, 64] px");
  require(extend_max_rounds >= 0 && extend_max_rounds <= 100, "extend_max_rounds",
          "expected an integer in [0, 100] (0: off)");
  require(extend_min_rows >= 1 && extend_min_rows <= 10000, "extend_min_rows", "expected an integer in [1, 10000]");
  require(extend_step_m > 0 && extend_step_m <= 100, "extend_step_m", "expected a number in (0, 100] m");
  require(extend_static_guard_px >= 0 && extend_static_guard_px <= 10000, "extend_static_guard_px",
          "expected an integer in [0, 10000] px (0: off)");
  require(roi_scale == 1.0 || roi_scale == 0.5, "roi_scale", "expected 1 or 0.5");
  require(roi_row_step == 1 || roi_row_step == 2, "roi_row_step", "expected 1 or 2 (rows per matched row)");
  require(roi_row_step_min_area_px >= 0, "roi_row_step_min_area_px", "expected an integer >= 0 px");
  require(densify_radius_px >= 0 && densify_radius_px <= 500, "densify_radius_px", "expected a number in [0, 500] px");
  require(densify_radius_disparity_factor >= 0 && densify_radius_disparity_factor <= 50, "densify_radius_disparity_factor",
          "expected a number in [0, 50]");
  require(densify_max_points >= 0 && densify_max_points <= 1000, "densify_max_points", "expected an integer in [0, 1000]");
  require(densify_min_distance_px >= 0 && densify_min_distance_px <= 100, "densify_min_distance_px",
          "expected a number in [0, 100] px");
  require(densify_min_seeds >= 1 && densify_min_seeds <= 100, "densify_min_seeds", "expected an integer in [1, 100]");
  require(densify_depth_seed_factor >= 0 && densify_depth_seed_factor <= 100, "densify_depth_seed_factor",
          "expected a number in [0, 100] (0: depth-test points alone never seed)");
  require(densify_extra_tracks >= 0 && densify_extra_tracks <= 10000, "densify_extra_tracks",
          "expected an integer in [0, 10000]");
  require(densify_multiframe_levels >= -1 && densify_multiframe_levels <= 5, "densify_multiframe_levels",
          "expected an integer in [-1, 5] (-1: off)");
  require(densify_multiframe_agreement > 0 && densify_multiframe_agreement <= 2, "densify_multiframe_agreement",
          "expected a number in (0, 2]");
  require(densify_multiframe_factor >= 1 && densify_multiframe_factor <= 20, "densify_multiframe_factor",
          "expected a number in [1, 20]");
  require(continue_min_points >= 1 && continue_min_points <= 1000, "continue_min_points", "expected an integer in [1, 1000]");
  require(coast_max_frames >= 0 && coast_max_frames <= 100, "coast_max_frames", "expected an integer in [0, 100] frames");
  require(coast_min_detections >= 1 && coast_min_detections <= 1000, "coast_min_detections",
          "expected an integer in [1, 1000] frames");
  require(coast_min_tracks >= 1 && coast_min_tracks <= 1000, "coast_min_tracks", "expected an integer in [1, 1000]");
  require(coast_min_area_ratio >= 0 && coast_min_area_ratio <= 1, "coast_min_area_ratio", "expected a number in [0, 1]");
  require(band_carry_max_frames >= 0 && band_carry_max_frames <= 100, "band_carry_max_frames",
          "expected an integer in [0, 100] frames (0: off)");
  require(band_carry_min_tracks >= 1 && band_carry_min_tracks <= 1000, "band_carry_min_tracks",
          "expected an integer in [1, 1000]");
  require(band_carry_min_dynamic >= 0 && band_carry_min_dynamic <= 1000, "band_carry_min_dynamic",
          "expected an integer in [0, 1000]");
  require(growth_max_ratio == 0 || (growth_max_ratio >= 1 && growth_max_ratio <= 100), "growth_max_ratio",
          "expected 0 (off) or a number in [1, 100]");
  require(growth_margin >= 0 && growth_margin <= 2, "growth_margin", "expected a number in [0, 2]");
  require(carve_min_tracks >= 0 && carve_min_tracks <= 1000, "carve_min_tracks", "expected an integer in [0, 1000] (0: off)");
  require(carve_max_offset_px >= 0 && carve_max_offset_px <= 100, "carve_max_offset_px", "expected a number in [0, 100] px");
  require(carve_max_multiframe_px >= 0 && carve_max_multiframe_px <= 100, "carve_max_multiframe_px",
          "expected a number in [0, 100] px");
  require(carve_min_distance_px >= 0 && carve_min_distance_px <= 1000, "carve_min_distance_px",
          "expected a number in [0, 1000] px");
  require(confirm_min_box_iou >= 0 && confirm_min_box_iou <= 1, "confirm_min_box_iou",
          "expected a number in [0, 1] (0: off)");
  require(confirm_below_px >= 0, "confirm_below_px", "expected an integer >= 0 px (0: every object waits)");
  require(confirm_near_min_disparity_px >= 0 && confirm_near_min_disparity_px <= 1024, "confirm_near_min_disparity_px",
          "expected a number in [0, 1024] px");
  require(confirm_near_min_offset_px >= 0 && confirm_near_min_offset_px <= 1000, "confirm_near_min_offset_px",
          "expected a number in [0, 1000] px");
  require(confirm_near_min_px >= 0, "confirm_near_min_px", "expected an integer >= 0 px (0: off)");
  require(confirm_near_min_roi_fill >= 0 && confirm_near_min_roi_fill <= 1, "confirm_near_min_roi_fill",
          "expected a number in [0, 1]");
  require(half_scale_min_area_px >= 0, "half_scale_min_area_px", "expected an integer >= 0 px");
  require(half_scale_erode_px >= 0 && half_scale_erode_px <= 10, "half_scale_erode_px", "expected an integer in [0, 10] px");
  require(extend_to_height_m >= 0 && extend_to_height_m <= 20, "extend_to_height_m", "expected a number in [0, 20] m");
  require(roi_disparity_margin_px >= 0 && roi_disparity_margin_px <= 1024, "roi_disparity_margin_px",
          "expected a number in [0, 1024] px (a large value searches the whole configured range)");
}

std::string DetectorOptions::describe() const {
  char densify_text[400] = "off";
  char widen_text[200] = "off";
  if (extend_max_rounds > 0) {
    std::snprintf(widen_text, sizeof(widen_text),
                  "<= %d times by %.2f m when the outline reaches a side over >= %d rows without a static track within %d px",
                  extend_max_rounds, extend_step_m, extend_min_rows, extend_static_guard_px);
  }
  if (densify) {
    std::snprintf(densify_text, sizeof(densify_text),
                  "<= %d points within %.0f + %.2f d px, %.0f px apart, >= %d seeds (depth-test points alone at >= %.2fx "
                  "its threshold, 0 = never), <= %d tracks beyond the cap, static ones kept %s, multi-frame test %s (%d levels)",
                  densify_max_points, densify_radius_px, densify_radius_disparity_factor, densify_min_distance_px,
                  densify_min_seeds, densify_depth_seed_factor, densify_extra_tracks, densify_keep_static ? "yes" : "no",
                  densify_multiframe_levels >= 0 ? "on" : "off", std::max(0, densify_multiframe_levels));
  }
  char objects_text[640] = "off";
  if (track_objects) {
    char carry_text[120] = "off";
    if (band_carry_max_frames > 0) {
      std::snprintf(carry_text, sizeof(carry_text), "<= %d frames alone, >= %d tracks, >= %d dynamic",
                    band_carry_max_frames, band_carry_min_tracks, band_carry_min_dynamic);
    }
    std::snprintf(objects_text, sizeof(objects_text),
                  "on (>= %d points continue one; after >= %d detections it coasts <= %d frames on >= %d tracks, "
                  ">= %.2f of its area; carried into the left band: %s; an outline grown > %.2fx in a frame is cut to "
                  "its last pixels + %.2f of its size (0: off); an outline holding >= %d static tracks (offset <= %.2f px, "
                  "multi-frame <= %.2f px, >= %.0f px from its dynamic points) loses their cells (0: off))",
                  continue_min_points, coast_min_detections, coast_max_frames, coast_min_tracks, coast_min_area_ratio,
                  carry_text, growth_max_ratio, growth_margin, carve_min_tracks, carve_max_offset_px,
                  carve_max_multiframe_px, carve_min_distance_px);
  }
  char buf[2400];  // the echo runs to ~1500 characters
  std::snprintf(buf, sizeof(buf),
                "detector: epipolar test %s, depth test %s, disparity %s, <= %d ROIs searched up to max point "
                "disparity + %.1f px at scale %.1f, %d row(s) per matched row for ROIs >= %d px (half scale above "
                "%d px, 0 = never, eroded %d px more), speckle filter %s, left border padded %s, ROIs "
                "extended to the floor %s and %.2f m above it, widened %s, side-by-side pieces split %s, stacked regions merged "
                "%s, mask dilation %d px, densification %s, objects over frames %s, reported when their box overlaps "
                "one of the previous frame by IoU >= %.2f (0: always) or they hold >= %d px (0: none) or, near "
                "(points' disparity >= %.1f px), >= %d px (0: none) with their tracks' median offset >= %.2f px, "
                "their box filling >= %.2f of the ROI and not half inside another object's",
                use_epipolar_test ? "on" : "off", use_depth_test ? "on" : "off",
                full_frame_disparity ? "whole frame (debug)" : "points + ROIs", max_rois, roi_disparity_margin_px,
                roi_scale, roi_row_step, roi_row_step_min_area_px, half_scale_min_area_px, half_scale_erode_px,
                roi_speckle_filter ? "on" : "off", pad_left_border ? "on" : "off", extend_to_floor ? "on" : "off",
                extend_to_height_m, widen_text, split_side_by_side ? "on" : "off", merge_stacked_regions ? "on" : "off",
                mask_dilation_px, densify_text, objects_text, confirm_min_box_iou, confirm_below_px,
                confirm_near_min_disparity_px, confirm_near_min_px, confirm_near_min_offset_px, confirm_near_min_roi_fill);
  return buf;
}

void DynamicDetectorConfig::validate(const std::string& source) const {
  features.validate(source);
  tracking.validate(source);
  epipolar.validate(source);
  depth_test.validate(source);
  multiframe.validate(source);
  grouping.validate(source);
  slic.validate(source);
  planes.validate(source);
  boundaries.validate(source);
  regions.validate(source);
  outline.validate(source);
  edge_refine.validate(source);
  photometric.validate(source);
  motion_carve.validate(source);
  band.validate(source);
  detector.validate(source);
}

std::vector<std::string> DynamicDetectorConfig::describe() const {
  return {features.describe(), tracking.describe(),   epipolar.describe(), depth_test.describe(), multiframe.describe(),
          grouping.describe(), slic.describe(),       planes.describe(),   boundaries.describe(),
          regions.describe(),  outline.describe(),     edge_refine.describe(), photometric.describe(), motion_carve.describe(), band.describe(),
          detector.describe()};
}

std::string StageTimings::describe() const {
  char buf[440];
  std::snprintf(buf, sizeof(buf),
                "total %.2f ms: pyramid %.2f, tracking %.2f, point disparity %.2f, epipolar %.2f, depth test %.2f, "
                "multi-frame %.2f, densify %.2f, grouping %.2f, ROI disparity %.2f, SLIC %.2f, planes %.2f, boundaries %.2f, regions %.2f, "
                "motion carve %.2f, band %.2f, features %.2f",
                total_ms, pyramid_ms, tracking_ms, point_disparity_ms, epipolar_ms, depth_test_ms, multiframe_ms, densify_ms, grouping_ms,
                roi_disparity_ms, slic_ms, planes_ms, boundaries_ms, regions_ms, motion_carve_ms, band_ms, features_ms);
  return buf;
}

std::string to_string(OutlineVerdict verdict) {
  switch (verdict) {
    case OutlineVerdict::kKept: return "kept";
    case OutlineVerdict::kNoSeed: return "no seed";
    case OutlineVerdict::kTooSmall: return "too small";
    case OutlineVerdict::kMostlyStaticTracks: return "mostly static tracks";
    case OutlineVerdict::kTooTall: return "too tall";
    case OutlineVerdict::kMovesWithBackground: return "moves with the background";
  }
  return "unknown";
}

int DetectorResult::dynamic_point_count() const {
  int n = 0;
  for (const TrackedPoint& p : points) n += p.dynamic;
  return n;
}

DynamicDetector::DynamicDetector(const StereoCalibration& calibration, const DynamicDetectorConfig& config,
                                 const stereo::StereoConfig& stereo_config)
    : calibration_(calibration),
      config_(config),
      stereo_config_(stereo_config),
      features_(config.features),
      tracker_(config.tracking),
      epipolar_(config.epipolar),
      depth_test_(config.depth_test),
      multiframe_(config.multiframe),
      history_(config.multiframe.max_frames + 1),
      slic_(config.slic),
      slic_half_([&] {
        SlicConfig half = config.slic;
        half.superpixel_size_px = std::max(3, (config.slic.superpixel_size_px + 1) / 2);
        return half;
      }()),
      sgbm_([&] {
        stereo::SgbmConfig c = stereo_config.sgbm;
        if (!config.detector.roi_speckle_filter && !config.detector.full_frame_disparity) c.speckle_window_size = 0;
        return c;
      }()),
      sparse_(stereo_config.sparse),
      check_sparse_([&] {
        stereo::SparseStereoConfig c = stereo_config.sparse;
        c.half_window = std::max(1, config.multiframe.check_half_window);
        c.uniqueness_margin = config.multiframe.check_uniqueness_margin;
        return c;
      }()),
      outliner_(config.outline),
      edge_refiner_(config.edge_refine),
      band_(config.band) {
  config_.validate("DynamicDetectorConfig");
  stereo_config_.validate("StereoConfig");
  if (config_.detector.use_depth_test && !(calibration_.bf() > 0)) {
    throw InputError("StereoCalibration", "baseline_m", "expected a positive focal length and baseline for the depth test");
  }
}

void DynamicDetector::reset() {
  has_previous_ = false;
  last_max_motion_px_ = -1;
  prev_left_.release();
  prev_right_.release();
  prev_pts_.clear();
  prev_disparity_px_.clear();
  history_.clear();
  multiframe_.reset();
  track_object_.clear();
  objects_.clear();
  prev_object_boxes_.clear();
  prev_instances_.release();
}

DetectorResult DynamicDetector::detect(const StereoFrame& frame) {
  DetectorResult result;
  detect(frame, result);
  return result;
}

void DynamicDetector::measure_point_disparities(const StereoFrame& frame, const std::vector<cv::Point2f>& pts,
                                                std::vector<float>& out, const cv::Mat& full_disparity_px) {
  out.assign(pts.size(), 0.0f);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!usable_.empty() && i < usable_.size() && !usable_[i]) continue;
    if (!full_disparity_px.empty()) {
      const int x = static_cast<int>(std::lround(pts[i].x)), y = static_cast<int>(std::lround(pts[i].y));
      if (x >= 0 && y >= 0 && x < full_disparity_px.cols && y < full_disparity_px.rows) {
        out[i] = full_disparity_px.at<float>(y, x);
      }
    } else {
      out[i] = sparse_.match(frame.left, frame.right, pts[i]);
    }
  }
}

void DynamicDetector::detect(const StereoFrame& frame, DetectorResult& result) {
  const auto t_start = Clock::now();
  CV_Assert(frame.left.type() == CV_8UC1 && frame.right.type() == CV_8UC1 && frame.left.size() == frame.right.size());
  const DetectorOptions& opt = config_.detector;
  begin_frame(frame, result);
  StageTimings& tm = result.timings;

  auto t = Clock::now();
  if (opt.full_frame_disparity) {
    sgbm_.compute(frame.left, frame.right, result.full_disparity_px);
  } else {
    result.full_disparity_px.release();
  }
  tm.point_disparity_ms += ms_since(t);

  t = Clock::now();
  tracker_.build_pyramid(frame.left, cur_pyramid_);
  tm.pyramid_ms = ms_since(t);

  if (result.has_previous) {
    track_and_test(frame, result);
    collect_points(result);
    // Points beside the tracks: the left band's driving seeds, and densification around small dynamic groups.
    t = Clock::now();
    if (config_.band.enabled && result.depth.valid && !prev_left_.empty()) add_band_driving_seeds(frame, result);
    tm.band_ms += ms_since(t);
    t = Clock::now();
    if (opt.densify && opt.densify_max_points > 0 && !prev_left_.empty()) densify(frame, result);
    tm.densify_ms = ms_since(t);
    std::vector<DynamicGroup> groups;
    group_dynamic(frame.left.size(), result, groups);
    int next_instance = 1;
    outline_groups(frame, result, groups, next_instance);
    finish_mask(frame, result, next_instance);
  }
  replenish_tracks(frame, result);
  confirm_objects(result);

  std::swap(prev_pyramid_, cur_pyramid_);
  if (opt.densify || config_.photometric.enabled || config_.band.enabled || config_.motion_carve.enabled) {
    frame.left.copyTo(prev_left_);
    frame.right.copyTo(prev_right_);
  }
  has_previous_ = true;
  tm.total_ms = ms_since(t_start);
}

bool DynamicDetector::tracks_objects() const {
  return config_.detector.track_objects && config_.regions.mask_mode == MaskMode::kDisparity;
}

void DynamicDetector::begin_frame(const StereoFrame& frame, DetectorResult& result) {
  const cv::Size size = frame.left.size();
  result.frame_index = frame.index;
  result.t_ns = frame.t_ns;
  // A frame of another size than the previous one (a new camera mode) starts over.
  if (has_previous_ && (prev_pyramid_.empty() || prev_pyramid_.front().size() != size)) reset();
  result.has_previous = has_previous_ && !prev_pts_.empty();
  result.points.clear();
  result.rois.clear();
  result.mask.regions.clear();
  result.mask.image.create(size, CV_8UC1);
  result.mask.image.setTo(0);
  result.mask.instances.create(size, CV_8UC1);
  result.mask.instances.setTo(0);
  result.ground_plane = DisparityPlane{};
  result.epipolar = EpipolarResult{};
  result.depth = DepthTestResult{};
  result.multiframe.valid = false;
  result.multiframe.frames_back = 0;
  result.multiframe.test.dynamic.clear();
  result.band = BandResult{};
  result.band_joined = result.band_objects = 0;
  result.band_driving_seeds = result.band_driving_dynamic = 0;
  result.timings = StageTimings{};
  static_offset_median_px_ = -1;
}

void DynamicDetector::track_and_test(const StereoFrame& frame, DetectorResult& result) {
  const DetectorOptions& opt = config_.detector;
  StageTimings& tm = result.timings;
  // Tracks and their disparity in the current frame.
  auto t = Clock::now();
  result.lk_levels = tracker_.levels_for_motion(last_max_motion_px_);
  tracker_.track(prev_pyramid_, cur_pyramid_, prev_pts_, cur_pts_, tracked_, result.lk_levels);
  // The largest motion among this frame's tracks chooses the next frame's levels (unknown without tracks).
  float max_motion2 = -1;
  for (std::size_t i = 0; i < tracked_.size(); ++i) {
    if (!tracked_[i]) continue;
    const cv::Point2f m = cur_pts_[i] - prev_pts_[i];
    max_motion2 = std::max(max_motion2, m.dot(m));
  }
  last_max_motion_px_ = max_motion2 < 0 ? -1.0 : std::sqrt(static_cast<double>(max_motion2));
  tm.tracking_ms = ms_since(t);
  t = Clock::now();
  usable_ = tracked_;
  measure_point_disparities(frame, cur_pts_, cur_disparity_px_, result.full_disparity_px);
  usable_.clear();
  tm.point_disparity_ms += ms_since(t);

  // The two motion tests.
  t = Clock::now();
  epipolar_.run(prev_pts_, cur_pts_, tracked_, cur_disparity_px_, result.epipolar);
  tm.epipolar_ms = ms_since(t);
  t = Clock::now();
  if (opt.use_depth_test) {
    depth_test_.run(calibration_.left, calibration_.bf(), prev_pts_, prev_disparity_px_, cur_pts_, cur_disparity_px_,
                    tracked_, result.depth);
  }
  tm.depth_test_ms = ms_since(t);
  // The tracks' histories move to this frame; the multi-frame test compares them with an earlier frame.
  t = Clock::now();
  consistent_.assign(prev_pts_.size(), 0);
  if (result.depth.valid) {
    for (std::size_t i = 0; i < consistent_.size(); ++i) {
      const double r_disp = result.depth.disparity_residual_px[i];
      const bool measured = tracked_[i] && result.depth.reprojection_px[i] >= 0 && r_disp >= 0;
      if (!measured) continue;
      if (!result.depth.dynamic[i]) {
        consistent_[i] = TrackHistory::kStepConsistent;
      } else if (!depth_test_.disparity_off(result.depth, r_disp, cur_disparity_px_[i])) {
        consistent_[i] = TrackHistory::kStepStereoOnly;
      }
    }
  }
  history_.next_frame(cur_pts_, cur_disparity_px_, consistent_);
  multiframe_.add_frame(result.depth.T_cur_prev, opt.use_depth_test && result.depth.valid, frame.left);
  if (opt.use_depth_test) {
    multiframe_.run(calibration_.left, calibration_.bf(), history_, tracked_, cur_pyramid_, config_.tracking,
                    result.multiframe);
  } else {
    result.multiframe = MultiFrameResult{};
  }
  // Depth-edge check of the tracks only the multi-frame test flags.
  const MultiFrameTestConfig& mf = config_.multiframe;
  if (result.multiframe.valid && mf.edge_check_px > 0) {
    for (std::size_t i = 0; i < result.multiframe.test.dynamic.size(); ++i) {
      if (!result.multiframe.test.dynamic[i] || result.depth.dynamic.empty() || result.depth.dynamic[i] ||
          (!result.epipolar.dynamic.empty() && result.epipolar.dynamic[i])) {
        continue;
      }
      if (on_depth_edge_or_ambiguous(frame, cur_pts_[i], cur_disparity_px_[i])) result.multiframe.test.dynamic[i] = 0;
    }
  }
  tm.multiframe_ms = ms_since(t);
}

void DynamicDetector::collect_points(DetectorResult& result) {
  const std::size_t n = prev_pts_.size();
  result.points.resize(n);
  dyn_pts_.clear();
  dyn_disp_.clear();
  dyn_index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    TrackedPoint& p = result.points[i];
    p = TrackedPoint{};
    p.prev_px = prev_pts_[i];
    p.cur_px = cur_pts_[i];
    p.prev_disparity_px = prev_disparity_px_[i];
    p.cur_disparity_px = cur_disparity_px_[i];
    p.tracked = tracked_[i] != 0;
    p.age = history_.age(i);
    if (!p.tracked) continue;
    if (result.epipolar.valid) {
      p.d_epi_px = result.epipolar.d_epi_px[i];
      p.t_epi_px = result.epipolar.t_epi_px[i];
      p.dynamic_epipolar = result.epipolar.dynamic[i] != 0;
    }
    if (result.depth.valid) {
      p.reprojection_px = result.depth.reprojection_px[i];
      p.disparity_residual_px = result.depth.disparity_residual_px[i];
      p.dynamic_depth = result.depth.dynamic[i] != 0;
    }
    if (result.multiframe.valid) {
      p.multiframe_px = result.multiframe.test.reprojection_px[i];
      p.multiframe_disparity_residual_px = result.multiframe.test.disparity_residual_px[i];
      p.dynamic_multiframe = result.multiframe.test.dynamic[i] != 0;
    }
    p.dynamic = flagged_by_enabled_tests(p);
    if (p.dynamic) add_dynamic_point(p, static_cast<int>(i));
  }
}

void DynamicDetector::group_dynamic(cv::Size size, DetectorResult& result, std::vector<DynamicGroup>& groups) {
  const DetectorOptions& opt = config_.detector;
  const auto t = Clock::now();
  const bool objects = tracks_objects();
  RoiGroupingConfig grouping = config_.grouping;
  if (objects) grouping.min_points = std::min(grouping.min_points, opt.continue_min_points);
  groups = group_dynamic_points(dyn_pts_, dyn_disp_, size, grouping, calibration_.baseline_m);
  // A group smaller than grouping.min_points is a ROI only when continue_min_points of it belong to one object
  // of the previous frame; each group takes over the object most of its points belong to.
  group_object_.clear();
  {
    std::vector<DynamicGroup> kept;
    for (DynamicGroup& g : groups) {
      int object = -1, votes = 0;
      if (objects) {
        for (int m : g.members) {
          const int idx = dyn_index_[static_cast<std::size_t>(m)];
          const int o = static_cast<std::size_t>(idx) < track_object_.size() ? track_object_[static_cast<std::size_t>(idx)] : -1;
          if (o < 0) continue;
          int count = 0;
          for (int m2 : g.members) {
            const int idx2 = dyn_index_[static_cast<std::size_t>(m2)];
            count += static_cast<std::size_t>(idx2) < track_object_.size() && track_object_[static_cast<std::size_t>(idx2)] == o;
          }
          if (count > votes) {
            votes = count;
            object = o;
          }
        }
      }
      if (static_cast<int>(g.members.size()) < config_.grouping.min_points && votes < opt.continue_min_points) continue;
      if (votes < opt.continue_min_points) object = -1;
      // Groups are largest first: a smaller group continuing an object that a larger one continues already is
      // a part of it (its flood reaches the same connected pixels), not a second object.
      if (object >= 0 && std::find(group_object_.begin(), group_object_.end(), object) != group_object_.end() &&
          static_cast<int>(g.members.size()) < config_.grouping.min_points) {
        continue;
      }
      group_object_.push_back(object);
      kept.push_back(std::move(g));
    }
    groups = std::move(kept);
  }
  if (static_cast<int>(groups.size()) > opt.max_rois) {
    groups.resize(static_cast<std::size_t>(opt.max_rois));
    group_object_.resize(groups.size());
  }
  result.timings.grouping_ms = ms_since(t);
}

void DynamicDetector::outline_groups(const StereoFrame& frame, DetectorResult& result,
                                     std::vector<DynamicGroup>& groups, int& next_instance) {
  const DetectorOptions& opt = config_.detector;
  const cv::Size size = frame.left.size();
  // The floor in disparity space, from the static points below the principal point (ground veto).
  const bool coasting = tracks_objects() && opt.coast_max_frames > 0 && !objects_.empty();
  if ((!groups.empty() || coasting) && (config_.regions.ground_veto || opt.extend_to_floor)) {
    static_pts_.clear();
    static_disp_.clear();
    for (const TrackedPoint& p : result.points) {
      if (!p.tracked || p.dynamic || !(p.cur_disparity_px > 0)) continue;
      static_pts_.push_back(p.cur_px);
      static_disp_.push_back(p.cur_disparity_px);
    }
    result.ground_plane = fit_ground_plane(static_pts_, static_disp_, calibration_.left.cy);
  }

  result.rois.resize(groups.size());
  instance_object_.assign(1, -1);
  instance_near_moving_.assign(1, 0);
  kept_regions_.clear();
  coast_group_.assign(groups.size(), 0);
  for (std::size_t g = 0; g < groups.size(); ++g) outline_group(frame, result, groups, g, next_instance);
  // Objects of earlier frames that no region of this frame continues coast on their own tracks.
  if (coasting) {
    const std::size_t first_coasted = groups.size();
    add_coasting_groups(result, size, groups);
    result.rois.resize(groups.size());
    coast_group_.resize(groups.size(), 1);
    for (std::size_t g = first_coasted; g < groups.size(); ++g) outline_group(frame, result, groups, g, next_instance);
  }
}

void DynamicDetector::outline_group(const StereoFrame& frame, DetectorResult& result,
                                    const std::vector<DynamicGroup>& groups, std::size_t g, int& next_instance) {
  const DetectorOptions& opt = config_.detector;
  const cv::Size size = frame.left.size();
  StageTimings& tm = result.timings;
  auto t = Clock::now();
  RoiSegmentation& seg = result.rois[g];
  const DynamicGroup& group = groups[g];
  seg.coasted = coast_group_[g] != 0;
  seg.roi = group.roi;
  seg.mean_disparity_px = group.mean_disparity_px;
  // Objects stand on the floor: when the group's lowest corner is well above the floor row at the group's
  // disparity (legs without corners), the ROI reaches down to that row so the outline can include them.
  if (opt.extend_to_floor && result.ground_plane.valid && result.ground_plane.b > 0) {
    const DisparityPlane& gp = result.ground_plane;
    const double x_mid = seg.roi.x + 0.5 * seg.roi.width;
    const double d_near = group.mean_disparity_px + config_.grouping.t_disp_px + config_.grouping.t_disp_rel * group.mean_disparity_px;
    const double y_floor = (d_near - gp.c - gp.a * x_mid) / gp.b;
    const int margin = config_.grouping.margin_px;
    const int bottom = std::min(size.height, static_cast<int>(std::ceil(y_floor)) + margin);
    if (bottom > seg.roi.br().y && y_floor > seg.roi.y) seg.roi.height = bottom - seg.roi.y;
    // ... and up to the top of an object of extend_to_height_m standing there (h * d / B px above the floor).
    if (opt.extend_to_height_m > 0 && y_floor > seg.roi.y) {
      const double baseline_m = calibration_.bf() / calibration_.left.fx;
      const int top = std::max(0, static_cast<int>(std::floor(y_floor - opt.extend_to_height_m * group.mean_disparity_px / baseline_m)));
      if (top < seg.roi.y) {
        seg.roi.height += seg.roi.y - top;
        seg.roi.y = top;
      }
    }
  }
  // An object near the left border may reach into the band without stereo matches (x < d): the ROI then
  // starts at the border, so the outline can be completed there (outline.left_band_touch_px).
  if (config_.outline.left_band_touch_px >= 0 && seg.roi.x > 0 && seg.roi.x <= 1.5 * group.mean_disparity_px) {
    seg.roi.width += seg.roi.x;
    seg.roi.x = 0;
  }
  seg.points.clear();
  group_pts_.clear();
  group_disp_.clear();
  for (int m : group.members) {
    const int idx = dyn_index_[static_cast<std::size_t>(m)];
    seg.points.push_back(idx);
    result.points[static_cast<std::size_t>(idx)].group = static_cast<int>(g);
    group_pts_.push_back(dyn_pts_[static_cast<std::size_t>(m)]);
    group_disp_.push_back(dyn_disp_[static_cast<std::size_t>(m)]);
  }
  seg.object_id = group_object_[g];
  if (seg.roi.empty()) return;

  t = Clock::now();
  seg.half_scale = false;
  if (opt.full_frame_disparity) {
    result.full_disparity_px(seg.roi).copyTo(seg.disparity_px);
  } else {
    float max_d = 0;
    for (float dd : group_disp_) max_d = std::max(max_d, dd);
    const bool half = config_.regions.mask_mode == MaskMode::kDisparity && opt.half_scale_min_area_px > 0 &&
                      seg.roi.area() > opt.half_scale_min_area_px;
    seg.half_scale = half || opt.roi_scale != 1.0;
    roi_max_disparity_px_ = static_cast<int>(std::ceil(max_d + opt.roi_disparity_margin_px));
    roi_scale_used_ = half ? 0.5 : opt.roi_scale;
    // Widening strips are matched like their ROI.
    roi_row_step_used_ = seg.roi.area() >= opt.roi_row_step_min_area_px ? opt.roi_row_step : 1;
    roi_disparity(frame, seg.roi, roi_max_disparity_px_, roi_scale_used_, seg.disparity_px);
  }
  tm.roi_disparity_ms += ms_since(t);

  if (config_.regions.mask_mode == MaskMode::kDisparity) {
    // The outline from the ROI's disparity (no SLIC, planes or boundaries).
    t = Clock::now();
    widen_ms_ = 0;
    carve_ms_ = 0;
    outline_region(frame, result, seg, next_instance);
    tm.regions_ms += ms_since(t) - widen_ms_ - carve_ms_;
    tm.motion_carve_ms += carve_ms_;
    tm.roi_disparity_ms += widen_ms_;
    return;
  }

  t = Clock::now();
  if (opt.roi_scale == 1.0) {
    seg.superpixels = slic_.segment(frame.left(seg.roi), seg.labels, &seg.slic);
  } else {
    cv::resize(frame.left(seg.roi), small_grey_, cv::Size(), opt.roi_scale, opt.roi_scale, cv::INTER_AREA);
    seg.superpixels = slic_half_.segment(small_grey_, small_labels_, &seg.slic);
    cv::resize(small_labels_, seg.labels, seg.roi.size(), 0, 0, cv::INTER_NEAREST);
  }
  tm.slic_ms += ms_since(t);

  t = Clock::now();
  fit_superpixel_planes(seg.labels, seg.superpixels, seg.disparity_px, seg.roi.tl(), config_.planes, seg.planes,
                        opt.roi_scale == 1.0 ? 1 : 2);
  tm.planes_ms += ms_since(t);

  t = Clock::now();
  graph_.build(seg.labels, seg.superpixels, seg.roi.tl());
  label_boundaries(graph_, seg.planes, config_.boundaries);
  seg.boundaries = graph_.boundaries();
  tm.boundaries_ms += ms_since(t);

  t = Clock::now();
  static_pts_.clear();
  static_disp_.clear();
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || p.dynamic || !seg.roi.contains(cv::Point(cvRound(p.cur_px.x), cvRound(p.cur_px.y)))) continue;
    static_pts_.push_back(p.cur_px);
    static_disp_.push_back(p.cur_disparity_px);
  }
  const std::vector<char>* moves_with_background = nullptr;
  if (config_.photometric.enabled && result.depth.valid && !prev_left_.empty()) {
    check_superpixel_motion(frame.left, prev_left_, calibration_.left, calibration_.bf(), result.depth.T_cur_prev,
                            seg.labels, seg.roi.tl(), seg.planes, config_.photometric, seg.motion);
    background_flags_.assign(seg.motion.size(), 0);
    for (std::size_t k = 0; k < seg.motion.size(); ++k) background_flags_[k] = seg.motion[k].moves_with_background ? 1 : 0;
    moves_with_background = &background_flags_;
  } else {
    seg.motion.clear();
  }
  seg.region = find_dynamic_region(seg.labels, seg.roi.tl(), graph_, seg.planes, group_pts_, group_disp_,
                                   config_.regions, static_pts_, static_disp_,
                                   result.ground_plane.valid ? &result.ground_plane : nullptr, moves_with_background);
  if (!seg.region.rectangle.empty()) {
    const cv::Rect rect = seg.region.rectangle & cv::Rect(cv::Point(0, 0), size);
    result.mask.regions.push_back(rect);
    region_mask_.create(size, CV_8UC1);
    region_mask_(rect).setTo(0);
    paint_region(seg.region, seg.labels, seg.roi.tl(), config_.regions.mask_mode, region_mask_);
    next_instance = label_region_objects(region_mask_(rect), opt.split_side_by_side, next_instance,
                                  result.mask.instances(rect));
  }
  tm.regions_ms += ms_since(t);
}

void DynamicDetector::finish_mask(const StereoFrame& frame, DetectorResult& result, int& next_instance) {
  const DetectorOptions& opt = config_.detector;
  const bool objects = tracks_objects();
  StageTimings& tm = result.timings;
  carried_.clear();
  if (objects && opt.band_carry_max_frames > 0 && !objects_.empty()) carry_band_masks(result, next_instance);
  if (config_.band.enabled && result.depth.valid && !prev_left_.empty()) {
    const auto t = Clock::now();
    band_prev_.clear();
    band_cur_.clear();
    for (const TrackedPoint& p : result.points) {
      if (!p.tracked || p.cur_px.x >= config_.band.strip_px) continue;
      band_prev_.push_back(p.prev_px);
      band_cur_.push_back(p.cur_px);
    }
    band_.segment(frame.left, prev_left_, cur_pyramid_, prev_pyramid_, tracker_, result.lk_levels, calibration_.left,
                  calibration_.bf(), result.depth.T_cur_prev, result.mask.instances, band_prev_, band_cur_, result.band);
    add_band_regions(result, next_instance);
    tm.band_ms += ms_since(t);
  }
  if (opt.mask_dilation_px > 0 && !result.mask.regions.empty()) {
    const int k = 2 * opt.mask_dilation_px + 1;
    cv::dilate(result.mask.instances, dilated_, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
    dilated_.copyTo(result.mask.instances);
  }
  cv::compare(result.mask.instances, 0, result.mask.image, cv::CMP_GT);
  if (objects) update_objects(result);
  // Each object's pixels, for the next frame's growth check (detector.growth_max_ratio).
  if (objects && opt.growth_max_ratio > 0 && !result.mask.regions.empty()) {
    result.mask.instances.copyTo(prev_instances_);
    prev_instance_object_ = instance_object_;
  } else {
    prev_instances_.release();
  }
}

void DynamicDetector::replenish_tracks(const StereoFrame& frame, DetectorResult& result) {
  const DetectorOptions& opt = config_.detector;
  const cv::Size size = frame.left.size();
  StageTimings& tm = result.timings;
  // The tracks that held continue into the next call (tracking.persistent); this frame's quadtree corners fill
  // the places no track covers.
  auto t = Clock::now();
  const LkTrackerConfig& trk = config_.tracking;
  prev_pts_.clear();
  prev_disparity_px_.clear();
  if (result.has_previous && trk.persistent) {
    keep_.assign(history_.size(), 0);
    const std::size_t n = tracked_.size();
    for (std::size_t i = 0; i < history_.size(); ++i) {
      // Beyond n: densified tracks (all tracked); static ones continue only with densify_keep_static.
      keep_[i] = i < n ? tracked_[i] : (opt.densify_keep_static || result.points[i].dynamic ? 1 : 0);
      if (!keep_[i]) continue;
      cv::Point2f p;
      float d = 0;
      history_.observation(i, 0, p, d);
      prev_pts_.push_back(p);
      prev_disparity_px_.push_back(opt.use_depth_test ? d : 0.0f);
    }
    history_.retain(keep_);
  } else {
    history_.clear();
  }
  if (!result.has_previous) multiframe_.add_frame(SE3d::Identity(), false, frame.left);
  features_.detect(frame.left, corners_);
  new_pts_.clear();
  const float min_d2 = static_cast<float>(trk.min_track_distance_px * trk.min_track_distance_px);
  // The tracks binned in cells of min_track_distance_px: a corner is near a track only in its own or a
  // neighbouring cell.
  const float cell_px = static_cast<float>(std::max(1.0, trk.min_track_distance_px));
  const int cells_x = static_cast<int>(size.width / cell_px) + 1, cells_y = static_cast<int>(size.height / cell_px) + 1;
  auto cell_of = [&](const cv::Point2f& p, int& cx, int& cy) {
    cx = std::clamp(static_cast<int>(p.x / cell_px), 0, cells_x - 1);
    cy = std::clamp(static_cast<int>(p.y / cell_px), 0, cells_y - 1);
  };
  cell_start_.assign(static_cast<std::size_t>(cells_x * cells_y) + 1, 0);
  for (const cv::Point2f& p : prev_pts_) {
    int cx, cy;
    cell_of(p, cx, cy);
    ++cell_start_[static_cast<std::size_t>(cy * cells_x + cx) + 1];
  }
  for (std::size_t k = 1; k < cell_start_.size(); ++k) cell_start_[k] += cell_start_[k - 1];
  cell_fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  cell_points_.resize(prev_pts_.size());
  for (const cv::Point2f& p : prev_pts_) {
    int cx, cy;
    cell_of(p, cx, cy);
    cell_points_[static_cast<std::size_t>(cell_fill_[static_cast<std::size_t>(cy * cells_x + cx)]++)] = p;
  }
  for (const Corner& c : corners_) {
    if (static_cast<int>(prev_pts_.size() + new_pts_.size()) >= trk.max_tracks) break;
    int cx, cy;
    cell_of(c.pt, cx, cy);
    bool near = false;
    for (int y = std::max(0, cy - 1); y <= std::min(cells_y - 1, cy + 1) && !near; ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(cells_x - 1, cx + 1) && !near; ++x) {
        const std::size_t cell = static_cast<std::size_t>(y * cells_x + x);
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1] && !near; ++k) {
          const cv::Point2f e = cell_points_[static_cast<std::size_t>(k)] - c.pt;
          near = e.dot(e) < min_d2;
        }
      }
    }
    if (!near) new_pts_.push_back(c.pt);
  }
  tm.features_ms = ms_since(t);
  t = Clock::now();
  if (opt.use_depth_test) {
    measure_point_disparities(frame, new_pts_, new_disp_, result.full_disparity_px);
  } else {
    new_disp_.assign(new_pts_.size(), 0.0f);
  }
  for (std::size_t i = 0; i < new_pts_.size(); ++i) {
    prev_pts_.push_back(new_pts_[i]);
    prev_disparity_px_.push_back(new_disp_[i]);
    history_.add(new_pts_[i], new_disp_[i]);
  }
  // Each track's object for the next frame: the region it lies in now.
  track_object_.assign(prev_pts_.size(), -1);
  if (opt.track_objects && result.has_previous && !result.mask.regions.empty()) {
    const cv::Mat& inst = result.mask.instances;
    for (std::size_t i = 0; i < prev_pts_.size(); ++i) {
      const cv::Point q(cvRound(prev_pts_[i].x), cvRound(prev_pts_[i].y));
      if (q.x < 0 || q.y < 0 || q.x >= inst.cols || q.y >= inst.rows) continue;
      const int k = inst.at<uint8_t>(q);
      if (k > 0 && static_cast<std::size_t>(k) < instance_object_.size()) track_object_[i] = instance_object_[static_cast<std::size_t>(k)];
    }
  }
  tm.point_disparity_ms += ms_since(t);
}

void DynamicDetector::confirm_objects(DetectorResult& result) {
  result.unconfirmed_objects = 0;
  const DetectorOptions& opt = config_.detector;
  cv::Mat& inst = result.mask.instances;
  // Object pixels lie in the regions' rectangles (grown by the mask dilation): only their union is scanned.
  cv::Rect area;
  for (const cv::Rect& r : result.mask.regions) area |= r;
  const int grow = opt.mask_dilation_px;
  area = cv::Rect(area.x - grow, area.y - grow, area.width + 2 * grow, area.height + 2 * grow) &
         cv::Rect(0, 0, inst.cols, inst.rows);
  // Each object's bounding box and pixel count (instances 1..255).
  object_pixels_.assign(256, 0);
  box_limits_.assign(4 * 256, 0);  // per instance: x0, y0, x1, y1 (inclusive)
  int max_instance = 0;
  if (!result.mask.regions.empty()) {
    for (int y = area.y; y < area.br().y; ++y) {
      const uint8_t* row = inst.ptr<uint8_t>(y);
      for (int x = area.x; x < area.br().x; ++x) {
        const int k = row[x];
        if (k == 0) continue;
        int* b = &box_limits_[4 * static_cast<std::size_t>(k)];
        if (object_pixels_[static_cast<std::size_t>(k)]++ == 0) {
          b[0] = b[2] = x;
          b[1] = b[3] = y;
          max_instance = std::max(max_instance, k);
        } else {
          b[0] = std::min(b[0], x);
          b[2] = std::max(b[2], x);
          b[3] = y;  // rows are scanned in order
        }
      }
    }
  }
  object_boxes_.assign(static_cast<std::size_t>(max_instance) + 1, cv::Rect());
  for (int k = 1; k <= max_instance; ++k) {
    const int* b = &box_limits_[4 * static_cast<std::size_t>(k)];
    if (object_pixels_[static_cast<std::size_t>(k)] > 0) object_boxes_[static_cast<std::size_t>(k)] = cv::Rect(b[0], b[1], b[2] - b[0] + 1, b[3] - b[1] + 1);
  }
  if (opt.confirm_min_box_iou > 0 && max_instance > 0) {
    drop_object_.assign(object_boxes_.size(), 0);
    for (int k = 1; k <= max_instance; ++k) {
      const cv::Rect& b = object_boxes_[static_cast<std::size_t>(k)];
      if (b.empty()) continue;
      const int pixels = object_pixels_[static_cast<std::size_t>(k)];
      bool confirmed = opt.confirm_below_px > 0 && pixels >= opt.confirm_below_px;
      // A near object whose tracks are far off the ego-motion is no flicker of noise: reported at once, unless its
      // box lies half inside another object's (a fragment beside the object it belongs to).
      if (!confirmed && pixels >= opt.confirm_near_min_px && static_cast<std::size_t>(k) < instance_near_moving_.size() &&
          instance_near_moving_[static_cast<std::size_t>(k)] != 0) {
        confirmed = !lies_half_inside_another(object_boxes_, static_cast<std::size_t>(k));
      }
      for (std::size_t i = 0; i < prev_object_boxes_.size() && !confirmed; ++i) {
        const double overlap = (b & prev_object_boxes_[i]).area();
        confirmed = overlap > 0 && overlap >= opt.confirm_min_box_iou * (b.area() + prev_object_boxes_[i].area() - overlap);
      }
      if (!confirmed) {
        drop_object_[static_cast<std::size_t>(k)] = 1;
        ++result.unconfirmed_objects;
      }
    }
    if (result.unconfirmed_objects > 0) {
      for (int y = area.y; y < area.br().y; ++y) {
        uint8_t* row = inst.ptr<uint8_t>(y);
        for (int x = area.x; x < area.br().x; ++x) {
          if (row[x] && drop_object_[row[x]]) row[x] = 0;
        }
      }
      cv::compare(inst, 0, result.mask.image, cv::CMP_GT);
      // The rectangles left without a reported pixel go too.
      auto& regions = result.mask.regions;
      regions.erase(std::remove_if(regions.begin(), regions.end(),
                                   [&](const cv::Rect& r) { return cv::countNonZero(inst(r)) == 0; }),
                    regions.end());
    }
  }
  prev_object_boxes_.clear();
  for (const cv::Rect& b : object_boxes_) {
    if (!b.empty()) prev_object_boxes_.push_back(b);
  }
}

void DynamicDetector::outline_region(const StereoFrame& frame, DetectorResult& result, RoiSegmentation& seg,
                                     int& next_instance) {
  // Competing static seeds (outline.static_competition): confirmed static points only, those that passed the
  // multi-frame test where it ran (its longer baseline sees the slow movers that pass the per-frame tests).
  static_pts_.clear();
  static_disp_.clear();
  if (config_.outline.static_competition) {
    for (const TrackedPoint& p : result.points) {
      if (!p.tracked || p.dynamic || !(p.cur_disparity_px > 0)) continue;
      if (result.multiframe.valid ? p.multiframe_px < 0 : p.reprojection_px < 0) continue;
      if (!seg.roi.contains(cv::Point(cvRound(p.cur_px.x), cvRound(p.cur_px.y)))) continue;
      static_pts_.push_back(p.cur_px);
      static_disp_.push_back(p.cur_disparity_px);
    }
  }
  const auto outline_roi = [&]() {
    seg.outline_stats = outliner_.outline(seg.disparity_px, seg.roi.tl(), group_pts_, group_disp_, static_pts_,
                                          static_disp_, result.ground_plane.valid ? &result.ground_plane : nullptr,
                                          calibration_.bf(), seg.outline);
  };
  outline_roi();
  // An outline cut by the ROI's left or right side: widen the ROI there, match the new strip, outline again.
  const DetectorOptions& dopt = config_.detector;
  for (int round = 0;
       round < dopt.extend_max_rounds && seg.outline_stats.object_pixels > 0 && !dopt.full_frame_disparity; ++round) {
    // Rows with outline in the two outermost columns of each side.
    const int w = seg.outline.cols;
    int rows_left = 0, rows_right = 0;
    for (int y = 0; y < seg.outline.rows; ++y) {
      const uint8_t* row = seg.outline.ptr<uint8_t>(y);
      rows_left += (row[0] || (w > 1 && row[1])) ? 1 : 0;
      rows_right += (row[w - 1] || (w > 1 && row[w - 2])) ? 1 : 0;
    }
    bool widen_left = seg.roi.x > 0 && rows_left >= dopt.extend_min_rows;
    bool widen_right = seg.roi.br().x < frame.left.cols && rows_right >= dopt.extend_min_rows;
    if (!widen_left && !widen_right) break;
    const double d = seg.outline_stats.median_disparity_px > 0 ? seg.outline_stats.median_disparity_px : 8.0;
    const int step = std::max(16, static_cast<int>(std::lround(dopt.extend_step_m * d / calibration_.baseline_m)));
    // A side whose outline holds static tracks near it has flooded a static surface at the object's depth (a wall
    // behind a board, a shelf beside a person), not run into the object's side without corners: not widened.
    if (dopt.extend_static_guard_px > 0) {
      int static_left = 0, static_right = 0;
      for (const TrackedPoint& p : result.points) {
        if (!p.tracked || p.dynamic || p.reprojection_px < 0) continue;
        const cv::Point q(cvRound(p.cur_px.x) - seg.roi.x, cvRound(p.cur_px.y) - seg.roi.y);
        if (q.x < 0 || q.y < 0 || q.x >= w || q.y >= seg.outline.rows || !seg.outline.at<uint8_t>(q)) continue;
        static_left += q.x < dopt.extend_static_guard_px ? 1 : 0;
        static_right += q.x >= w - dopt.extend_static_guard_px ? 1 : 0;
      }
      widen_left = widen_left && static_left == 0;
      widen_right = widen_right && static_right == 0;
      if (!widen_left && !widen_right) break;
    }
    const auto t_widen = Clock::now();
    const int add_left = widen_left ? std::min(step, seg.roi.x) : 0;
    const int add_right = widen_right ? std::min(step, frame.left.cols - seg.roi.br().x) : 0;
    const cv::Rect widened(seg.roi.x - add_left, seg.roi.y, seg.roi.width + add_left + add_right, seg.roi.height);
    widened_disparity_.create(widened.size(), CV_32FC1);
    seg.disparity_px.copyTo(widened_disparity_(cv::Rect(add_left, 0, seg.roi.width, seg.roi.height)));
    if (add_left > 0) {
      roi_disparity(frame, cv::Rect(widened.x, widened.y, add_left, widened.height), roi_max_disparity_px_,
                    roi_scale_used_, strip_disparity_);
      strip_disparity_.copyTo(widened_disparity_(cv::Rect(0, 0, add_left, widened.height)));
    }
    if (add_right > 0) {
      roi_disparity(frame, cv::Rect(seg.roi.br().x, widened.y, add_right, widened.height), roi_max_disparity_px_,
                    roi_scale_used_, strip_disparity_);
      strip_disparity_.copyTo(widened_disparity_(cv::Rect(add_left + seg.roi.width, 0, add_right, widened.height)));
    }
    std::swap(seg.disparity_px, widened_disparity_);
    seg.roi = widened;
    widen_ms_ += ms_since(t_widen);
    outline_roi();
  }
  // Post-processing of the outline; its pixel count is taken again once at the end.
  const bool has_pixels = seg.outline_stats.object_pixels > 0;
  bool reshaped = false;
  if (config_.edge_refine.band_px > 0 && has_pixels && !seg.half_scale) {
    const EdgeRefineStats es = edge_refiner_.refine(frame.left, frame.right, seg.roi, seg.disparity_px, seg.outline);
    reshaped = es.moved > 0;
  }
  const int extra_erode = seg.half_scale ? config_.detector.half_scale_erode_px : 0;
  if (extra_erode > 0 && has_pixels) {
    const int k = 2 * extra_erode + 1;
    cv::erode(seg.outline, reshaped_outline_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
    std::swap(seg.outline, reshaped_outline_);
    reshaped = true;
  }
  const OutlineConfig& occ = config_.outline;
  const double d_med = seg.outline_stats.median_disparity_px;
  if (occ.close_far_m > 0 && d_med > 0 && d_med <= occ.close_max_disparity_px && has_pixels) {
    // close_far_m at depth bf / d spans close_far_m * fx * d / bf = close_far_m * d / B px.
    const int k = std::max(3, 2 * static_cast<int>(std::lround(0.5 * occ.close_far_m * d_med / calibration_.baseline_m)) + 1);
    cv::morphologyEx(seg.outline, reshaped_outline_, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)),
                     cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    std::swap(seg.outline, reshaped_outline_);
    reshaped = true;
  }
  if (occ.left_band_touch_px >= 0 && d_med > 0 && seg.roi.x < d_med && has_pixels) {
    // Rows whose outline starts within left_band_touch_px of the unmatched band x < d_med: filled to the border.
    const int limit = std::min(static_cast<int>(std::ceil(d_med)) - seg.roi.x + occ.left_band_touch_px, seg.outline.cols - 1);
    for (int y = 0; y < seg.outline.rows; ++y) {
      uint8_t* row = seg.outline.ptr<uint8_t>(y);
      int x0 = 0;
      while (x0 <= limit && !row[x0]) ++x0;
      if (x0 > 0 && x0 <= limit) std::fill(row, row + x0, static_cast<uint8_t>(255));
    }
    reshaped = true;
  }
  if (reshaped) seg.outline_stats.object_pixels = cv::countNonZero(seg.outline);
  clamp_growth(result, seg);
  seg.labels.release();
  seg.superpixels = 0;
  seg.planes.clear();
  seg.boundaries.clear();
  seg.motion.clear();
  seg.region = DynamicRegion{};
  seg.outline_motion = SuperpixelMotion{};
  seg.outline_motion_multiframe = SuperpixelMotion{};
  inside_offsets_.clear();
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked) continue;
    const cv::Point q(cvRound(p.cur_px.x) - seg.roi.x, cvRound(p.cur_px.y) - seg.roi.y);
    if (q.x < 0 || q.y < 0 || q.x >= seg.outline.cols || q.y >= seg.outline.rows || !seg.outline.at<uint8_t>(q)) continue;
    ++seg.outline_stats.tracked_inside;
    seg.outline_stats.dynamic_inside += p.dynamic ? 1 : 0;
    seg.outline_stats.multiframe_tested_inside += p.multiframe_px >= 0 ? 1 : 0;
    seg.outline_stats.multiframe_dynamic_inside += p.dynamic_multiframe ? 1 : 0;
    if (p.reprojection_px >= 0) inside_offsets_.push_back(static_cast<float>(p.reprojection_px));
  }
  const OutlineStats& st = seg.outline_stats;
  const OutlineConfig& oc = config_.outline;
  seg.outline_stats.median_offset_px = median_of(inside_offsets_);
  // An outline mostly of static tracks, or (outline.aggregate_min_tracks) one with enough tracks to judge them
  // together, is kept only when its tracks move together (reported as "mostly static tracks" otherwise).
  const bool mostly_static = !seg.coasted && ((st.tracked_inside >= oc.min_tracked_for_fraction &&
                                               st.dynamic_inside < oc.min_dynamic_fraction * st.tracked_inside) ||
                                              (oc.aggregate_min_tracks > 0 && oc.aggregate_ratio > 0 &&
                                               static_cast<int>(inside_offsets_.size()) >= oc.aggregate_min_tracks));
  // ... unless they move together (outline.aggregate_*): most of them off the multi-frame reference, or their median
  // offset against the frame's static tracks' (taken once per frame and only when an outline needs it).
  bool moves_together = mostly_static && tracks_move_together_multiframe(st.multiframe_tested_inside,
                                                                         st.multiframe_dynamic_inside, st.median_offset_px, oc);
  if (mostly_static && !moves_together && oc.aggregate_ratio > 0) {
    if (static_offset_median_px_ < 0) {
      static_offsets_.clear();
      for (const TrackedPoint& p : result.points) {
        if (p.tracked && !p.dynamic && p.reprojection_px >= 0) static_offsets_.push_back(static_cast<float>(p.reprojection_px));
      }
      static_offset_median_px_ = static_offsets_.empty() ? 0.0 : median_of(static_offsets_);
    }
    moves_together = tracks_move_together(st.median_offset_px, static_offset_median_px_, oc);
  }
  int coast_min_pixels = 0;  // a coasted outline: a good part of the object's last one
  if (seg.coasted) {
    const auto ob = std::lower_bound(objects_.begin(), objects_.end(), seg.object_id,
                                     [](const auto& e, int id) { return e.first < id; });
    if (ob != objects_.end() && ob->first == seg.object_id) {
      coast_min_pixels = static_cast<int>(config_.detector.coast_min_area_ratio * ob->second.pixels);
    }
  }
  if (st.object_pixels == 0) {
    seg.outline_verdict = OutlineVerdict::kNoSeed;
  } else if (st.object_pixels < std::max(oc.min_pixels, coast_min_pixels)) {
    seg.outline_verdict = OutlineVerdict::kTooSmall;
  } else if (mostly_static && !moves_together) {
    seg.outline_verdict = OutlineVerdict::kMostlyStaticTracks;
  } else if (oc.max_height_m > 0 && st.median_disparity_px > 0 &&
             cv::boundingRect(seg.outline).height * calibration_.baseline_m / st.median_disparity_px > oc.max_height_m) {
    seg.outline_verdict = OutlineVerdict::kTooTall;
  } else {
    seg.outline_verdict = OutlineVerdict::kKept;
  }
  // A kept outline that flooded a static surface (its clearly static tracks away from the object's points) loses it.
  if (seg.outline_verdict == OutlineVerdict::kKept) {
    carve_static(result, seg);
    carve_motion(frame, result, seg);
    if (seg.outline_stats.object_pixels < oc.min_pixels) seg.outline_verdict = OutlineVerdict::kTooSmall;
  }
  // Photometric confirmation: an outline whose content moved as a static surface would, frame to frame and against
  // the multi-frame reference (where there is one), is dropped.
  const PhotometricCheckConfig& pc = config_.photometric;
  if (seg.outline_verdict == OutlineVerdict::kKept && pc.enabled && result.depth.valid && !prev_left_.empty()) {
    seg.outline_motion = region_motion(frame.left, prev_left_, calibration_.left, calibration_.bf(), result.depth.T_cur_prev,
                                       seg.outline, seg.disparity_px, seg.roi.tl(), pc, pc.max_motion_px);
    bool moves_with_background = seg.outline_motion.apparent_motion_px >= 0 && seg.outline_motion.moves_with_background;
    // A coasted outline has no dynamic point of this frame behind it: it must show its motion frame to frame (a
    // person who has just stopped still differs from the multi-frame reference).
    if (seg.coasted) moves_with_background = !(seg.outline_motion.apparent_motion_px >= 0) || moves_with_background;
    if (moves_with_background && !seg.coasted && result.multiframe.valid &&
        st.median_disparity_px >= pc.multiframe_min_disparity_px) {
      seg.outline_motion_multiframe =
          region_motion(frame.left, result.multiframe.reference_left, calibration_.left, calibration_.bf(),
                        result.multiframe.T_cur_ref, seg.outline, seg.disparity_px, seg.roi.tl(), pc,
                        pc.multiframe_max_motion_px);
      moves_with_background = seg.outline_motion_multiframe.apparent_motion_px >= 0 &&
                              seg.outline_motion_multiframe.moves_with_background;
    }
    if (moves_with_background) seg.outline_verdict = OutlineVerdict::kMovesWithBackground;
  }
  if (seg.outline_verdict != OutlineVerdict::kKept) return;
  // The object over frames: the continued one, unless a region of this frame took it already.
  for (int o : instance_object_) {
    if (o == seg.object_id) seg.object_id = -1;
  }
  if (seg.object_id < 0) seg.object_id = next_object_id_++;
  const cv::Rect local = cv::boundingRect(seg.outline);
  seg.region.rectangle = cv::Rect(local.tl() + seg.roi.tl(), local.size());
  seg.region.started_points = st.object_seeds;
  const cv::Rect rect = seg.region.rectangle & cv::Rect(cv::Point(0, 0), frame.left.size());
  // detector.confirm_near_*: a near outline whose tracks are far off the ego-motion.
  const bool near_moving = dopt.confirm_near_min_px > 0 && seg.mean_disparity_px >= dopt.confirm_near_min_disparity_px &&
                           st.median_offset_px >= dopt.confirm_near_min_offset_px &&
                           static_cast<double>(local.area()) >= dopt.confirm_near_min_roi_fill * seg.roi.area();
  const auto mark_near_moving = [&](int first, int end) {
    const std::size_t size = static_cast<std::size_t>(std::clamp(end, 1, 256));
    if (instance_near_moving_.size() < size) instance_near_moving_.resize(size, 0);
    for (int k = first; k < end && k < 256; ++k) instance_near_moving_[static_cast<std::size_t>(k)] |= near_moving ? 1 : 0;
  };
  // A region stacked on an earlier one of this frame at agreeing depth is a part of that object.
  if (config_.detector.merge_stacked_regions && st.median_disparity_px > 0) {
    const RoiGroupingConfig& gc = config_.grouping;
    const double max_height_m = config_.outline.max_height_m > 0 ? config_.outline.max_height_m : 3.0;
    for (KeptRegion& k : kept_regions_) {
      const double d = std::max(k.median_disparity_px, st.median_disparity_px);
      if (std::abs(k.median_disparity_px - st.median_disparity_px) > gc.t_disp_px + gc.t_disp_rel * d) continue;
      const double px_per_m = std::min(k.median_disparity_px, st.median_disparity_px) / calibration_.baseline_m;
      // Columns overlap by half the narrower, or by a quarter when one lies wholly above the other (a near
      // person's torso and striding legs, split where the thighs have no texture) ...
      const int overlap = std::min(rect.br().x, k.rect.br().x) - std::max(rect.x, k.rect.x);
      const int gap = std::max(rect.y, k.rect.y) - std::min(rect.br().y, k.rect.br().y);
      const int narrower = std::min(rect.width, k.rect.width);
      if (2 * overlap < narrower && !(gap >= 0 && 4 * overlap >= narrower)) continue;
      // ... the vertical gap is within T_s or 0.8 m, and together they are no taller than an object can be.
      if (gap > std::max(gc.a_s_px + gc.b_s * d, 0.8 * px_per_m)) continue;
      if ((k.rect | rect).height > max_height_m * px_per_m) continue;
      result.mask.instances(rect).setTo(static_cast<uint8_t>(std::min(k.instance, 255)),
                                        seg.outline(cv::Rect(rect.tl() - seg.roi.tl(), rect.size())));
      k.rect |= rect;
      result.mask.regions[k.region_index] = k.rect;
      mark_near_moving(k.instance, k.instance + 1);
      seg.object_id = k.instance < static_cast<int>(instance_object_.size())
                          ? instance_object_[static_cast<std::size_t>(k.instance)]
                          : seg.object_id;
      return;
    }
  }
  kept_regions_.push_back({rect, st.median_disparity_px, next_instance, result.mask.regions.size()});
  result.mask.regions.push_back(rect);
  const int first_instance = next_instance;
  next_instance = label_region_objects(seg.outline(cv::Rect(rect.tl() - seg.roi.tl(), rect.size())),
                                       config_.detector.split_side_by_side, next_instance, result.mask.instances(rect));
  instance_object_.resize(static_cast<std::size_t>(std::min(next_instance, 256)), -1);
  for (int k = first_instance; k < next_instance && k < 256; ++k) instance_object_[static_cast<std::size_t>(k)] = seg.object_id;
  mark_near_moving(first_instance, next_instance);
}

bool lies_half_inside_another(const std::vector<cv::Rect>& boxes, std::size_t k) {
  const cv::Rect& b = boxes.at(k);
  for (std::size_t j = 0; j < boxes.size(); ++j) {
    if (j != k && !boxes[j].empty() && 2 * (b & boxes[j]).area() >= b.area()) return true;
  }
  return false;
}

int cut_to_moved_pixels(cv::Mat& outline, cv::Point outline_origin, const cv::Mat& last_pixels, cv::Point last_origin,
                        cv::Point shift_px, cv::Size grow_px) {
  CV_Assert(outline.type() == CV_8UC1 && last_pixels.type() == CV_8UC1);
  cv::Mat allowed = cv::Mat::zeros(outline.size(), CV_8UC1);
  // The last pixels' rectangle, moved, in the outline's coordinates.
  const cv::Rect moved = cv::Rect(last_origin + shift_px - outline_origin, last_pixels.size()) &
                         cv::Rect(0, 0, outline.cols, outline.rows);
  if (!moved.empty()) {
    last_pixels(cv::Rect(moved.tl() + outline_origin - shift_px - last_origin, moved.size())).copyTo(allowed(moved));
  }
  cv::Mat grown;
  cv::dilate(allowed, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * grow_px.width + 1, 2 * grow_px.height + 1)));
  cv::bitwise_and(outline, grown, outline);
  return cv::countNonZero(outline);
}

namespace {
float squared_distance(cv::Point2f a, cv::Point2f b) {
  const cv::Point2f e = a - b;
  return e.x * e.x + e.y * e.y;
}

// True when image point p is nearer to one of static_px than to every point of object_px.
bool nearer_static(cv::Point2f p, const std::vector<cv::Point2f>& object_px, const std::vector<cv::Point2f>& static_px) {
  float nearest_static = std::numeric_limits<float>::max();
  for (const cv::Point2f& q : static_px) nearest_static = std::min(nearest_static, squared_distance(q, p));
  for (const cv::Point2f& q : object_px) {
    if (squared_distance(q, p) <= nearest_static) return false;
  }
  return true;
}

// The points of `points` that can be the nearest one to some pixel of a block centred at c, whose pixels lie within
// half_diagonal of c: within the nearest distance from c plus twice that (triangle inequality, both ways).
void near_block(const std::vector<cv::Point2f>& points, cv::Point2f c, float nearest, float half_diagonal,
                std::vector<cv::Point2f>& out) {
  const float reach = (nearest + 2 * half_diagonal) * (nearest + 2 * half_diagonal);
  for (const cv::Point2f& q : points) {
    if (squared_distance(q, c) <= reach) out.push_back(q);
  }
}

float nearest_distance(const std::vector<cv::Point2f>& points, cv::Point2f c) {
  float best = std::numeric_limits<float>::max();
  for (const cv::Point2f& q : points) best = std::min(best, squared_distance(q, c));
  return std::sqrt(best);
}
}  // namespace

int carve_static_cells(cv::Mat& outline, cv::Point outline_origin, const std::vector<cv::Point2f>& object_px,
                       const std::vector<cv::Point2f>& static_px) {
  CV_Assert(outline.type() == CV_8UC1);
  if (object_px.empty() || static_px.empty() || outline.empty()) return cv::countNonZero(outline);
  // The Voronoi split on a grid of 4x4 blocks first: a distance transform from the cells holding each set's points
  // (O(blocks), whatever the number of points). Blocks with a neighbour decided otherwise (where a cell boundary
  // passes) are then decided pixel by pixel, against the few points that can be nearest there.
  constexpr int kBlock = 4;
  const int gw = (outline.cols + kBlock - 1) / kBlock, gh = (outline.rows + kBlock - 1) / kBlock;
  cv::Mat static_seeds(gh, gw, CV_8UC1, cv::Scalar(255)), object_seeds(gh, gw, CV_8UC1, cv::Scalar(255));
  const auto mark = [&](const std::vector<cv::Point2f>& points, cv::Mat& seeds) {
    for (const cv::Point2f& q : points) {
      const int gx = std::clamp(static_cast<int>(std::floor((q.x - static_cast<float>(outline_origin.x)) / kBlock)), 0, gw - 1);
      const int gy = std::clamp(static_cast<int>(std::floor((q.y - static_cast<float>(outline_origin.y)) / kBlock)), 0, gh - 1);
      seeds.at<uint8_t>(gy, gx) = 0;
    }
  };
  mark(static_px, static_seeds);
  mark(object_px, object_seeds);
  cv::Mat static_distance, object_distance;
  cv::distanceTransform(static_seeds, static_distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(object_seeds, object_distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  enum : uint8_t { kEmpty = 0, kObject = 1, kStatic = 2 };
  std::vector<uint8_t> block(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh), kEmpty);
  for (int by = 0; by < gh; ++by) {
    const float* ds = static_distance.ptr<float>(by);
    const float* dobj = object_distance.ptr<float>(by);
    for (int bx = 0; bx < gw; ++bx) {
      const cv::Rect r = cv::Rect(bx * kBlock, by * kBlock, kBlock, kBlock) & cv::Rect(0, 0, outline.cols, outline.rows);
      bool any = false;
      for (int y = r.y; y < r.br().y && !any; ++y) {
        const uint8_t* row = outline.ptr<uint8_t>(y);
        for (int x = r.x; x < r.br().x; ++x) any = any || row[x] != 0;
      }
      if (any) block[static_cast<std::size_t>(by * gw + bx)] = ds[bx] < dobj[bx] ? kStatic : kObject;
    }
  }
  std::vector<cv::Point2f> near_object, near_static;
  const float half_diagonal = kBlock * 0.7072f;  // >= the 1.5 * sqrt(2) px from a block's centre to its pixels
  int kept = 0;
  for (int by = 0; by < gh; ++by) {
    for (int bx = 0; bx < gw; ++bx) {
      const uint8_t b = block[static_cast<std::size_t>(by * gw + bx)];
      if (b == kEmpty) continue;
      bool uniform = true;
      for (int ny = std::max(0, by - 1); ny <= std::min(gh - 1, by + 1) && uniform; ++ny) {
        for (int nx = std::max(0, bx - 1); nx <= std::min(gw - 1, bx + 1); ++nx) {
          const uint8_t n = block[static_cast<std::size_t>(ny * gw + nx)];
          if (n != kEmpty && n != b) {
            uniform = false;
            break;
          }
        }
      }
      const int y1 = std::min(outline.rows, (by + 1) * kBlock), x1 = std::min(outline.cols, (bx + 1) * kBlock);
      if (!uniform) {
        const cv::Point2f c(static_cast<float>(outline_origin.x) + static_cast<float>(bx * kBlock + x1 - 1) * 0.5f,
                            static_cast<float>(outline_origin.y) + static_cast<float>(by * kBlock + y1 - 1) * 0.5f);
        const float nearest = std::min(nearest_distance(object_px, c), nearest_distance(static_px, c));
        near_object.clear();
        near_static.clear();
        near_block(object_px, c, nearest, half_diagonal, near_object);
        near_block(static_px, c, nearest, half_diagonal, near_static);
      }
      for (int y = by * kBlock; y < y1; ++y) {
        uint8_t* row = outline.ptr<uint8_t>(y);
        for (int x = bx * kBlock; x < x1; ++x) {
          if (!row[x]) continue;
          bool carve = b == kStatic;
          if (!uniform) {
            const cv::Point2f p(static_cast<float>(x + outline_origin.x), static_cast<float>(y + outline_origin.y));
            carve = !near_static.empty() && (near_object.empty() || nearer_static(p, near_object, near_static));
          }
          if (carve) {
            row[x] = 0;
          } else {
            ++kept;
          }
        }
      }
    }
  }
  return kept;
}

void DynamicDetector::carve_static(const DetectorResult& result, RoiSegmentation& seg) {
  const DetectorOptions& opt = config_.detector;
  if (opt.carve_min_tracks <= 0 || seg.coasted || seg.outline_stats.object_pixels == 0 || group_pts_.empty()) return;
  const double min_d2 = opt.carve_min_distance_px * opt.carve_min_distance_px;
  carve_static_px_.clear();
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || p.dynamic || p.reprojection_px < 0 || p.reprojection_px > opt.carve_max_offset_px ||
        p.multiframe_px < 0 || p.multiframe_px > opt.carve_max_multiframe_px) {
      continue;
    }
    const cv::Point q(cvRound(p.cur_px.x) - seg.roi.x, cvRound(p.cur_px.y) - seg.roi.y);
    if (q.x < 0 || q.y < 0 || q.x >= seg.outline.cols || q.y >= seg.outline.rows || !seg.outline.at<uint8_t>(q)) continue;
    bool far_from_object = true;
    for (const cv::Point2f& o : group_pts_) {
      const double dx = o.x - p.cur_px.x, dy = o.y - p.cur_px.y;
      if (dx * dx + dy * dy < min_d2) {
        far_from_object = false;
        break;
      }
    }
    if (far_from_object) carve_static_px_.push_back(p.cur_px);
  }
  if (static_cast<int>(carve_static_px_.size()) < opt.carve_min_tracks) return;
  seg.outline_stats.object_pixels = carve_static_cells(seg.outline, seg.roi.tl(), group_pts_, carve_static_px_);
}

void DynamicDetector::carve_motion(const StereoFrame& frame, const DetectorResult& result, RoiSegmentation& seg) {
  seg.motion_carve = MotionCarveStats{};
  if (!config_.motion_carve.enabled || !result.depth.valid || prev_left_.empty() || seg.outline_stats.object_pixels == 0) return;
  // The object's image motion and its offset from the ego-motion: the medians over its points.
  motion_dx_.clear();
  motion_dy_.clear();
  carve_offsets_.clear();
  for (int idx : seg.points) {
    const TrackedPoint& p = result.points[static_cast<std::size_t>(idx)];
    if (!p.tracked) continue;
    motion_dx_.push_back(p.cur_px.x - p.prev_px.x);
    motion_dy_.push_back(p.cur_px.y - p.prev_px.y);
    if (p.reprojection_px >= 0) carve_offsets_.push_back(static_cast<float>(p.reprojection_px));
  }
  if (motion_dx_.empty() || carve_offsets_.empty()) return;
  const auto t0 = Clock::now();
  const cv::Point2f motion(static_cast<float>(median_of(motion_dx_)), static_cast<float>(median_of(motion_dy_)));
  seg.motion_carve = carve_by_motion(frame.left, prev_left_, calibration_.left, calibration_.bf(), result.depth.T_cur_prev,
                                     motion, median_of(carve_offsets_), group_pts_, seg.disparity_px, seg.roi.tl(),
                                     config_.motion_carve, seg.outline);
  if (seg.motion_carve.pixels_removed > 0) seg.outline_stats.object_pixels = cv::countNonZero(seg.outline);
  carve_ms_ += ms_since(t0);
}

void DynamicDetector::clamp_growth(const DetectorResult& result, RoiSegmentation& seg) {
  const DetectorOptions& opt = config_.detector;
  if (!(opt.growth_max_ratio > 0) || seg.coasted || seg.object_id < 0 || seg.outline_stats.object_pixels == 0 ||
      prev_instances_.size() != result.mask.instances.size()) {
    return;
  }
  const auto ob = std::lower_bound(objects_.begin(), objects_.end(), seg.object_id,
                                   [](const auto& e, int id) { return e.first < id; });
  if (ob == objects_.end() || ob->first != seg.object_id) return;
  const ObjectTrack& last = ob->second;
  const int width = result.mask.instances.cols;
  if (last.detections < 2 || last.coasted > 0 || last.band_frames > 0 || last.pixels <= 0 || last.rect.x <= 2 ||
      last.rect.br().x >= width - 2 || !(seg.outline_stats.object_pixels > opt.growth_max_ratio * last.pixels)) {
    return;
  }
  // An object beside or behind another one may come out from behind it: growth is no evidence there.
  for (const auto& [id, other] : objects_) {
    if (id != seg.object_id && (other.rect & last.rect).area() > 0) return;
  }
  // The object's motion: the median of its tracks' image motion.
  motion_dx_.clear();
  motion_dy_.clear();
  const std::size_t n = std::min(track_object_.size(), result.points.size());
  for (std::size_t i = 0; i < n; ++i) {
    const TrackedPoint& p = result.points[i];
    if (track_object_[i] != seg.object_id || !p.tracked) continue;
    motion_dx_.push_back(p.cur_px.x - p.prev_px.x);
    motion_dy_.push_back(p.cur_px.y - p.prev_px.y);
  }
  if (motion_dx_.empty()) return;
  const cv::Point shift(static_cast<int>(std::lround(median_of(motion_dx_))), static_cast<int>(std::lround(median_of(motion_dy_))));
  const cv::Size grow(static_cast<int>(std::lround(opt.growth_margin * last.rect.width)) + 2,
                      static_cast<int>(std::lround(opt.growth_margin * last.rect.height)) + 2);
  // The object's last pixels: its instances of the previous frame.
  const cv::Rect last_rect = last.rect & cv::Rect(0, 0, prev_instances_.cols, prev_instances_.rows);
  if (last_rect.empty()) return;
  clamp_lut_.create(1, 256, CV_8UC1);
  clamp_lut_.setTo(0);
  for (std::size_t i = 1; i < prev_instance_object_.size(); ++i) {
    if (prev_instance_object_[i] == seg.object_id) clamp_lut_.at<uint8_t>(static_cast<int>(i)) = 255;
  }
  cv::LUT(prev_instances_(last_rect), clamp_lut_, clamp_last_);
  seg.outline_stats.object_pixels = cut_to_moved_pixels(seg.outline, seg.roi.tl(), clamp_last_, last_rect.tl(), shift, grow);
}

void DynamicDetector::add_coasting_groups(const DetectorResult& result, cv::Size image_size,
                                          std::vector<DynamicGroup>& groups) {
  const DetectorOptions& opt = config_.detector;
  const RoiGroupingConfig& gc = config_.grouping;
  const cv::Rect image(cv::Point(0, 0), image_size);
  const std::size_t n = std::min(track_object_.size(), result.points.size());
  for (const auto& [id, ob] : objects_) {
    if (static_cast<int>(groups.size()) >= opt.max_rois) break;
    if (ob.detections < opt.coast_min_detections || ob.coasted >= opt.coast_max_frames) continue;
    if (std::find(instance_object_.begin(), instance_object_.end(), id) != instance_object_.end()) continue;
    // Its tracks: inside its outline in the last frame, tracked into this one, at its depth.
    const double tol = gc.t_disp_px + gc.t_disp_rel * ob.median_disparity_px;
    coast_tracks_.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const TrackedPoint& p = result.points[i];
      if (track_object_[i] != id || !p.tracked || !(p.cur_disparity_px > 0)) continue;
      if (std::abs(p.cur_disparity_px - ob.median_disparity_px) > tol) continue;
      coast_tracks_.push_back(static_cast<int>(i));
    }
    if (static_cast<int>(coast_tracks_.size()) < opt.coast_min_tracks) continue;
    // The last rectangle moved with the median motion of its tracks, and the tracks themselves.
    std::vector<float>& dx = motion_dx_;
    std::vector<float>& dy = motion_dy_;
    dx.clear();
    dy.clear();
    DynamicGroup g;
    float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
    double sum_d = 0;
    for (int i : coast_tracks_) {
      const TrackedPoint& p = result.points[static_cast<std::size_t>(i)];
      dx.push_back(p.cur_px.x - p.prev_px.x);
      dy.push_back(p.cur_px.y - p.prev_px.y);
      x0 = std::min(x0, p.cur_px.x);
      y0 = std::min(y0, p.cur_px.y);
      x1 = std::max(x1, p.cur_px.x);
      y1 = std::max(y1, p.cur_px.y);
      sum_d += p.cur_disparity_px;
      g.members.push_back(static_cast<int>(dyn_pts_.size()));
      add_dynamic_point(p, i);
    }
    const cv::Point shift(cvRound(median_of(dx)), cvRound(median_of(dy)));
    g.mean_disparity_px = sum_d / static_cast<double>(coast_tracks_.size());
    g.bounds = cv::Rect(cv::Point(cvFloor(x0), cvFloor(y0)), cv::Point(cvCeil(x1) + 1, cvCeil(y1) + 1));
    const int margin = gc.margin_px + static_cast<int>(std::lround(gc.margin_disparity_factor * g.mean_disparity_px));
    const cv::Rect moved = (ob.rect + shift) | g.bounds;
    g.roi = cv::Rect(moved.x - margin, moved.y - margin, moved.width + 2 * margin, moved.height + 2 * margin) & image;
    if (g.roi.empty()) continue;
    groups.push_back(std::move(g));
    group_object_.push_back(id);
  }
}

void DynamicDetector::add_band_rect(DetectorResult& result, const cv::Rect& painted, int instance, bool new_region) {
  // A new region, or the band part of the region that holds the instance (regions number their instances in the
  // order they were kept: the last one starting at or below it).
  auto holder = std::find_if(kept_regions_.rbegin(), kept_regions_.rend(), [&](const KeptRegion& k) { return k.instance <= instance; });
  if (new_region || holder == kept_regions_.rend()) {
    result.mask.regions.push_back(painted);
  } else {
    holder->rect |= painted;
    result.mask.regions[holder->region_index] = holder->rect;
  }
}

void DynamicDetector::carry_band_masks(DetectorResult& result, int& next_instance) {
  const DetectorOptions& opt = config_.detector;
  cv::Mat& inst = result.mask.instances;
  const std::size_t n = std::min(track_object_.size(), result.points.size());
  for (const auto& [id, ob] : objects_) {
    if (ob.carry_mask.empty() || ob.band_frames >= opt.band_carry_max_frames) continue;
    // Its tracks held into this frame (in the band without disparity: their image motion alone).
    motion_dx_.clear();
    motion_dy_.clear();
    int dynamic = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const TrackedPoint& p = result.points[i];
      if (track_object_[i] != id || !p.tracked) continue;
      motion_dx_.push_back(p.cur_px.x - p.prev_px.x);
      motion_dy_.push_back(p.cur_px.y - p.prev_px.y);
      dynamic += p.dynamic ? 1 : 0;
    }
    if (static_cast<int>(motion_dx_.size()) < opt.band_carry_min_tracks || dynamic < opt.band_carry_min_dynamic) continue;
    const cv::Point shift(cvRound(median_of(motion_dx_)), cvRound(median_of(motion_dy_)));
    // The band without stereo at the object's depth (and the 2 px beside it where SGBM seldom gives a match).
    const int band = std::min(inst.cols, static_cast<int>(std::ceil(ob.median_disparity_px)) + 2);
    const cv::Rect moved = ob.carry_rect + shift;
    const cv::Rect area = moved & cv::Rect(0, 0, band, inst.rows);
    if (area.empty()) continue;
    // The instance of the region continuing the object in this frame, if any.
    const auto continuing = std::find(instance_object_.begin() + 1, instance_object_.end(), id);
    int instance = continuing == instance_object_.end() ? -1 : static_cast<int>(continuing - instance_object_.begin());
    // ... or, when none does, the region whose pixels its carried mask overlaps most beside the band (the same
    // person continued by a region of another object, e.g. its torso where the legs were the object).
    int carry_id = id;
    if (instance < 0) {
      const cv::Rect beside = moved & cv::Rect(band, 0, std::max(0, inst.cols - band), inst.rows);
      overlap_count_.assign(256, 0);
      int mask_beside = 0;
      for (int y = beside.y; y < beside.br().y; ++y) {
        const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
        const uint8_t* dst = inst.ptr<uint8_t>(y);
        for (int x = beside.x; x < beside.br().x; ++x) {
          if (!src[x]) continue;
          ++mask_beside;
          ++overlap_count_[dst[x]];
        }
      }
      int best = 0, best_count = 0;
      for (int k = 1; k < 256; ++k) {
        if (overlap_count_[static_cast<std::size_t>(k)] > best_count) {
          best = k;
          best_count = overlap_count_[static_cast<std::size_t>(k)];
        }
      }
      if (best > 0 && 10 * best_count >= mask_beside && static_cast<std::size_t>(best) < instance_object_.size() &&
          instance_object_[static_cast<std::size_t>(best)] >= 0) {
        instance = best;
        carry_id = instance_object_[static_cast<std::size_t>(best)];
      }
    }
    int candidates = 0;
    for (int y = area.y; y < area.br().y; ++y) {
      const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
      const uint8_t* dst = inst.ptr<uint8_t>(y);
      for (int x = area.x; x < area.br().x; ++x) candidates += (src[x] && !dst[x]) ? 1 : 0;
    }
    const bool band_only = instance < 0;
    if (candidates == 0 || (band_only && (candidates < config_.outline.min_pixels || next_instance > 255))) continue;
    if (band_only) {
      instance = next_instance++;
      instance_object_.resize(static_cast<std::size_t>(std::min(next_instance, 256)), -1);
      instance_object_[static_cast<std::size_t>(instance)] = id;
    }
    int x0 = area.br().x, y0 = area.br().y, x1 = -1, y1 = -1;
    for (int y = area.y; y < area.br().y; ++y) {
      const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
      uint8_t* dst = inst.ptr<uint8_t>(y);
      for (int x = area.x; x < area.br().x; ++x) {
        if (!src[x] || dst[x]) continue;
        dst[x] = static_cast<uint8_t>(instance);
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
    }
    const cv::Rect painted(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
    add_band_rect(result, painted, instance, band_only);
    carried_.push_back({carry_id, instance, band_only, painted, candidates});
  }
}

void DynamicDetector::add_band_regions(DetectorResult& result, int& next_instance) {
  const BandSegmenterConfig& bc = config_.band;
  cv::Mat& inst = result.mask.instances;
  const cv::Rect image(0, 0, inst.cols, inst.rows);
  const int reach = bc.merge_distance_px;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 2 * reach + 1));
  // Largest first: a person's torso and legs may be two regions (a smooth belt between them), the legs joining the
  // torso's object.
  band_order_.resize(result.band.regions.size());
  for (std::size_t i = 0; i < band_order_.size(); ++i) band_order_[i] = static_cast<int>(i);
  std::sort(band_order_.begin(), band_order_.end(), [&](int a, int b) {
    return result.band.regions[static_cast<std::size_t>(a)].pixels > result.band.regions[static_cast<std::size_t>(b)].pixels;
  });
  for (int index : band_order_) {
    const BandRegion& region = result.band.regions[static_cast<std::size_t>(index)];
    // The object of the mask it touches most (within merge_distance_px) ...
    const cv::Rect around = cv::Rect(region.rect.x - reach, region.rect.y - reach, region.rect.width + 2 * reach,
                                     region.rect.height + 2 * reach) & image;
    cv::Mat reach_mask = cv::Mat::zeros(around.size(), CV_8UC1);
    region.mask.copyTo(reach_mask(region.rect - around.tl()));
    if (reach > 0) cv::dilate(reach_mask, reach_mask, kernel);
    overlap_count_.assign(256, 0);
    for (int y = 0; y < around.height; ++y) {
      const uint8_t* m = reach_mask.ptr<uint8_t>(y);
      const uint8_t* k = inst.ptr<uint8_t>(y + around.y) + around.x;
      for (int x = 0; x < around.width; ++x) {
        if (m[x] && k[x]) ++overlap_count_[k[x]];
      }
    }
    int instance = 0, best_count = 0;
    for (int k = 1; k < 256; ++k) {
      if (overlap_count_[static_cast<std::size_t>(k)] > best_count) {
        instance = k;
        best_count = overlap_count_[static_cast<std::size_t>(k)];
      }
    }
    // ... or the one it is stacked on (above or below within stack_gap_px, over at least half of its columns).
    if (instance == 0 && bc.stack_gap_px > 0) {
      const cv::Rect window = cv::Rect(region.rect.x, region.rect.y - bc.stack_gap_px, region.rect.width,
                                       region.rect.height + 2 * bc.stack_gap_px) & image;
      overlap_count_.assign(256, 0);
      column_seen_.assign(256, -1);
      for (int x = window.x; x < window.br().x; ++x) {
        for (int y = window.y; y < window.br().y; ++y) {
          const int k = inst.at<uint8_t>(y, x);
          if (k == 0 || column_seen_[static_cast<std::size_t>(k)] == x) continue;
          column_seen_[static_cast<std::size_t>(k)] = x;
          ++overlap_count_[static_cast<std::size_t>(k)];
        }
      }
      for (int k = 1; k < 256; ++k) {
        if (2 * overlap_count_[static_cast<std::size_t>(k)] >= region.rect.width && overlap_count_[static_cast<std::size_t>(k)] > best_count) {
          instance = k;
          best_count = overlap_count_[static_cast<std::size_t>(k)];
        }
      }
    }
    const bool alone = instance == 0;
    if (alone) {
      // An object of its own: upright (a person stepping into view, not a shadow on the floor) and large enough.
      if (region.pixels < bc.min_pixels || region.rect.height < bc.min_height_px ||
          region.rect.height < region.rect.width || next_instance > 255) {
        continue;
      }
      instance = next_instance++;
      instance_object_.resize(static_cast<std::size_t>(std::min(next_instance, 256)), -1);
    }
    // Joined to an object, the region adds in each row where the object has pixels only those left of them (its
    // outline ends where stereo does, at x ~ d; right of it the region would add background the object uncovers).
    int x0 = region.rect.br().x, y0 = region.rect.br().y, x1 = -1, y1 = -1;
    for (int y = 0; y < region.rect.height; ++y) {
      const uint8_t* m = region.mask.ptr<uint8_t>(y);
      uint8_t* k = inst.ptr<uint8_t>(y + region.rect.y);
      int limit = region.rect.br().x;
      if (!alone) {
        int first = 0;
        while (first < inst.cols && k[first] != instance) ++first;
        if (first < inst.cols) limit = std::min(limit, first);
      }
      for (int x = region.rect.x; x < limit; ++x) {
        if (!m[x - region.rect.x] || k[x]) continue;
        k[x] = static_cast<uint8_t>(instance);
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y + region.rect.y);
        y1 = std::max(y1, y + region.rect.y);
      }
    }
    if (x1 < 0) continue;
    add_band_rect(result, cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1), instance, alone);
    (alone ? result.band_objects : result.band_joined) += 1;
  }
}

void DynamicDetector::update_objects(const DetectorResult& result) {
  next_objects_.clear();
  std::vector<uint8_t>& own = coast_own_;  // per entry of next_objects_: kept on its own evidence this frame
  own.clear();
  for (const RoiSegmentation& seg : result.rois) {
    if (seg.outline_verdict != OutlineVerdict::kKept || seg.object_id < 0) continue;
    auto it = std::find_if(next_objects_.begin(), next_objects_.end(), [&](const auto& e) { return e.first == seg.object_id; });
    if (it == next_objects_.end()) {
      ObjectTrack ob;
      ob.rect = seg.region.rectangle;
      ob.median_disparity_px = seg.outline_stats.median_disparity_px;
      ob.pixels = seg.outline_stats.object_pixels;
      next_objects_.emplace_back(seg.object_id, ob);
      own.push_back(seg.coasted ? 0 : 1);
    } else {
      it->second.rect |= seg.region.rectangle;
      it->second.pixels += seg.outline_stats.object_pixels;
      own[static_cast<std::size_t>(it - next_objects_.begin())] |= seg.coasted ? 0 : 1;
    }
  }
  // Objects carried into the left band: their band pixels belong to them; one no region continues is kept alone.
  band_only_.assign(next_objects_.size(), 0);
  for (const CarriedObject& c : carried_) {
    auto it = std::find_if(next_objects_.begin(), next_objects_.end(), [&](const auto& e) { return e.first == c.id; });
    if (it == next_objects_.end()) {
      auto prev = std::lower_bound(objects_.begin(), objects_.end(), c.id, [](const auto& e, int id) { return e.first < id; });
      if (prev == objects_.end() || prev->first != c.id) continue;
      ObjectTrack ob;
      ob.rect = c.rect;
      ob.median_disparity_px = prev->second.median_disparity_px;
      ob.pixels = c.pixels;
      next_objects_.emplace_back(c.id, ob);
      own.push_back(0);
      band_only_.push_back(1);
    } else {
      it->second.rect |= c.rect;
      it->second.pixels += c.pixels;
    }
  }
  const DetectorOptions& opt = config_.detector;
  for (std::size_t k = 0; k < next_objects_.size(); ++k) {
    ObjectTrack& ob = next_objects_[k].second;
    auto prev = std::lower_bound(objects_.begin(), objects_.end(), next_objects_[k].first,
                                 [](const auto& e, int id) { return e.first < id; });
    const bool known = prev != objects_.end() && prev->first == next_objects_[k].first;
    ob.detections = (known ? prev->second.detections : 0) + own[k];
    ob.coasted = own[k] ? 0 : (known ? prev->second.coasted : 0) + 1;
    ob.band_frames = band_only_[k] ? (known ? prev->second.band_frames : 0) + 1 : 0;
    // Near the left band (it may reach it by the next frame): its pixels are kept for carrying (with
    // detector.mask_dilation_px > 0 they are the dilated ones, so a carried band part grows by that much per frame,
    // within the band and for at most band_carry_max_frames frames alone).
    if (opt.band_carry_max_frames > 0 && ob.rect.x < 2 * ob.median_disparity_px + 16) {
      const cv::Rect r = ob.rect & cv::Rect(0, 0, result.mask.instances.cols, result.mask.instances.rows);
      ob.carry_rect = r;
      // Its instances' pixels, in one pass through an instance -> 255 / 0 table.
      carry_lut_.create(1, 256, CV_8UC1);
      carry_lut_.setTo(0);
      for (std::size_t i = 1; i < instance_object_.size(); ++i) {
        if (instance_object_[i] == next_objects_[k].first) carry_lut_.at<uint8_t>(static_cast<int>(i)) = 255;
      }
      cv::LUT(result.mask.instances(r), carry_lut_, ob.carry_mask);
    }
  }
  std::sort(next_objects_.begin(), next_objects_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::swap(objects_, next_objects_);
}

void DynamicDetector::roi_disparity(const StereoFrame& frame, const cv::Rect& roi, int max_disparity_px, double scale,
                                    cv::Mat& out) {
  const stereo::SgbmConfig& sc = stereo_config_.sgbm;
  const cv::Rect r = roi & cv::Rect(cv::Point(0, 0), frame.left.size());
  const int row_step = scale == 1.0 ? roi_row_step_used_ : 1;
  // What compute_roi reaches left of the ROI (search range, context margin, half block) and a little more.
  const int reach = sc.min_disparity + sc.num_disparities + sc.roi_margin_px + sc.block_size + 2;
  if (!config_.detector.pad_left_border || r.empty() || r.x >= reach) {
    sgbm_.compute_roi(frame.left, frame.right, r, out, max_disparity_px, scale, row_step);
    return;
  }
  const int pad = reach - r.x;
  // The columns compute_roi reads right of the ROI, and the 16 it may add for a minimum width.
  const int width = std::min(frame.left.cols, r.br().x + sc.roi_margin_px + sc.block_size + sc.num_disparities + 16);
  const cv::Rect strip(0, 0, width, frame.left.rows);
  cv::copyMakeBorder(frame.left(strip), padded_left_, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(frame.right(strip), padded_right_, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  sgbm_.compute_roi(padded_left_, padded_right_, r + cv::Point(pad, 0), out, max_disparity_px, scale, row_step);
}

void DynamicDetector::add_band_driving_seeds(const StereoFrame& frame, DetectorResult& result) {
  band_track_cur_.clear();
  for (const TrackedPoint& p : result.points) {
    if (p.tracked && p.cur_px.x < config_.band.strip_px) band_track_cur_.push_back(p.cur_px);
  }
  if (!band_.driving_seeds(frame.left, cur_pyramid_, prev_pyramid_, tracker_, result.lk_levels, calibration_.left,
                           calibration_.bf(), result.depth.T_cur_prev, band_track_cur_, driving_seeds_)) {
    return;
  }
  result.band_driving_seeds = static_cast<int>(driving_seeds_.size());
  for (const BandSeed& seed : driving_seeds_) {
    // A corner seen now but not by the tracks: its own disparities and the frame's tests, as a densified point.
    const TrackedPoint p = tested_new_point(result, seed.prev_px, seed.cur_px,
                                            sparse_.match(prev_left_, prev_right_, seed.prev_px),
                                            sparse_.match(frame.left, frame.right, seed.cur_px), -1, false);
    if (!p.dynamic) continue;  // the others are not kept as tracks: the quadtree decides where tracks start
    ++result.band_driving_dynamic;
    append_new_point(result, p);
  }
}

void DynamicDetector::densify(const StereoFrame& frame, DetectorResult& result) {
  const DetectorOptions& opt = config_.detector;
  // Seeds: dynamic points with strong evidence. When both tests ran, a point both flag (a track that slid
  // along an edge can fool one of them, rarely both); otherwise every dynamic point.
  const bool both = opt.use_epipolar_test && opt.use_depth_test && result.epipolar.valid && result.depth.valid;
  // ... or one the depth test flags well beyond its threshold: a far person walking along the epipolar lines.
  auto strong_depth = [&](const TrackedPoint& p) {
    return opt.densify_depth_seed_factor > 0 && p.dynamic_depth && p.reprojection_px >= 0 &&
           p.reprojection_px >= opt.densify_depth_seed_factor *
                                    depth_test_.reprojection_threshold_px(result.depth, std::max(0.0f, p.cur_disparity_px));
  };
  seed_pts_.clear();
  seed_disp_.clear();
  seed_index_.clear();
  for (std::size_t k = 0; k < dyn_index_.size(); ++k) {
    const TrackedPoint& p = result.points[static_cast<std::size_t>(dyn_index_[k])];
    if (both && !(p.dynamic_epipolar && p.dynamic_depth) && !p.dynamic_multiframe && !strong_depth(p)) continue;
    seed_pts_.push_back(dyn_pts_[k]);
    seed_disp_.push_back(dyn_disp_[k]);
    seed_index_.push_back(dyn_index_[k]);
  }
  if (static_cast<int>(seed_pts_.size()) < opt.densify_min_seeds) return;
  const int min_points = config_.grouping.min_points;
  RoiGroupingConfig small = config_.grouping;
  small.min_points = opt.densify_min_seeds;
  const std::vector<DynamicGroup> groups =
      group_dynamic_points(seed_pts_, seed_disp_, frame.left.size(), small, calibration_.baseline_m);
  const int b = config_.features.border_px;
  const cv::Rect inner(b, b, frame.left.cols - 2 * b, frame.left.rows - 2 * b);
  const float min_d2 = static_cast<float>(opt.densify_min_distance_px * opt.densify_min_distance_px);
  extra_prev_.clear();
  extra_group_motion_.clear();
  extra_group_valid_.clear();
  for (const DynamicGroup& g : groups) {
    if (static_cast<int>(g.members.size()) >= min_points) continue;  // already a ROI
    // The window around the group's previous positions.
    float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
    // Groups that are ROIs already need no help; count all dynamic points near the seeds for that.
    int near_dynamic = 0;
    for (const cv::Point2f& q : dyn_pts_) {
      for (int m : g.members) {
        const cv::Point2f d = q - seed_pts_[static_cast<std::size_t>(m)];
        if (d.dot(d) <= static_cast<float>(config_.grouping.a_s_px * config_.grouping.a_s_px)) {
          ++near_dynamic;
          break;
        }
      }
    }
    if (near_dynamic >= 2 * min_points) continue;
    for (int m : g.members) {
      const cv::Point2f& p = result.points[static_cast<std::size_t>(seed_index_[static_cast<std::size_t>(m)])].prev_px;
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    const int r = static_cast<int>(std::lround(opt.densify_radius_px + opt.densify_radius_disparity_factor * g.mean_disparity_px));
    const cv::Rect window = cv::Rect(cv::Point(static_cast<int>(x0) - r, static_cast<int>(y0) - r),
                                     cv::Point(static_cast<int>(x1) + r + 1, static_cast<int>(y1) + r + 1)) & inner;
    if (window.width < 8 || window.height < 8) continue;
    keypoints_.clear();
    cv::FAST(prev_left_(window), keypoints_, config_.features.min_threshold, true);
    std::sort(keypoints_.begin(), keypoints_.end(),
              [](const cv::KeyPoint& a, const cv::KeyPoint& c) { return a.response > c.response; });
    const std::size_t first_new = extra_prev_.size();
    // The group's own motion against the multi-frame reference: the median offset of its seeds' reference
    // observations from where static points at their current disparity would have been.
    cv::Point2f group_motion(0, 0);
    bool group_motion_valid = false;
    if (opt.densify_multiframe_levels >= 0 && result.multiframe.valid) {
      const SE3d T_ref_cur = result.multiframe.T_cur_ref.inverse();
      mf_vx_.clear();
      mf_vy_.clear();
      for (int m : g.members) {
        const auto idx = static_cast<std::size_t>(seed_index_[static_cast<std::size_t>(m)]);
        const TrackedPoint& sp = result.points[idx];
        cv::Point2f ref_px;
        float ref_d = 0;
        Eigen::Vector2d pred;
        double depth_m = 0;
        if (idx >= history_.size() || !history_.observation(idx, result.multiframe.frames_back, ref_px, ref_d) ||
            !(sp.cur_disparity_px > 0) ||
            !DepthConsistencyTest::predict(calibration_.left, calibration_.bf(), T_ref_cur, sp.cur_px, sp.cur_disparity_px,
                                           pred, depth_m)) {
          continue;
        }
        mf_vx_.push_back(ref_px.x - static_cast<float>(pred.x()));
        mf_vy_.push_back(ref_px.y - static_cast<float>(pred.y()));
      }
      if (static_cast<int>(mf_vx_.size()) >= opt.densify_min_seeds) {
        group_motion = cv::Point2f(static_cast<float>(median_of(mf_vx_)), static_cast<float>(median_of(mf_vy_)));
        group_motion_valid = true;
      }
    }
    for (const cv::KeyPoint& kp : keypoints_) {
      if (static_cast<int>(extra_prev_.size() - first_new) >= opt.densify_max_points) break;
      const int track_cap = config_.tracking.max_tracks + opt.densify_extra_tracks;
      if (static_cast<int>(prev_pts_.size() + extra_prev_.size()) >= track_cap) break;
      const cv::Point2f p(kp.pt.x + static_cast<float>(window.x), kp.pt.y + static_cast<float>(window.y));
      bool near = false;
      for (const cv::Point2f& q : prev_pts_) {
        const cv::Point2f d = q - p;
        if (d.dot(d) < min_d2) {
          near = true;
          break;
        }
      }
      for (std::size_t k = 0; k < extra_prev_.size() && !near; ++k) {
        const cv::Point2f d = extra_prev_[k] - p;
        near = d.dot(d) < min_d2;
      }
      if (!near) {
        extra_prev_.push_back(p);
        extra_group_motion_.push_back(group_motion);
        extra_group_valid_.push_back(group_motion_valid ? 1 : 0);
      }
    }
  }
  if (extra_prev_.empty()) return;

  tracker_.track(prev_pyramid_, cur_pyramid_, extra_prev_, extra_cur_, extra_ok_, result.lk_levels);
  extra_prev_disp_.assign(extra_prev_.size(), 0.0f);
  extra_cur_disp_.assign(extra_prev_.size(), 0.0f);
  for (std::size_t i = 0; i < extra_prev_.size(); ++i) {
    if (!extra_ok_[i]) continue;
    extra_cur_disp_[i] = sparse_.match(frame.left, frame.right, extra_cur_[i]);
    if (opt.use_depth_test) extra_prev_disp_[i] = sparse_.match(prev_left_, prev_right_, extra_prev_[i]);
  }
  test_densified_multiframe(frame, result);
  for (std::size_t i = 0; i < extra_prev_.size(); ++i) {
    if (!extra_ok_[i]) continue;
    append_new_point(result, tested_new_point(result, extra_prev_[i], extra_cur_[i], extra_prev_disp_[i],
                                              extra_cur_disp_[i], extra_mf_px_[i], extra_mf_[i] != 0));
  }
}

TrackedPoint DynamicDetector::tested_new_point(const DetectorResult& result, const cv::Point2f& prev_px,
                                               const cv::Point2f& cur_px, float prev_disparity_px, float cur_disparity_px,
                                               double multiframe_px, bool dynamic_multiframe) const {
  const DetectorOptions& opt = config_.detector;
  TrackedPoint p;
  p.prev_px = prev_px;
  p.cur_px = cur_px;
  p.prev_disparity_px = prev_disparity_px;
  p.cur_disparity_px = cur_disparity_px;
  p.tracked = true;
  p.densified = true;
  p.age = 1;
  p.dynamic_epipolar = epipolar_.test_track(result.epipolar, p.prev_px, p.cur_px, p.cur_disparity_px, &p.d_epi_px, &p.t_epi_px);
  if (opt.use_depth_test && result.depth.valid) {
    DepthConsistencyTest::residuals(calibration_.left, calibration_.bf(), result.depth.T_cur_prev, p.prev_px,
                                    p.prev_disparity_px, p.cur_px, p.cur_disparity_px, p.reprojection_px,
                                    p.disparity_residual_px);
    p.dynamic_depth = depth_test_.is_dynamic(result.depth, p.reprojection_px, p.disparity_residual_px,
                                             p.cur_disparity_px > 0 ? p.cur_disparity_px : p.prev_disparity_px);
  }
  p.multiframe_px = multiframe_px;
  p.dynamic_multiframe = dynamic_multiframe;
  p.dynamic = flagged_by_enabled_tests(p);
  return p;
}

void DynamicDetector::append_new_point(DetectorResult& result, const TrackedPoint& p) {
  result.points.push_back(p);
  history_.add(p.cur_px, p.cur_disparity_px);
  history_.add_earlier(1, p.prev_px, p.prev_disparity_px);
  if (p.dynamic) add_dynamic_point(p, static_cast<int>(result.points.size() - 1));
}

bool DynamicDetector::flagged_by_enabled_tests(const TrackedPoint& p) const {
  const DetectorOptions& opt = config_.detector;
  return (opt.use_epipolar_test && p.dynamic_epipolar) ||
         (opt.use_depth_test && (p.dynamic_depth || p.dynamic_multiframe));
}

void DynamicDetector::add_dynamic_point(const TrackedPoint& p, int index) {
  dyn_pts_.push_back(p.cur_px);
  dyn_disp_.push_back(p.cur_disparity_px);
  dyn_index_.push_back(index);
}

void DynamicDetector::test_densified_multiframe(const StereoFrame& frame, const DetectorResult& result) {
  const DetectorOptions& opt = config_.detector;
  const std::size_t n = extra_prev_.size();
  extra_mf_.assign(n, 0);
  extra_mf_px_.assign(n, -1.0);
  if (opt.densify_multiframe_levels < 0 || !opt.use_depth_test || !result.multiframe.valid ||
      result.multiframe.reference_left.empty()) {
    return;
  }
  const MultiFrameTestConfig& mf = config_.multiframe;
  const cv::Mat& ref_left = result.multiframe.reference_left;
  const SE3d T_ref_cur = result.multiframe.T_cur_ref.inverse();
  const float w = static_cast<float>(ref_left.cols - 1), h = static_cast<float>(ref_left.rows - 1);
  // Where each point, static at its current disparity, was in the reference frame.
  mf_cur_.clear();
  mf_pred_.clear();
  mf_index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!extra_ok_[i] || !extra_group_valid_[i] || !(extra_cur_disp_[i] >= mf.min_disparity_px)) continue;
    Eigen::Vector2d pred;
    double depth_m = 0;
    if (!DepthConsistencyTest::predict(calibration_.left, calibration_.bf(), T_ref_cur, extra_cur_[i], extra_cur_disp_[i],
                                       pred, depth_m)) {
      continue;
    }
    const cv::Point2f q(static_cast<float>(pred.x()), static_cast<float>(pred.y()));
    if (!(q.x >= 0 && q.y >= 0 && q.x <= w && q.y <= h)) continue;
    mf_cur_.push_back(extra_cur_[i]);
    mf_pred_.push_back(q);
    mf_index_.push_back(static_cast<int>(i));
  }
  if (mf_index_.empty()) return;
  const LkTrackerConfig& trk = config_.tracking;
  const int levels = opt.densify_multiframe_levels;
  const cv::Size win(trk.window_px, trk.window_px);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, trk.max_iterations, trk.epsilon);
  // LK on the part of both images the points and their predictions lie in, with room for the pyramid's reach
  // (OpenCV takes the derivatives of every pyramid level it is given, so whole images would cost ~10x more).
  cv::Rect area = cv::boundingRect(mf_cur_) | cv::boundingRect(mf_pred_);
  const int margin = trk.window_px * (1 << levels);
  area = cv::Rect(area.x - margin, area.y - margin, area.width + 2 * margin, area.height + 2 * margin) &
         cv::Rect(0, 0, ref_left.cols, ref_left.rows);
  const cv::Point2f origin(static_cast<float>(area.x), static_cast<float>(area.y));
  for (std::size_t k = 0; k < mf_cur_.size(); ++k) {
    mf_cur_[k] -= origin;
    mf_pred_[k] -= origin;
  }
  cv::buildOpticalFlowPyramid(frame.left(area), mf_cur_pyramid_, win, levels, false);
  cv::buildOpticalFlowPyramid(ref_left(area), mf_ref_pyramid_, win, levels, false);
  mf_ref_ = mf_pred_;
  cv::calcOpticalFlowPyrLK(mf_cur_pyramid_, mf_ref_pyramid_, mf_cur_, mf_ref_, mf_status_, mf_errors_, win, levels, crit,
                           cv::OPTFLOW_USE_INITIAL_FLOW, trk.min_eigen_threshold);
  mf_back_ = mf_cur_;
  cv::calcOpticalFlowPyrLK(mf_ref_pyramid_, mf_cur_pyramid_, mf_ref_, mf_back_, mf_back_status_, mf_errors_, win, levels,
                           crit, cv::OPTFLOW_USE_INITIAL_FLOW, trk.min_eigen_threshold);
  for (std::size_t k = 0; k < mf_cur_.size(); ++k) {
    mf_cur_[k] += origin;
    mf_pred_[k] += origin;
    mf_ref_[k] += origin;
    mf_back_[k] += origin;
  }
  const float fb2 = static_cast<float>(mf.verify_fb_px * mf.verify_fb_px);
  for (std::size_t k = 0; k < mf_index_.size(); ++k) {
    const auto i = static_cast<std::size_t>(mf_index_[k]);
    const cv::Point2f found = mf_ref_[k];
    const cv::Point2f fb = mf_back_[k] - mf_cur_[k];
    if (!mf_status_[k] || !mf_back_status_[k] || fb.dot(fb) > fb2 ||
        !(found.x >= 0 && found.y >= 0 && found.x <= w && found.y <= h)) {
      continue;
    }
    const float d = extra_cur_disp_[i];
    const cv::Point2f off = found - mf_pred_[k];
    const double offset = std::sqrt(static_cast<double>(off.dot(off)));
    extra_mf_px_[i] = offset;
    const double threshold =
        opt.densify_multiframe_factor * (result.multiframe.test.a_reproj_used_px + mf.b_reproj * d);
    if (!(offset > threshold)) continue;
    // ... and it moved with its group (a static point whose current disparity is wrong, on repetitive racking, is
    // predicted off and LK finds it somewhere else: off by as much, but not the way the group moved).
    const cv::Point2f& gm = extra_group_motion_[i];
    const cv::Point2f dv = off - gm;
    const double group_offset = std::sqrt(static_cast<double>(gm.dot(gm)));
    if (!(group_offset > threshold) ||
        std::sqrt(static_cast<double>(dv.dot(dv))) > std::max(threshold, opt.densify_multiframe_agreement * group_offset)) {
      continue;
    }
    // On an edge-like patch only the offset across the edge counts (multiframe.aperture_ratio).
    if (mf.aperture_ratio > 0) {
      const double across = offset_across_edge(ref_left, found, trk.window_px / 2, calibration_.left, calibration_.bf(),
                                               T_ref_cur, extra_cur_[i], d, mf.aperture_ratio);
      if (across >= 0 && !(across > threshold)) continue;
    }
    // Not on a depth edge (its window mixes two surfaces that move apart over the frames), not an ambiguous match.
    const bool edge = on_depth_edge_or_ambiguous(frame, extra_cur_[i], d);
    if (!edge) extra_mf_[i] = 1;
  }
}

bool DynamicDetector::on_depth_edge_or_ambiguous(const StereoFrame& frame, const cv::Point2f& p, float disparity_px) {
  const MultiFrameTestConfig& mf = config_.multiframe;
  const double tol = mf.edge_tolerance_px + mf.edge_tolerance_rel * disparity_px;
  bool edge = !(disparity_px > 0);
  if (mf.edge_check_px > 0) {
    const auto r = static_cast<float>(mf.edge_check_px);
    const cv::Point2f offsets[4] = {{-r, 0}, {r, 0}, {0, -r}, {0, r}};
    const auto w = static_cast<float>(frame.left.cols - 1), h = static_cast<float>(frame.left.rows - 1);
    for (int k = 0; k < 4 && !edge; ++k) {
      const cv::Point2f q = p + offsets[k];
      if (q.x < 0 || q.y < 0 || q.x > w || q.y > h) continue;
      const float dq = sparse_.match(frame.left, frame.right, q);
      edge = dq > 0 && std::abs(dq - disparity_px) > tol;
    }
  }
  if (!edge && mf.check_half_window > 0) {
    const float dc = check_sparse_.match(frame.left, frame.right, p);
    edge = !(dc > 0) || std::abs(dc - disparity_px) > tol;
  }
  return edge;
}

}  // namespace agvslam::dynamic
