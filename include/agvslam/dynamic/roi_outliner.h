#pragma once
// One dynamic ROI from its group of dynamic points to a region of the mask (or a verdict why not). The ROI is the
// group's box, extended to the floor and to a person's height above it and to the left border near the band without
// stereo; SGBM runs on the ROI alone (RoiMatcher). Then, by regions.mask_mode:
//   disparity (default): the object's pixels connected to its points through smooth disparity (object_outline.h),
//     the ROI widened where the outline runs into its left or right side, the sides re-decided at full resolution
//     (edge_refine.h), cut back when it suddenly grew (ObjectTracker), judged by the tracks inside it, carved of
//     static surfaces it flooded (static_carve.h, motion_carve.h), and dropped when its content moves with the
//     background (photometric check);
//   superpixels / rectangle (the paper): SLIC, disparity planes, boundary types, search to the occlusion boundaries.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/boundary.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/disparity_plane.h"
#include "agvslam/dynamic/edge_refine.h"
#include "agvslam/dynamic/frame_regions.h"
#include "agvslam/dynamic/motion_carve.h"
#include "agvslam/dynamic/object_confirmer.h"
#include "agvslam/dynamic/object_outline.h"
#include "agvslam/dynamic/object_tracker.h"
#include "agvslam/dynamic/photometric_check.h"
#include "agvslam/dynamic/point_tracks.h"
#include "agvslam/dynamic/region_search.h"
#include "agvslam/dynamic/roi_disparity.h"
#include "agvslam/dynamic/roi_grouping.h"
#include "agvslam/dynamic/slic.h"
#include "agvslam/dynamic/static_carve.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `roi`.
struct RoiOptions {
  // SGBM of a ROI searches [0, the group's largest point disparity + this] (px), within the configured range: the
  // object is the nearest thing in its ROI.
  double disparity_margin_px = 8;
  // 1 or 0.5: SGBM and SLIC of the ROIs at this resolution (planes, boundaries and regions stay at full resolution).
  double scale = 1.0;
  // 1 or 2 (scale 1): ROIs of at least row_step_min_area_px (0 = all) are matched on every column but with pairs of
  // rows averaged, half the work; an upright object's outline is decided by its sides, which keep full horizontal
  // resolution.
  int row_step = 2;
  int row_step_min_area_px = 20000;
  // mask_mode disparity: ROIs larger than this (px) get their SGBM at half resolution anyway (0 = never) ...
  int half_scale_min_area_px = 0;
  // ... and their outline loses this many more pixels at its edge (the half-resolution block fattens the foreground
  // twice as far in full-resolution pixels).
  int half_scale_erode_px = 0;
  // StereoSGBM leaves the leftmost num_disparities columns it matches without disparity: a ROI near the left border
  // is matched in images padded on the left (edge replicated), so its pixels get a disparity from x = d on.
  bool pad_left_border = true;
  // SGBM's speckle filter (stereo sgbm.speckle_*) on the ROI crops; the outline's flood drops lone specks itself.
  bool speckle_filter = false;
  // Objects stand on the floor: a ROI whose lowest point lies above the floor row at the group's disparity (from
  // the frame's ground plane; legs often have no corners) is extended down to it ...
  bool extend_to_floor = true;
  // ... and up to this height above the floor row (m; 0 = not): corners seldom reach a person's head.
  double extend_to_height_m = 1.9;
  // mask_mode disparity: an outline that reaches the left or right side of its ROI over at least extend_min_rows
  // rows (a side without corners lies beyond the tracks' box) is cut there: the ROI is widened on that side by
  // extend_step_m at the outline's depth (at least 16 px), the new strip matched and the outline redone, up to
  // extend_max_rounds times (0 = off) ...
  int extend_max_rounds = 2;
  int extend_min_rows = 20;
  double extend_step_m = 0.3;
  // ... but not on a side whose outline holds a static track (tested, not dynamic) within this many px of it: the
  // outline flooded a static surface at the object's depth (0 = no such check).
  int extend_static_guard_px = 24;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// What the ROI outliner reads beside its own section.
struct RoiOutlinerContext {
  RoiGroupingConfig grouping;
  SlicConfig slic;
  PlaneFitConfig planes;
  BoundaryConfig boundaries;
  RegionSearchConfig regions;
  OutlineConfig outline;
  EdgeRefineConfig edge_refine;
  PhotometricCheckConfig photometric;
  MotionCarveConfig motion_carve;
  StaticCarveOptions static_carve;
  ConfirmOptions confirm;             // near_*: which kept outlines are near and moving
  bool full_frame_disparity = false;  // detector.full_frame_disparity: ROIs cut from the whole-frame SGBM
  bool merge_stacked_regions = true;  // detector.merge_stacked_regions
  bool split_side_by_side = true;     // detector.split_side_by_side
};

class RoiOutliner {
 public:
  RoiOutliner(const RoiOptions& options, const RoiOutlinerContext& context, const StereoCalibration& calibration,
              const stereo::SgbmConfig& sgbm);

  // Starts a frame (forgets the frame's static offset median).
  void begin_frame() { static_offset_median_px_ = -1; }
  // detector.full_frame_disparity: SGBM of the whole frame.
  void full_frame_disparity(const StereoFrame& frame, cv::Mat& disparity_px) {
    matcher_.match_full(frame, disparity_px);
  }

  // Outlines `group` (group index `group_index`; its members index `dynamic`) into `seg`: its points get the group
  // index, a kept region is painted into result.mask through `regions`. object_id: the object it continues (-1:
  // none); coasted: the group came from an object's own tracks (ObjectTracker::add_coasting_groups). prev_left: the
  // previous frame's left image (empty: none). Adds to result.timings.
  void outline_group(const StereoFrame& frame, const cv::Mat& prev_left, const DynamicGroup& group, int group_index,
                     int object_id, bool coasted, const DynamicPoints& dynamic, ObjectTracker& objects,
                     FrameRegions& regions, RoiSegmentation& seg, DetectorResult& result);

 private:
  // How one ROI is matched (its widening strips alike).
  struct RoiMatch {
    int max_disparity_px = 0;
    double scale = 1.0;
    int row_step = 1;
  };
  // Time of the disparity outline spent elsewhere than outlining.
  struct OutlineTimes {
    double widen_ms = 0;  // matching widened strips (counted as ROI disparity)
    double carve_ms = 0;  // motion carving
  };

  // The ROI: the group's, extended to the floor and a person's height, and to the left border near the band.
  void place_roi(const DynamicGroup& group, const DisparityPlane& ground, cv::Size image_size, cv::Rect& roi) const;
  // The ROI's disparity into seg.disparity_px (and seg.half_scale), and how it was matched.
  RoiMatch match_roi(const StereoFrame& frame, const DetectorResult& result, RoiSegmentation& seg);

  // mask_mode disparity.
  void outline_by_disparity(const StereoFrame& frame, const cv::Mat& prev_left, ObjectTracker& objects,
                            FrameRegions& regions, const RoiMatch& match, RoiSegmentation& seg, DetectorResult& result,
                            OutlineTimes& times);
  // Competing static seeds (outline.static_competition) inside the ROI into static_pts_ / static_disp_.
  void collect_static_seeds(const DetectorResult& result, const cv::Rect& roi);
  void outline_roi(const StereoFrame& frame, const DetectorResult& result, RoiSegmentation& seg);
  // The sides of the ROI to widen (roi.extend_*); false when none.
  bool sides_to_widen(const StereoFrame& frame, const DetectorResult& result, const RoiSegmentation& seg, bool& left,
                      bool& right) const;
  // Widens the ROI on those sides, matching only the new strips, and outlines again.
  void widen(const StereoFrame& frame, const RoiMatch& match, bool left, bool right, RoiSegmentation& seg);
  // Edge refinement, half-scale erosion, closing of far outlines and the fill to the left band.
  void reshape(const StereoFrame& frame, RoiSegmentation& seg);
  // The tracks inside the outline (outline_stats.*_inside, median_offset_px; offsets into inside_offsets_).
  void count_tracks_inside(const DetectorResult& result, RoiSegmentation& seg);
  // The outline's verdict from its size, its tracks and its height.
  OutlineVerdict judge(const DetectorResult& result, const ObjectTracker& objects, const RoiSegmentation& seg);
  // A kept outline that flooded a static surface loses it (static_carve.*, motion_carve.*).
  void carve(const StereoFrame& frame, const cv::Mat& prev_left, const DetectorResult& result, RoiSegmentation& seg,
             OutlineTimes& times);
  // The photometric check of a kept outline: kMovesWithBackground when its content moved as a static surface would.
  void check_photometric(const StereoFrame& frame, const cv::Mat& prev_left, const DetectorResult& result,
                         RoiSegmentation& seg) const;
  // A kept outline: its object, its region, and its pixels in the mask.
  void keep(const StereoFrame& frame, ObjectTracker& objects, FrameRegions& regions, RoiSegmentation& seg,
            DetectorResult& result) const;

  // mask_mode superpixels / rectangle.
  void outline_by_superpixels(const StereoFrame& frame, const cv::Mat& prev_left, FrameRegions& regions,
                              RoiSegmentation& seg, DetectorResult& result);

  RoiOptions options_;
  RoiOutlinerContext context_;
  StereoCalibration calibration_;
  RoiMatcher matcher_;
  Slic slic_;
  Slic slic_half_;  // superpixel size halved, for scale 0.5
  SuperpixelGraph graph_;
  ObjectOutliner outliner_;
  EdgeRefiner edge_refiner_;
  double static_offset_median_px_ = -1;  // of this frame's static tracks (-1: not computed yet)

  // Scratch.
  std::vector<cv::Point2f> group_pts_, static_pts_;  // the group's dynamic points, the competing static ones
  std::vector<float> group_disp_, static_disp_;
  std::vector<float> inside_offsets_, static_offsets_, carve_offsets_;
  std::vector<float> motion_dx_, motion_dy_;
  std::vector<cv::Point2f> carve_static_px_;
  std::vector<char> background_flags_;
  cv::Mat small_grey_, small_labels_, reshaped_outline_, region_mask_, strip_disparity_, widened_disparity_;
};

}  // namespace agvslam::dynamic
