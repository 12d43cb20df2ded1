#pragma once
// Object outline from the ROI's disparity (beyond paper 004; regions.mask_mode = disparity).
//
// The paper outlines a dynamic object by searching from its dynamic points to the first occlusion boundary
// between superpixels. Where the disparity inside the ROI is dense (SGBM), the object is more directly the set
// of pixels connected to its dynamic points through smoothly varying disparity: an object in front of its
// background is separated from it by a disparity jump (the occlusion boundary, at pixel level), and where it
// touches the floor the floor is recognised by the frame's ground plane.
//
//   seeds:  per dynamic point, the nearest ROI pixel within seed_radius_px whose disparity agrees with the
//           point's (seed_tolerance_px + seed_tolerance_rel * d); static points (tracked, passed the motion
//           tests) seed a competing "static" label the same way;
//   flood:  breadth-first from all seeds at once (a geodesic partition: where the object and a static
//           surface at the same depth touch, e.g. a person beside a shelf, each pixel goes to the nearer
//           seed); a 4-neighbour joins when its disparity is valid, differs from the current pixel's by at
//           most step_tolerance_px + step_tolerance_rel * d (no occlusion jump), lies within depth_band_m of
//           its seed's depth, and is not floor (|d - ground(x, y)| <= ground_tolerance_px + rel * d);
//   unmeasured: (left_roi given, weak_texture_dn > 0) SGBM measures nothing on a surface without texture (a
//           vehicle's plain counterweight or rear panel): it leaves holes or carries its neighbours' disparities
//           into it, so the flood stops at its edge. A pixel whose mean |dI/dx| over the 5x5 matching block is
//           below weak_texture_dn grey levels per px, or that has no disparity, is unmeasured. An object stands
//           on the floor: below the outline, a column's run of unmeasured pixels and pixels at the object's depth
//           (within depth_band_m of the outline's median, not floor) joins it when it reaches the floor (a floor
//           pixel at that depth, or the floor row at the object's disparity); and in a row, such a run between two
//           outline pixels joins it. A measured pixel at another depth (the background between a person's legs) stops
//           both;
//   holes:  parts of the ROI enclosed by the object (not reaching the ROI border) that are mostly without
//           disparity (textureless clothing, the half-occluded strip between arm and body) join it; enclosed
//           parts smaller than min_hole_fill_px join whatever they hold.
// The result is a per-pixel mask of the ROI.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/dynamic/disparity_plane.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `outline`.
struct OutlineConfig {
  int seed_radius_px = 4;          // a point's seed pixel is searched this far from it
  double seed_tolerance_px = 1.0;  // |d(seed pixel) - d(point)| <= this + rel * d
  double seed_tolerance_rel = 0.08;
  double step_tolerance_px = 0.75;  // neighbouring pixels of one surface differ by <= this + rel * d
  double step_tolerance_rel = 0.04;
  double depth_band_m = 0.8;         // and lie within this depth of their seed (a person's depth extent)
  double ground_tolerance_px = 0.6;  // floor: |d - ground plane| <= this + rel * d
  double ground_tolerance_rel = 0.03;
  bool static_competition = false;         // static points claim their surfaces (see above)
  double max_hole_invalid_fraction = 0.5;  // enclosed parts with at least this fraction without disparity join
  int min_hole_fill_px = 64;               // enclosed parts smaller than this join regardless
  double weak_texture_dn = 1.0;            // unmeasured below this mean |dI/dx| (grey levels per px); 0 = no fill
  // SGBM fattens a foreground object by about half its block (its cost window spills over the edge onto the
  // background): the outline is eroded by this many px (0 = not; edge_refine.h re-decides the sides instead).
  int erode_px = 0;
  // The detector drops an outline of fewer than min_pixels px, or one holding at least min_tracked_for_fraction
  // tracked points of which fewer than min_dynamic_fraction are dynamic (a few tracks at a depth edge flooded a
  // large static surface).
  int min_pixels = 150;
  double min_dynamic_fraction = 0.2;
  int min_tracked_for_fraction = 10;
  // ... unless its tracks move together (beyond the paper; paper 001 decides per object with its own points): the
  // median depth-test reprojection offset of the tracks inside is at least aggregate_min_px and aggregate_ratio
  // times the median of the frame's static tracks. A person walking ahead of the AGV at a similar speed moves
  // each of its tracks by a little less than the per-track threshold (which grows with d), all of them the same
  // way; a static surface flooded from a depth edge keeps the static tracks' offsets. 0 = off.
  double aggregate_ratio = 3.0;
  double aggregate_min_px = 0.45;
  // An outline holding at least this many tracks with a depth-test offset must move together as above even when
  // more than min_dynamic_fraction of them are dynamic (0 = only for mostly static outlines).
  int aggregate_min_tracks = 5;
  // They also move together when the multi-frame test flagged at least aggregate_multiframe_fraction of the (at
  // least aggregate_min_tracks) tracks inside that it tested, with their median depth-test offset at least
  // aggregate_multiframe_min_px. A person walking ahead of the AGV can stay below aggregate_min_px, or below
  // aggregate_ratio times the static tracks' median, frame to frame, but is off by several of the multi-frame test's
  // thresholds over its 0.3-0.6 s. A person who has just stopped is still off the multi-frame
  // reference; frame to frame its offsets are the static ones (0.05-0.2 px), hence the floor. 0 = off.
  double aggregate_multiframe_fraction = 0.5;
  double aggregate_multiframe_min_px = 0.2;
  // ... or one taller than max_height_m at its median disparity (people, forklifts and AGVs are lower; a rack
  // upright flooded from a few false tracks at its edge is not). 0 = no limit.
  double max_height_m = 3.0;
  // Beyond the paper: a far outline (median disparity <= close_max_disparity_px) is closed (morphologically) with
  // a disc of close_far_m at its depth: a far forklift's mast and overhead guard are a few pixels wide and get no
  // SGBM disparity of their own. The detector applies it (it knows the camera). 0 m = off.
  double close_far_m = 0.5;
  double close_max_disparity_px = 8.0;
  // Beyond the paper: the leftmost d columns of the left image have no match in the right one at disparity d, so an
  // object entering or leaving at the left border has no disparity there (nor an outline). In each row where the
  // outline reaches within left_band_touch_px of that band (x < median d of the outline), the row is filled from
  // the image border to the outline. The detector applies it. -1 = off.
  int left_band_touch_px = 3;

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct OutlineStats {
  int object_seeds = 0, static_seeds = 0;
  int object_pixels = 0;
  int tracked_inside = 0, dynamic_inside = 0;  // tracked points inside the outline, and the dynamic ones (detector)
  int multiframe_tested_inside = 0, multiframe_dynamic_inside = 0;  // ... those the multi-frame test tested / flagged
  double median_offset_px = -1;    // their median depth-test reprojection offset (detector; -1 none)
  double median_disparity_px = 0;  // of the outline's pixels with a disparity
};

// outline.aggregate_*: whether the tracks inside an outline move together, their median depth-test reprojection
// offset (median_offset_px, < 0 = none measured) at least aggregate_min_px and aggregate_ratio x static_median_px
// (the frame's static tracks'). False when aggregate_ratio is 0.
bool tracks_move_together(double median_offset_px, double static_median_px, const OutlineConfig& config);
// outline.aggregate_multiframe_*: whether the tracks inside an outline move together by the multi-frame test:
// multiframe_dynamic of multiframe_tested (>= aggregate_min_tracks) at least aggregate_multiframe_fraction, with
// median_offset_px >= aggregate_multiframe_min_px. False when aggregate_multiframe_fraction is 0.
bool tracks_move_together_multiframe(int multiframe_tested, int multiframe_dynamic, double median_offset_px,
                                     const OutlineConfig& config);

// Reusable buffers (no allocation per call once sizes have settled).
class ObjectOutliner {
 public:
  explicit ObjectOutliner(const OutlineConfig& config = {});
  const OutlineConfig& config() const { return config_; }

  // disparity_px: CV_32FC1 of the ROI (0 = none); origin: the ROI's top-left in the full image. points_px /
  // point_disparity_px: the object's dynamic points (full image). static_px / static_disparity_px: static
  // points (may be empty). ground: the frame's floor in disparity space (nullptr or invalid = none). bf_px_m:
  // focal length x baseline. mask: CV_8UC1 of the ROI, 255 = object. left_roi: the ROI of the left image
  // (CV_8UC1, the disparity's size; empty = unmeasured pixels are not filled). Returns the statistics.
  OutlineStats outline(const cv::Mat& disparity_px, cv::Point origin, const std::vector<cv::Point2f>& points_px,
                       const std::vector<float>& point_disparity_px, const std::vector<cv::Point2f>& static_px,
                       const std::vector<float>& static_disparity_px, const DisparityPlane* ground, double bf_px_m,
                       cv::Mat& mask, const cv::Mat& left_roi = cv::Mat());

 private:
  struct Seed {
    float lo = 0, hi = 0;  // the seed's depth band, in disparity
  };
  // The floor plane's column and row terms over the ROI (ground_x_, ground_y_); ground_ null: no floor test.
  void prepare_floor(const DisparityPlane* ground, cv::Point origin, int w, int h);
  bool is_floor(int x, int y, float d) const;
  // Seeds the flood at the pixel within seed_radius_px of point p whose disparity agrees with d (and is no floor),
  // nearest first; false when there is none or it is claimed already.
  bool add_seed(const cv::Mat& disparity_px, cv::Point origin, double bf_px_m, const cv::Point2f& p, float d,
                uint8_t label);
  // Breadth-first from all seeds at once through smooth disparity within each seed's depth band.
  void flood(const cv::Mat& disparity_px);
  // Adds the unmeasured runs below the outline down to the floor and between outline pixels in a row (see above).
  void fill_unmeasured(const cv::Mat& disparity_px, const cv::Mat& left_roi, cv::Point origin, double bf_px_m,
                       cv::Mat& mask);
  // Fills the enclosed parts of `mask` (complement components not reaching the ROI border) that are mostly without
  // disparity or small.
  void fill_enclosed(const cv::Mat& disparity_px, cv::Mat& mask);
  // Median disparity of the mask's pixels (0 without any).
  float median_disparity(const cv::Mat& disparity_px, const cv::Mat& mask);

  OutlineConfig config_;
  const DisparityPlane* ground_ = nullptr;  // during outline(): the floor, when used
  std::vector<int> queue_;
  std::vector<uint8_t> label_;               // 0 unvisited, 1 object, 2 static
  std::vector<double> ground_x_, ground_y_;  // the floor plane's column and row terms over the ROI
  std::vector<int32_t> seed_of_;             // per claimed pixel: its seed
  std::vector<Seed> seeds_;
  std::vector<uint8_t> fill_;
  std::vector<float> disparities_;
  std::vector<int> disparity_bins_;
  cv::Mat holes_, hole_labels_, hole_stats_, hole_centroids_, eroded_;
  cv::Mat gradient_, texture_, passable_, added_;
  std::vector<int> invalid_count_;
};

}  // namespace agvslam::dynamic
