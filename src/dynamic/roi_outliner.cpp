#include "agvslam/dynamic/roi_outliner.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::dynamic {

namespace {
using Clock = std::chrono::steady_clock;
double median_of(std::vector<float>& v) { return median_in_place(v, -1.0f); }

// Whether image point p lies on a pixel of `outline` (its top-left at `origin`).
bool inside_outline(const cv::Mat& outline, cv::Point origin, const cv::Point2f& p) {
  const cv::Point q(cvRound(p.x) - origin.x, cvRound(p.y) - origin.y);
  return q.x >= 0 && q.y >= 0 && q.x < outline.cols && q.y < outline.rows && outline.at<uint8_t>(q) != 0;
}

stereo::SgbmConfig roi_sgbm(const stereo::SgbmConfig& sgbm, const RoiOptions& options, bool full_frame_disparity) {
  stereo::SgbmConfig c = sgbm;
  if (!options.speckle_filter && !full_frame_disparity) c.speckle_window_size = 0;
  return c;
}

SlicConfig halved(const SlicConfig& slic) {
  SlicConfig half = slic;
  half.superpixel_size_px = std::max(3, (slic.superpixel_size_px + 1) / 2);
  return half;
}
}  // namespace

RoiOutliner::RoiOutliner(const RoiOptions& options, const RoiOutlinerContext& context,
                         const StereoCalibration& calibration, const stereo::SgbmConfig& sgbm)
    : options_(options),
      context_(context),
      calibration_(calibration),
      matcher_(roi_sgbm(sgbm, options, context.full_frame_disparity), options.pad_left_border),
      slic_(context.slic),
      slic_half_(halved(context.slic)),
      outliner_(context.outline),
      edge_refiner_(context.edge_refine) {}

void RoiOutliner::place_roi(const DynamicGroup& group, const DisparityPlane& ground, cv::Size image_size,
                            cv::Rect& roi) const {
  // Objects stand on the floor: when the group's lowest corner is well above the floor row at the group's
  // disparity (legs without corners), the ROI reaches down to that row so the outline can include them.
  if (options_.extend_to_floor && ground.valid && ground.b > 0) {
    const RoiGroupingConfig& gc = context_.grouping;
    const double x_mid = roi.x + 0.5 * roi.width;
    const double d_near = group.mean_disparity_px + gc.t_disp_px + gc.t_disp_rel * group.mean_disparity_px;
    const double y_floor = (d_near - ground.c - ground.a * x_mid) / ground.b;
    const int bottom = std::min(image_size.height, static_cast<int>(std::ceil(y_floor)) + gc.margin_px);
    if (bottom > roi.br().y && y_floor > roi.y) roi.height = bottom - roi.y;
    // ... and up to the top of an object of extend_to_height_m standing there (h * d / B px above the floor).
    if (options_.extend_to_height_m > 0 && y_floor > roi.y) {
      const double baseline_m = calibration_.bf() / calibration_.left.fx;
      const int top = std::max(0, static_cast<int>(std::floor(y_floor - options_.extend_to_height_m *
                                                                            group.mean_disparity_px / baseline_m)));
      if (top < roi.y) {
        roi.height += roi.y - top;
        roi.y = top;
      }
    }
  }
  // An object near the left border may reach into the band without stereo matches (x < d): the ROI then
  // starts at the border, so the outline can be completed there (outline.left_band_touch_px).
  if (context_.outline.left_band_touch_px >= 0 && roi.x > 0 && roi.x <= 1.5 * group.mean_disparity_px) {
    roi.width += roi.x;
    roi.x = 0;
  }
}

RoiOutliner::RoiMatch RoiOutliner::match_roi(const StereoFrame& frame, const DetectorResult& result,
                                             RoiSegmentation& seg) {
  RoiMatch match;
  seg.half_scale = false;
  if (context_.full_frame_disparity) {
    result.full_disparity_px(seg.roi).copyTo(seg.disparity_px);
    return match;
  }
  float max_d = 0;
  for (float dd : group_disp_) max_d = std::max(max_d, dd);
  const bool half = context_.regions.mask_mode == MaskMode::kDisparity && options_.half_scale_min_area_px > 0 &&
                    seg.roi.area() > options_.half_scale_min_area_px;
  seg.half_scale = half || options_.scale != 1.0;
  match.max_disparity_px = static_cast<int>(std::ceil(max_d + options_.disparity_margin_px));
  match.scale = half ? 0.5 : options_.scale;
  match.row_step = seg.roi.area() >= options_.row_step_min_area_px ? options_.row_step : 1;
  matcher_.match(frame, seg.roi, match.max_disparity_px, match.scale, match.row_step, seg.disparity_px);
  return match;
}

void RoiOutliner::outline_group(const StereoFrame& frame, const cv::Mat& prev_left, const DynamicGroup& group,
                                int group_index, int object_id, bool coasted, const DynamicPoints& dynamic,
                                ObjectTracker& objects, FrameRegions& regions, RoiSegmentation& seg,
                                DetectorResult& result) {
  StageTimings& tm = result.timings;
  seg.coasted = coasted;
  seg.roi = group.roi;
  seg.mean_disparity_px = group.mean_disparity_px;
  place_roi(group, result.ground_plane, frame.left.size(), seg.roi);
  seg.points.clear();
  group_pts_.clear();
  group_disp_.clear();
  for (int m : group.members) {
    const int idx = dynamic.index[static_cast<std::size_t>(m)];
    seg.points.push_back(idx);
    result.points[static_cast<std::size_t>(idx)].group = group_index;
    group_pts_.push_back(dynamic.px[static_cast<std::size_t>(m)]);
    group_disp_.push_back(dynamic.disparity_px[static_cast<std::size_t>(m)]);
  }
  seg.object_id = object_id;
  if (seg.roi.empty()) return;

  auto t = Clock::now();
  const RoiMatch match = match_roi(frame, result, seg);
  tm.roi_disparity_ms += ms_since(t);

  if (context_.regions.mask_mode != MaskMode::kDisparity) {
    outline_by_superpixels(frame, prev_left, regions, seg, result);
    return;
  }
  t = Clock::now();
  OutlineTimes times;
  outline_by_disparity(frame, prev_left, objects, regions, match, seg, result, times);
  tm.regions_ms += ms_since(t) - times.widen_ms - times.carve_ms;
  tm.motion_carve_ms += times.carve_ms;
  tm.roi_disparity_ms += times.widen_ms;
}

void RoiOutliner::collect_static_seeds(const DetectorResult& result, const cv::Rect& roi) {
  // Confirmed static points only: those that passed the multi-frame test where it ran (its longer baseline sees the
  // slow movers that pass the per-frame tests).
  static_pts_.clear();
  static_disp_.clear();
  if (!context_.outline.static_competition) return;
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || p.dynamic || !(p.cur_disparity_px > 0)) continue;
    if (result.multiframe.valid ? p.multiframe_px < 0 : p.reprojection_px < 0) continue;
    if (!roi.contains(cv::Point(cvRound(p.cur_px.x), cvRound(p.cur_px.y)))) continue;
    static_pts_.push_back(p.cur_px);
    static_disp_.push_back(p.cur_disparity_px);
  }
}

void RoiOutliner::outline_roi(const StereoFrame& frame, const DetectorResult& result, RoiSegmentation& seg) {
  seg.outline_stats = outliner_.outline(seg.disparity_px, seg.roi.tl(), group_pts_, group_disp_, static_pts_,
                                        static_disp_, result.ground_plane.valid ? &result.ground_plane : nullptr,
                                        calibration_.bf(), seg.outline, frame.left(seg.roi));
}

bool RoiOutliner::sides_to_widen(const StereoFrame& frame, const DetectorResult& result, const RoiSegmentation& seg,
                                 bool& left, bool& right) const {
  // Rows with outline in the two outermost columns of each side.
  const int w = seg.outline.cols;
  int rows_left = 0, rows_right = 0;
  for (int y = 0; y < seg.outline.rows; ++y) {
    const uint8_t* row = seg.outline.ptr<uint8_t>(y);
    rows_left += (row[0] || (w > 1 && row[1])) ? 1 : 0;
    rows_right += (row[w - 1] || (w > 1 && row[w - 2])) ? 1 : 0;
  }
  left = seg.roi.x > 0 && rows_left >= options_.extend_min_rows;
  right = seg.roi.br().x < frame.left.cols && rows_right >= options_.extend_min_rows;
  if (!left && !right) return false;
  // A side whose outline holds static tracks near it has flooded a static surface at the object's depth (a wall
  // behind a board, a shelf beside a person), not run into the object's side without corners: not widened.
  const int guard = options_.extend_static_guard_px;
  if (guard <= 0) return true;
  int static_left = 0, static_right = 0;
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || p.dynamic || p.reprojection_px < 0 || !inside_outline(seg.outline, seg.roi.tl(), p.cur_px))
      continue;
    const int x = cvRound(p.cur_px.x) - seg.roi.x;
    static_left += x < guard ? 1 : 0;
    static_right += x >= w - guard ? 1 : 0;
  }
  left = left && static_left == 0;
  right = right && static_right == 0;
  return left || right;
}

void RoiOutliner::widen(const StereoFrame& frame, const RoiMatch& match, bool left, bool right, RoiSegmentation& seg) {
  const double d = seg.outline_stats.median_disparity_px > 0 ? seg.outline_stats.median_disparity_px : 8.0;
  const int step = std::max(16, static_cast<int>(std::lround(options_.extend_step_m * d / calibration_.baseline_m)));
  const int add_left = left ? std::min(step, seg.roi.x) : 0;
  const int add_right = right ? std::min(step, frame.left.cols - seg.roi.br().x) : 0;
  const cv::Rect widened(seg.roi.x - add_left, seg.roi.y, seg.roi.width + add_left + add_right, seg.roi.height);
  widened_disparity_.create(widened.size(), CV_32FC1);
  seg.disparity_px.copyTo(widened_disparity_(cv::Rect(add_left, 0, seg.roi.width, seg.roi.height)));
  if (add_left > 0) {
    matcher_.match(frame, cv::Rect(widened.x, widened.y, add_left, widened.height), match.max_disparity_px, match.scale,
                   match.row_step, strip_disparity_);
    strip_disparity_.copyTo(widened_disparity_(cv::Rect(0, 0, add_left, widened.height)));
  }
  if (add_right > 0) {
    matcher_.match(frame, cv::Rect(seg.roi.br().x, widened.y, add_right, widened.height), match.max_disparity_px,
                   match.scale, match.row_step, strip_disparity_);
    strip_disparity_.copyTo(widened_disparity_(cv::Rect(add_left + seg.roi.width, 0, add_right, widened.height)));
  }
  std::swap(seg.disparity_px, widened_disparity_);
  seg.roi = widened;
}

void RoiOutliner::reshape(const StereoFrame& frame, RoiSegmentation& seg) {
  // Its pixel count is taken again once at the end.
  if (seg.outline_stats.object_pixels <= 0) return;
  bool reshaped = false;
  if (context_.edge_refine.band_px > 0 && !seg.half_scale) {
    const EdgeRefineStats es = edge_refiner_.refine(frame.left, frame.right, seg.roi, seg.disparity_px, seg.outline);
    reshaped = es.moved > 0;
  }
  const int extra_erode = seg.half_scale ? options_.half_scale_erode_px : 0;
  if (extra_erode > 0) {
    const int k = 2 * extra_erode + 1;
    cv::erode(seg.outline, reshaped_outline_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
    std::swap(seg.outline, reshaped_outline_);
    reshaped = true;
  }
  const OutlineConfig& oc = context_.outline;
  const double d_med = seg.outline_stats.median_disparity_px;
  if (oc.close_far_m > 0 && d_med > 0 && d_med <= oc.close_max_disparity_px) {
    // close_far_m at depth bf / d spans close_far_m * fx * d / bf = close_far_m * d / B px.
    const int k =
        std::max(3, 2 * static_cast<int>(std::lround(0.5 * oc.close_far_m * d_med / calibration_.baseline_m)) + 1);
    cv::morphologyEx(seg.outline, reshaped_outline_, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)), cv::Point(-1, -1), 1,
                     cv::BORDER_CONSTANT, cv::Scalar(0));
    std::swap(seg.outline, reshaped_outline_);
    reshaped = true;
  }
  if (oc.left_band_touch_px >= 0 && d_med > 0 && seg.roi.x < d_med) {
    // Rows whose outline starts within left_band_touch_px of the unmatched band x < d_med: filled to the border.
    const int limit =
        std::min(static_cast<int>(std::ceil(d_med)) - seg.roi.x + oc.left_band_touch_px, seg.outline.cols - 1);
    for (int y = 0; y < seg.outline.rows; ++y) {
      uint8_t* row = seg.outline.ptr<uint8_t>(y);
      int x0 = 0;
      while (x0 <= limit && !row[x0]) ++x0;
      if (x0 > 0 && x0 <= limit) std::fill(row, row + x0, static_cast<uint8_t>(255));
    }
    reshaped = true;
  }
  if (reshaped) seg.outline_stats.object_pixels = cv::countNonZero(seg.outline);
}

void RoiOutliner::count_tracks_inside(const DetectorResult& result, RoiSegmentation& seg) {
  inside_offsets_.clear();
  OutlineStats& st = seg.outline_stats;
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || !inside_outline(seg.outline, seg.roi.tl(), p.cur_px)) continue;
    ++st.tracked_inside;
    st.dynamic_inside += p.dynamic ? 1 : 0;
    st.multiframe_tested_inside += p.multiframe_px >= 0 ? 1 : 0;
    st.multiframe_dynamic_inside += p.dynamic_multiframe ? 1 : 0;
    if (p.reprojection_px >= 0) inside_offsets_.push_back(static_cast<float>(p.reprojection_px));
  }
  st.median_offset_px = median_of(inside_offsets_);
}

OutlineVerdict RoiOutliner::judge(const DetectorResult& result, const ObjectTracker& objects,
                                  const RoiSegmentation& seg) {
  const OutlineStats& st = seg.outline_stats;
  const OutlineConfig& oc = context_.outline;
  // An outline mostly of static tracks, or (outline.aggregate_min_tracks) one with enough tracks to judge them
  // together, is kept only when its tracks move together (reported as "mostly static tracks" otherwise).
  const bool mostly_static = !seg.coasted && ((st.tracked_inside >= oc.min_tracked_for_fraction &&
                                               st.dynamic_inside < oc.min_dynamic_fraction * st.tracked_inside) ||
                                              (oc.aggregate_min_tracks > 0 && oc.aggregate_ratio > 0 &&
                                               static_cast<int>(inside_offsets_.size()) >= oc.aggregate_min_tracks));
  // ... unless they move together (outline.aggregate_*): most of them off the multi-frame reference, or their median
  // offset against the frame's static tracks' (taken once per frame and only when an outline needs it).
  bool moves_together =
      mostly_static && tracks_move_together_multiframe(st.multiframe_tested_inside, st.multiframe_dynamic_inside,
                                                       st.median_offset_px, oc);
  if (mostly_static && !moves_together && oc.aggregate_ratio > 0) {
    if (static_offset_median_px_ < 0) {
      static_offsets_.clear();
      for (const TrackedPoint& p : result.points) {
        if (p.tracked && !p.dynamic && p.reprojection_px >= 0)
          static_offsets_.push_back(static_cast<float>(p.reprojection_px));
      }
      static_offset_median_px_ = static_offsets_.empty() ? 0.0 : median_of(static_offsets_);
    }
    moves_together = tracks_move_together(st.median_offset_px, static_offset_median_px_, oc);
  }
  // A coasted outline must keep a good part of the object's last one.
  const int coast_min_pixels = seg.coasted ? objects.coast_min_pixels(seg.object_id) : 0;
  if (st.object_pixels == 0) return OutlineVerdict::kNoSeed;
  if (st.object_pixels < std::max(oc.min_pixels, coast_min_pixels)) return OutlineVerdict::kTooSmall;
  if (mostly_static && !moves_together) return OutlineVerdict::kMostlyStaticTracks;
  if (oc.max_height_m > 0 && st.median_disparity_px > 0 &&
      cv::boundingRect(seg.outline).height * calibration_.baseline_m / st.median_disparity_px > oc.max_height_m) {
    return OutlineVerdict::kTooTall;
  }
  return OutlineVerdict::kKept;
}

void RoiOutliner::carve(const StereoFrame& frame, const cv::Mat& prev_left, const DetectorResult& result,
                        RoiSegmentation& seg, OutlineTimes& times) {
  if (context_.static_carve.min_tracks > 0 && !seg.coasted && seg.outline_stats.object_pixels != 0 &&
      !group_pts_.empty()) {
    const int kept = carve_static_tracks(context_.static_carve, result.points, group_pts_, seg.roi.tl(), seg.outline,
                                         carve_static_px_);
    if (kept >= 0) seg.outline_stats.object_pixels = kept;
  }
  seg.motion_carve = MotionCarveStats{};
  if (!context_.motion_carve.enabled || !result.depth.valid || prev_left.empty() ||
      seg.outline_stats.object_pixels == 0) {
    return;
  }
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
  seg.motion_carve = carve_by_motion(frame.left, prev_left, calibration_.left, calibration_.bf(),
                                     result.depth.T_cur_prev, motion, median_of(carve_offsets_), group_pts_,
                                     seg.disparity_px, seg.roi.tl(), context_.motion_carve, seg.outline);
  if (seg.motion_carve.pixels_removed > 0) seg.outline_stats.object_pixels = cv::countNonZero(seg.outline);
  times.carve_ms += ms_since(t0);
}

void RoiOutliner::check_photometric(const StereoFrame& frame, const cv::Mat& prev_left, const DetectorResult& result,
                                    RoiSegmentation& seg) const {
  const PhotometricCheckConfig& pc = context_.photometric;
  if (!pc.enabled || !result.depth.valid || prev_left.empty()) return;
  seg.outline_motion =
      region_motion(frame.left, prev_left, calibration_.left, calibration_.bf(), result.depth.T_cur_prev, seg.outline,
                    seg.disparity_px, seg.roi.tl(), pc, pc.max_motion_px);
  bool moves_with_background = seg.outline_motion.apparent_motion_px >= 0 && seg.outline_motion.moves_with_background;
  // A coasted outline has no dynamic point of this frame behind it: it must show its motion frame to frame (a
  // person who has just stopped still differs from the multi-frame reference).
  if (seg.coasted) moves_with_background = !(seg.outline_motion.apparent_motion_px >= 0) || moves_with_background;
  if (moves_with_background && !seg.coasted && result.multiframe.valid) {
    const OutlineStats& st = seg.outline_stats;
    if (st.median_disparity_px >= pc.multiframe_min_disparity_px) {
      seg.outline_motion_multiframe = region_motion(frame.left, result.multiframe.reference_left, calibration_.left,
                                                    calibration_.bf(), result.multiframe.T_cur_ref, seg.outline,
                                                    seg.disparity_px, seg.roi.tl(), pc, pc.multiframe_max_motion_px);
      moves_with_background =
          seg.outline_motion_multiframe.apparent_motion_px >= 0 && seg.outline_motion_multiframe.moves_with_background;
    } else if (pc.far_multiframe_tracks) {
      moves_with_background = !tracks_move_together_multiframe(
          st.multiframe_tested_inside, st.multiframe_dynamic_inside, st.median_offset_px, context_.outline);
    }
  }
  if (moves_with_background) seg.outline_verdict = OutlineVerdict::kMovesWithBackground;
}

void RoiOutliner::keep(const StereoFrame& frame, ObjectTracker& objects, FrameRegions& regions, RoiSegmentation& seg,
                       DetectorResult& result) const {
  const OutlineStats& st = seg.outline_stats;
  seg.object_id = objects.claim_id(seg.object_id, regions);
  const cv::Rect local = cv::boundingRect(seg.outline);
  seg.region.rectangle = cv::Rect(local.tl() + seg.roi.tl(), local.size());
  seg.region.started_points = st.object_seeds;
  const cv::Rect rect = seg.region.rectangle & cv::Rect(cv::Point(0, 0), frame.left.size());
  const bool near_moving =
      context_.confirm.near_moving(seg.mean_disparity_px, st.median_offset_px, local.area(), seg.roi.area());
  StackingRule stacking;
  stacking.enabled = context_.merge_stacked_regions;
  stacking.grouping = context_.grouping;
  stacking.max_height_m = context_.outline.max_height_m > 0 ? context_.outline.max_height_m : 3.0;
  stacking.baseline_m = calibration_.baseline_m;
  regions.keep_outline(seg, rect, near_moving, stacking, context_.split_side_by_side, result.mask);
}

void RoiOutliner::outline_by_disparity(const StereoFrame& frame, const cv::Mat& prev_left, ObjectTracker& objects,
                                       FrameRegions& regions, const RoiMatch& match, RoiSegmentation& seg,
                                       DetectorResult& result, OutlineTimes& times) {
  collect_static_seeds(result, seg.roi);
  outline_roi(frame, result, seg);
  // An outline cut by the ROI's left or right side: widen the ROI there, match the new strip, outline again.
  for (int round = 0;
       round < options_.extend_max_rounds && seg.outline_stats.object_pixels > 0 && !context_.full_frame_disparity;
       ++round) {
    bool left = false, right = false;
    if (!sides_to_widen(frame, result, seg, left, right)) break;
    const auto t_widen = Clock::now();
    widen(frame, match, left, right, seg);
    times.widen_ms += ms_since(t_widen);
    outline_roi(frame, result, seg);
  }
  reshape(frame, seg);
  objects.cut_growth(result, seg);
  seg.labels.release();
  seg.superpixels = 0;
  seg.planes.clear();
  seg.boundaries.clear();
  seg.motion.clear();
  seg.region = DynamicRegion{};
  seg.outline_motion = SuperpixelMotion{};
  seg.outline_motion_multiframe = SuperpixelMotion{};
  count_tracks_inside(result, seg);
  seg.outline_verdict = judge(result, objects, seg);
  // A kept outline that flooded a static surface (its clearly static tracks away from the object's points) loses it.
  if (seg.outline_verdict == OutlineVerdict::kKept) {
    carve(frame, prev_left, result, seg, times);
    if (seg.outline_stats.object_pixels < context_.outline.min_pixels) seg.outline_verdict = OutlineVerdict::kTooSmall;
  }
  // Photometric confirmation: an outline whose content moved as a static surface would, frame to frame and against
  // the multi-frame reference (where there is one), is dropped.
  if (seg.outline_verdict == OutlineVerdict::kKept) check_photometric(frame, prev_left, result, seg);
  if (seg.outline_verdict == OutlineVerdict::kKept) keep(frame, objects, regions, seg, result);
}

void RoiOutliner::outline_by_superpixels(const StereoFrame& frame, const cv::Mat& prev_left, FrameRegions& regions,
                                         RoiSegmentation& seg, DetectorResult& result) {
  StageTimings& tm = result.timings;
  auto t = Clock::now();
  if (options_.scale == 1.0) {
    seg.superpixels = slic_.segment(frame.left(seg.roi), seg.labels, &seg.slic);
  } else {
    cv::resize(frame.left(seg.roi), small_grey_, cv::Size(), options_.scale, options_.scale, cv::INTER_AREA);
    seg.superpixels = slic_half_.segment(small_grey_, small_labels_, &seg.slic);
    cv::resize(small_labels_, seg.labels, seg.roi.size(), 0, 0, cv::INTER_NEAREST);
  }
  tm.slic_ms += ms_since(t);

  t = Clock::now();
  fit_superpixel_planes(seg.labels, seg.superpixels, seg.disparity_px, seg.roi.tl(), context_.planes, seg.planes,
                        options_.scale == 1.0 ? 1 : 2);
  tm.planes_ms += ms_since(t);

  t = Clock::now();
  graph_.build(seg.labels, seg.superpixels, seg.roi.tl());
  label_boundaries(graph_, seg.planes, context_.boundaries);
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
  if (context_.photometric.enabled && result.depth.valid && !prev_left.empty()) {
    check_superpixel_motion(frame.left, prev_left, calibration_.left, calibration_.bf(), result.depth.T_cur_prev,
                            seg.labels, seg.roi.tl(), seg.planes, context_.photometric, seg.motion);
    background_flags_.assign(seg.motion.size(), 0);
    for (std::size_t k = 0; k < seg.motion.size(); ++k)
      background_flags_[k] = seg.motion[k].moves_with_background ? 1 : 0;
    moves_with_background = &background_flags_;
  } else {
    seg.motion.clear();
  }
  seg.region = find_dynamic_region(seg.labels, seg.roi.tl(), graph_, seg.planes, group_pts_, group_disp_,
                                   context_.regions, static_pts_, static_disp_,
                                   result.ground_plane.valid ? &result.ground_plane : nullptr, moves_with_background);
  if (!seg.region.rectangle.empty()) {
    const cv::Rect rect = seg.region.rectangle & cv::Rect(cv::Point(0, 0), frame.left.size());
    region_mask_.create(frame.left.size(), CV_8UC1);
    region_mask_(rect).setTo(0);
    paint_region(seg.region, seg.labels, seg.roi.tl(), context_.regions.mask_mode, region_mask_);
    regions.add_unowned_region(region_mask_(rect), rect, context_.split_side_by_side, result.mask);
  }
  tm.regions_ms += ms_since(t);
}

}  // namespace agvslam::dynamic
