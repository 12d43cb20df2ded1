#pragma once
// The dynamic-region detector of paper 004 (III.A-B) on consecutive rectified stereo frames. detect() is the list
// of stages; each part owns its state:
//
//   PointTracks (point_tracks.h)     the tracks of the previous frame followed by LK into this one, their disparity,
//                                    the epipolar, depth-consistency and multi-frame tests; a point is dynamic if
//                                    any enabled test says so
//   LeftBand (left_band.h)           while driving, candidate movers of the left strip join the dynamic points
//   Densifier (densifier.h)          extra corners around small groups of dynamic points, tested the same way
//   grouping (roi_grouping.h)        groups of dynamic points -> dynamic ROIs; ObjectTracker (object_tracker.h)
//                                    gives each the object of the last frame it continues
//   RoiOutliner (roi_outliner.h)     per ROI: SGBM on the ROI, then (regions.mask_mode) the disparity outline of the
//                                    object and its checks, or the paper's superpixel / rectangle region
//   ObjectTracker                    objects of the last frame that no region continues coast on their own tracks
//   LeftBand                         objects' pixels carried into the band x < d without stereo, and what moved
//                                    there by the left image alone (band_segmenter.h)
//   FrameRegions (frame_regions.h)   the mask's instances, their objects and regions as the stages add them
//   ObjectConfirmer (object_confirmer.h)  objects not confirmed by the previous frame are not reported
//   PointTracks                      the tracks that held continue; quadtree FAST corners fill the places no track
//                                    covers
//
// Disparity is computed only where it is used: a block matcher at the points, SGBM inside the ROIs (a whole-frame
// SGBM is available for debugging with detector.full_frame_disparity). The first frame, and any frame after
// reset(), gives an empty mask.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/band_segmenter.h"
#include "agvslam/dynamic/boundary.h"
#include "agvslam/dynamic/densifier.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/disparity_plane.h"
#include "agvslam/dynamic/edge_refine.h"
#include "agvslam/dynamic/epipolar.h"
#include "agvslam/dynamic/frame_regions.h"
#include "agvslam/dynamic/left_band.h"
#include "agvslam/dynamic/motion_carve.h"
#include "agvslam/dynamic/multiframe_test.h"
#include "agvslam/dynamic/object_confirmer.h"
#include "agvslam/dynamic/object_outline.h"
#include "agvslam/dynamic/object_tracker.h"
#include "agvslam/dynamic/photometric_check.h"
#include "agvslam/dynamic/point_tracks.h"
#include "agvslam/dynamic/quadtree_fast.h"
#include "agvslam/dynamic/region_search.h"
#include "agvslam/dynamic/roi_grouping.h"
#include "agvslam/dynamic/roi_outliner.h"
#include "agvslam/dynamic/slic.h"
#include "agvslam/dynamic/static_carve.h"
#include "agvslam/stereo/stereo_config.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `detector`: what the whole pipeline shares.
struct DetectorOptions {
  bool use_epipolar_test = true;      // paper 004's test
  bool use_depth_test = true;         // the depth-consistency test and the multi-frame test (beyond the paper)
  bool full_frame_disparity = false;  // debugging: whole-frame SGBM instead of points + ROIs
  int max_rois = 8;                   // at most this many ROIs per frame (the largest groups)
  // Regions of one frame that are stacked (their columns overlap by half the narrower, or by a quarter with one
  // wholly above the other; the vertical gap within T_s = a_s + b_s d of grouping or 0.8 m; together no taller
  // than outline.max_height_m) at agreeing median disparity (grouping t_disp) are one object: the later one takes
  // the earlier one's instance (torso and legs found from separate groups).
  bool merge_stacked_regions = true;
  // A region whose outline falls into pieces side by side (columns not overlapping, e.g. two people walking apart
  // inside one ROI) gives one object per piece in DynamicMask::instances.
  bool split_side_by_side = true;
  int mask_dilation_px = 0;  // grow the final mask by this many pixels

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Everything in params/dynamic.yaml: one struct per part; their tables (read, validate, echo): dynamic_config.cpp.
struct DynamicDetectorConfig {
  QuadtreeFastConfig features;
  LkTrackerConfig tracking;
  EpipolarTestConfig epipolar;
  DepthTestConfig depth_test;
  MultiFrameTestConfig multiframe;
  RoiGroupingConfig grouping;
  SlicConfig slic;
  PlaneFitConfig planes;
  BoundaryConfig boundaries;
  RegionSearchConfig regions;
  OutlineConfig outline;
  EdgeRefineConfig edge_refine;
  PhotometricCheckConfig photometric;
  MotionCarveConfig motion_carve;
  BandSegmenterConfig band;
  DetectorOptions detector;
  RoiOptions roi;
  DensifyOptions densify;
  ObjectTrackerOptions objects;
  BandCarryOptions band_carry;
  StaticCarveOptions static_carve;
  ConfirmOptions confirm;

  void validate(const std::string& source) const;
  // The start-up echo: one line per section, "section: key=value unit, ...".
  std::vector<std::string> describe() const;
};

// Loads params/dynamic.yaml over the defaults (absent keys keep their default). Throws InputError naming the
// file and the field ("epipolar.a_epi_px") for a missing file, bad YAML, an unknown key, or a value of the
// wrong type or out of range.
DynamicDetectorConfig load_dynamic_config(const std::string& path);

// What each part reads of the configuration beside its own section.
PointTracksConfig point_tracks_config(const DynamicDetectorConfig& config);
DensifierContext densifier_context(const DynamicDetectorConfig& config);
RoiOutlinerContext roi_outliner_context(const DynamicDetectorConfig& config);

class DynamicDetector {
 public:
  // calibration: of the rectified frames that detect() receives. Validates both configurations
  // (InputError naming the struct and field).
  explicit DynamicDetector(const StereoCalibration& calibration, const DynamicDetectorConfig& config = {},
                           const stereo::StereoConfig& stereo_config = {});

  const DynamicDetectorConfig& config() const { return config_; }

  // Runs the pipeline on the next frame (CV_8UC1 left/right of the calibration's size). The previous frame is
  // kept internally.
  DetectorResult detect(const StereoFrame& frame);
  // Same, reusing the buffers of `result` (no per-frame allocation once sizes have settled).
  void detect(const StereoFrame& frame, DetectorResult& result);

  // Forgets the previous frame (the next detect() gives an empty mask).
  void reset();

 private:
  // The stages of detect() that are the detector's own.
  // Clears the per-frame parts of `result` (a frame of another size than the last one resets the detector).
  void begin_frame(const StereoFrame& frame, DetectorResult& result);
  // Points beside the tracks: the left band's driving seeds, then densification around small dynamic groups.
  void add_points(const StereoFrame& frame, DynamicPoints& dynamic, DetectorResult& result);
  // Eq. 4 grouping of the dynamic points into at most detector.max_rois ROIs, each with the object of the last
  // frame it continues (group_object, -1: none).
  void group_points(const DynamicPoints& dynamic, cv::Size image_size, std::vector<DynamicGroup>& groups,
                    std::vector<int>& group_object, DetectorResult& result) const;
  // The floor from the frame's static points, then each group's outline, then the coasting objects' outlines, into
  // result.rois and the mask.
  void outline_groups(const StereoFrame& frame, std::vector<DynamicGroup>& groups, std::vector<int>& group_object,
                      DynamicPoints& dynamic, FrameRegions& regions, DetectorResult& result);
  // The left band (carried and segmented regions), the mask's dilation and the objects kept for the next frame.
  void finish_mask(const StereoFrame& frame, FrameRegions& regions, DetectorResult& result);
  // Whether the previous frame's images are kept (the stages that compare with them are on).
  bool keeps_previous_images() const;

  StereoCalibration calibration_;
  DynamicDetectorConfig config_;
  PointTracks tracks_;
  Densifier densifier_;
  ObjectTracker objects_;
  LeftBand band_;
  RoiOutliner outliner_;
  ObjectConfirmer confirmer_;

  bool has_previous_ = false;
  cv::Mat prev_left_, prev_right_;  // the previous frame (when keeps_previous_images())
  // Per frame.
  DynamicPoints dynamic_;
  std::vector<DynamicGroup> groups_;
  std::vector<int> group_object_;
  FrameRegions regions_;
  std::vector<cv::Point2f> static_pts_;
  std::vector<float> static_disp_;
  cv::Mat dilated_;
};

}  // namespace agvslam::dynamic
