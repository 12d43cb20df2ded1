#pragma once
// What DynamicDetector::detect() gives per frame: the tracked points with their tests, the ROIs with their outlines
// and verdicts, the mask, and the stage timings. Shared by the detector and the parts it delegates to.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/dynamic/band_segmenter.h"
#include "agvslam/dynamic/boundary.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/disparity_plane.h"
#include "agvslam/dynamic/epipolar.h"
#include "agvslam/dynamic/motion_carve.h"
#include "agvslam/dynamic/multiframe_test.h"
#include "agvslam/dynamic/object_outline.h"
#include "agvslam/dynamic/photometric_check.h"
#include "agvslam/dynamic/region_search.h"
#include "agvslam/dynamic/slic.h"

namespace agvslam::dynamic {

// One LK track from the previous frame into the current one.
struct TrackedPoint {
  cv::Point2f prev_px, cur_px;
  float prev_disparity_px = 0, cur_disparity_px = 0;  // 0 = unknown
  bool tracked = false;                               // LK converged and passed the forward-backward check
  bool densified = false;  // added around a small group of dynamic points (not a quadtree corner)
  int age = 0;             // frames the track has been followed before this one (1 = born in the previous)
  double d_epi_px = 0, t_epi_px = 0;
  double reprojection_px = -1, disparity_residual_px = -1;  // depth test, -1 = not tested
  double multiframe_px = -1;  // multi-frame test: offset from the prediction, -1 = not tested
  double multiframe_disparity_residual_px = -1;
  bool dynamic_epipolar = false, dynamic_depth = false, dynamic_multiframe = false;
  bool dynamic = false;  // the union of the enabled tests
  int group = -1;        // index into DetectorResult::rois, -1 = none
};

// What became of an outline (mask_mode disparity): a dynamic region, or why not.
enum class OutlineVerdict {
  kKept,
  kNoSeed,              // no point found a pixel of agreeing disparity
  kTooSmall,            // fewer than outline.min_pixels
  kMostlyStaticTracks,  // the tracks inside it are mostly static (outline.min_dynamic_fraction)
  kTooTall,             // taller than outline.max_height_m
  kMovesWithBackground  // the photometric check found it static (photometric)
};
std::string to_string(OutlineVerdict verdict);

// The segmentation of one dynamic ROI (debugging output; coordinates of `labels` are ROI-local).
struct RoiSegmentation {
  cv::Rect roi;
  std::vector<int> points;  // indices into DetectorResult::points
  double mean_disparity_px = 0;
  cv::Mat disparity_px;  // CV_32FC1, ROI size (SGBM on the crop), 0 = none
  cv::Mat labels;        // CV_32SC1, ROI size
  int superpixels = 0;
  SlicStats slic;
  std::vector<DisparityPlane> planes;  // per superpixel
  std::vector<SuperpixelBoundary> boundaries;
  std::vector<SuperpixelMotion> motion;  // photometric check per superpixel (when enabled)
  cv::Mat outline;                       // CV_8UC1, ROI size: the object's pixels (mask_mode disparity)
  bool half_scale = false;               // disparity_px came from half-resolution SGBM
  OutlineStats outline_stats;
  SuperpixelMotion outline_motion, outline_motion_multiframe;  // photometric check of the outline (when run)
  MotionCarveStats motion_carve;                               // two-motion carving of a kept outline (motion_carve)
  OutlineVerdict outline_verdict = OutlineVerdict::kNoSeed;    // kKept: the outline is a dynamic region
  int object_id = -1;    // the object over frames (objects.enabled): continued or new
  bool coasted = false;  // outlined from the tracks of an object of earlier frames (objects.coast_*)
  DynamicRegion region;
};

struct DynamicMask {
  cv::Mat image;                  // CV_8UC1, 255 = dynamic, the size of the input frame
  cv::Mat instances;              // CV_8UC1, 0 = static, k > 0 = pixel of detected object k (a region, or with
                                  // detector.split_side_by_side one of the side-by-side objects of a region)
  std::vector<cv::Rect> regions;  // the dynamic rectangles (paper's output)
  int pixel_count() const { return image.empty() ? 0 : cv::countNonZero(image); }
};

struct StageTimings {
  double pyramid_ms = 0, tracking_ms = 0, point_disparity_ms = 0, epipolar_ms = 0, depth_test_ms = 0, multiframe_ms = 0,
         densify_ms = 0, grouping_ms = 0, roi_disparity_ms = 0, slic_ms = 0, planes_ms = 0, boundaries_ms = 0,
         regions_ms = 0, motion_carve_ms = 0, band_ms = 0, features_ms = 0, total_ms = 0;
  std::string describe() const;
};

struct DetectorResult {
  std::size_t frame_index = 0;
  int64_t t_ns = 0;
  bool has_previous = false;  // false on the first frame: nothing can be tested
  DynamicMask mask;
  std::vector<TrackedPoint> points;
  std::vector<RoiSegmentation> rois;
  EpipolarResult epipolar;
  DepthTestResult depth;
  MultiFrameResult multiframe;
  BandResult band;  // the left band without stereo (band_segmenter.h)
  int band_joined = 0,
      band_objects = 0;  // its regions joined to an object of the mask / reported as objects of their own
  // While the AGV drives: the band's candidate movers (BandSegmenter::driving_seeds) / those the tests flagged, which
  // joined the dynamic points.
  int band_driving_seeds = 0, band_driving_dynamic = 0;
  DisparityPlane ground_plane;  // d = a x + b y + c of the floor from the static points (ground veto); may be invalid
  cv::Mat full_disparity_px;    // only with detector.full_frame_disparity
  StageTimings timings;
  int unconfirmed_objects = 0;  // objects found but not reported: nothing overlapped them in the previous frame
                                // (confirm.min_box_iou)
  int lk_levels = -1;           // the pyramid levels the tracks were followed on (tracking.min_levels; -1: none)

  int dynamic_point_count() const;
};

}  // namespace agvslam::dynamic
