#include "agvslam/dynamic/detector.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"

namespace agvslam::dynamic {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

PointTracksConfig point_tracks_config(const DynamicDetectorConfig& c) {
  PointTracksConfig p;
  p.features = c.features;
  p.tracking = c.tracking;
  p.epipolar = c.epipolar;
  p.depth_test = c.depth_test;
  p.multiframe = c.multiframe;
  p.use_epipolar_test = c.detector.use_epipolar_test;
  p.use_depth_test = c.detector.use_depth_test;
  return p;
}

DensifierContext densifier_context(const DynamicDetectorConfig& c) {
  DensifierContext d;
  d.features = c.features;
  d.grouping = c.grouping;
  d.tracking = c.tracking;
  d.multiframe = c.multiframe;
  d.use_epipolar_test = c.detector.use_epipolar_test;
  d.use_depth_test = c.detector.use_depth_test;
  return d;
}

RoiOutlinerContext roi_outliner_context(const DynamicDetectorConfig& c) {
  RoiOutlinerContext r;
  r.grouping = c.grouping;
  r.slic = c.slic;
  r.planes = c.planes;
  r.boundaries = c.boundaries;
  r.regions = c.regions;
  r.outline = c.outline;
  r.edge_refine = c.edge_refine;
  r.photometric = c.photometric;
  r.motion_carve = c.motion_carve;
  r.static_carve = c.static_carve;
  r.confirm = c.confirm;
  r.full_frame_disparity = c.detector.full_frame_disparity;
  r.merge_stacked_regions = c.detector.merge_stacked_regions;
  r.split_side_by_side = c.detector.split_side_by_side;
  return r;
}

DynamicDetector::DynamicDetector(const StereoCalibration& calibration, const DynamicDetectorConfig& config,
                                 const stereo::StereoConfig& stereo_config)
    : calibration_(calibration),
      config_(config),
      tracks_(point_tracks_config(config), calibration, stereo_config.sparse),
      densifier_(config.densify, densifier_context(config), calibration),
      objects_(config.objects, config.regions.mask_mode == MaskMode::kDisparity),
      band_(config.band, config.band_carry, config.outline.min_pixels, calibration),
      outliner_(config.roi, roi_outliner_context(config), calibration, stereo_config.sgbm),
      confirmer_(config.confirm) {
  config_.validate("DynamicDetectorConfig");
  stereo_config.validate("StereoConfig");
  if (config_.detector.use_depth_test && !(calibration_.bf() > 0)) {
    throw InputError("StereoCalibration", "baseline_m",
                     "expected a positive focal length and baseline for the depth test");
  }
}

void DynamicDetector::reset() {
  has_previous_ = false;
  prev_left_.release();
  prev_right_.release();
  tracks_.reset();
  objects_.reset();
  confirmer_.reset();
}

DetectorResult DynamicDetector::detect(const StereoFrame& frame) {
  DetectorResult result;
  detect(frame, result);
  return result;
}

void DynamicDetector::detect(const StereoFrame& frame, DetectorResult& result) {
  const auto t_start = Clock::now();
  CV_Assert(frame.left.type() == CV_8UC1 && frame.right.type() == CV_8UC1 && frame.left.size() == frame.right.size());
  begin_frame(frame, result);
  const auto t = Clock::now();
  if (config_.detector.full_frame_disparity) {
    outliner_.full_frame_disparity(frame, result.full_disparity_px);
  } else {
    result.full_disparity_px.release();
  }
  result.timings.point_disparity_ms += ms_since(t);
  tracks_.build_pyramid(frame.left, result.timings);

  if (result.has_previous) {
    tracks_.track_and_test(frame, result);
    tracks_.collect_points(result, dynamic_);
    add_points(frame, dynamic_, result);
    group_points(dynamic_, frame.left.size(), groups_, group_object_, result);
    regions_.clear();
    outline_groups(frame, groups_, group_object_, dynamic_, regions_, result);
    finish_mask(frame, regions_, result);
  }
  tracks_.replenish(frame, result, config_.densify.keep_static);
  objects_.assign_tracks(tracks_.tracks(), result, regions_);
  result.unconfirmed_objects =
      confirmer_.confirm(result.mask, config_.detector.mask_dilation_px, regions_.instance_near_moving());

  tracks_.end_frame();
  if (keeps_previous_images()) {
    frame.left.copyTo(prev_left_);
    frame.right.copyTo(prev_right_);
  }
  has_previous_ = true;
  result.timings.total_ms = ms_since(t_start);
}

bool DynamicDetector::keeps_previous_images() const {
  return config_.densify.enabled || config_.photometric.enabled || config_.band.enabled || config_.motion_carve.enabled;
}

void DynamicDetector::begin_frame(const StereoFrame& frame, DetectorResult& result) {
  const cv::Size size = frame.left.size();
  result.frame_index = frame.index;
  result.t_ns = frame.t_ns;
  // A frame of another size than the previous one (a new camera mode) starts over.
  if (has_previous_ && tracks_.previous_size() != size) reset();
  result.has_previous = has_previous_ && tracks_.has_tracks();
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
  result.unconfirmed_objects = 0;
  result.timings = StageTimings{};
  outliner_.begin_frame();
}

void DynamicDetector::add_points(const StereoFrame& frame, DynamicPoints& dynamic, DetectorResult& result) {
  auto t = Clock::now();
  if (band_.enabled() && result.depth.valid && !prev_left_.empty()) {
    band_.add_driving_seeds(frame, prev_left_, prev_right_, tracks_, dynamic, result);
  }
  result.timings.band_ms += ms_since(t);
  t = Clock::now();
  if (config_.densify.enabled && config_.densify.max_points > 0 && !prev_left_.empty()) {
    densifier_.densify(frame, prev_left_, prev_right_, tracks_, dynamic, result);
  }
  result.timings.densify_ms = ms_since(t);
}

void DynamicDetector::group_points(const DynamicPoints& dynamic, cv::Size image_size, std::vector<DynamicGroup>& groups,
                                   std::vector<int>& group_object, DetectorResult& result) const {
  const auto t = Clock::now();
  RoiGroupingConfig grouping = config_.grouping;
  grouping.min_points = objects_.group_min_points(grouping.min_points);
  groups = group_dynamic_points(dynamic.px, dynamic.disparity_px, image_size, grouping, calibration_.baseline_m);
  objects_.assign_groups(dynamic, config_.grouping.min_points, groups, group_object);
  if (static_cast<int>(groups.size()) > config_.detector.max_rois) {
    groups.resize(static_cast<std::size_t>(config_.detector.max_rois));
    group_object.resize(groups.size());
  }
  result.timings.grouping_ms = ms_since(t);
}

void DynamicDetector::outline_groups(const StereoFrame& frame, std::vector<DynamicGroup>& groups,
                                     std::vector<int>& group_object, DynamicPoints& dynamic, FrameRegions& regions,
                                     DetectorResult& result) {
  // The floor in disparity space, from the static points below the principal point (ground veto).
  const bool coasting = objects_.may_coast();
  if ((!groups.empty() || coasting) && (config_.regions.ground_veto || config_.roi.extend_to_floor)) {
    static_pts_.clear();
    static_disp_.clear();
    for (const TrackedPoint& p : result.points) {
      if (!p.tracked || p.dynamic || !(p.cur_disparity_px > 0)) continue;
      static_pts_.push_back(p.cur_px);
      static_disp_.push_back(p.cur_disparity_px);
    }
    result.ground_plane = fit_ground_plane(static_pts_, static_disp_, calibration_.left.cy);
  }
  const auto outline = [&](std::size_t first, bool coasted) {
    result.rois.resize(groups.size());
    for (std::size_t g = first; g < groups.size(); ++g) {
      outliner_.outline_group(frame, prev_left_, groups[g], static_cast<int>(g), group_object[g], coasted, dynamic,
                              objects_, regions, result.rois[g], result);
    }
  };
  outline(0, false);
  // Objects of earlier frames that no region of this frame continues coast on their own tracks.
  if (coasting) {
    const std::size_t first_coasted = groups.size();
    objects_.add_coasting_groups(result, regions, config_.grouping, config_.detector.max_rois, groups, group_object,
                                 dynamic);
    outline(first_coasted, true);
  }
}

void DynamicDetector::finish_mask(const StereoFrame& frame, FrameRegions& regions, DetectorResult& result) {
  band_.carry(objects_, regions, result);
  if (band_.enabled() && result.depth.valid && !prev_left_.empty()) {
    const auto t = Clock::now();
    band_.segment(frame, prev_left_, tracks_, regions, result);
    result.timings.band_ms += ms_since(t);
  }
  const int dilation = config_.detector.mask_dilation_px;
  if (dilation > 0 && !result.mask.regions.empty()) {
    const int k = 2 * dilation + 1;
    cv::dilate(result.mask.instances, dilated_, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
    dilated_.copyTo(result.mask.instances);
  }
  cv::compare(result.mask.instances, 0, result.mask.image, cv::CMP_GT);
  if (objects_.enabled()) objects_.update(result, regions, band_.carried(), config_.band_carry.max_frames > 0);
  objects_.remember_pixels(result, regions);
}

}  // namespace agvslam::dynamic
