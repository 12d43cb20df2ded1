#pragma once
// Densification (beyond the paper): a small object gets only a few of the quadtree's points, fewer than a ROI needs.
// Around each small group of seed points (dynamic points with strong evidence), extra FAST corners of the previous
// frame are tracked into this one and tested with this frame's F, motion and thresholds, and (having no history of
// their own) against the multi-frame reference by LK into that image. The points join the frame's points and the
// track histories.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/point_tracks.h"
#include "agvslam/dynamic/quadtree_fast.h"
#include "agvslam/dynamic/roi_grouping.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `densify`.
struct DensifyOptions {
  bool enabled = true;
  // The window around a group: its seeds' bounding box (previous frame) grown by radius_px +
  // radius_disparity_factor * the group's mean disparity (px).
  double radius_px = 24;
  double radius_disparity_factor = 1.0;
  int max_points = 24;         // extra corners per group
  double min_distance_px = 5;  // from existing tracks and from each other
  // Seed points a group needs (grouping's eq. 4 with this minimum); isolated single points are usually noise.
  int min_seeds = 2;
  // Seeds are the points both per-frame tests flag (when both ran: a track that slid along an edge fools one, rarely
  // both) and those the multi-frame test flags; a point only the depth test flags seeds when its offset is at least
  // this many times that test's threshold (a far person walking along the epipolar lines; 0 = never).
  double depth_seed_factor = 1.5;
  // Persistent tracks keep tracking.max_tracks full, so densified ones may go this far beyond it (0: none).
  int extra_tracks = 150;
  bool keep_static = false;  // densified tracks the tests pass as static continue into the next frame
  // A densified point's multi-frame test: its patch is tracked by LK (this many pyramid levels) from this frame into
  // the multi-frame reference, starting where a static point at its current disparity would be there; it is dynamic
  // when found farther from that prediction than multiframe_factor times the multi-frame test's threshold (a whole
  // far surface can be off by about one threshold) and its offset agrees with its group's (the median of its seeds'
  // reference observations against the same prediction) within max(threshold, multiframe_agreement x the group's
  // offset), not on a depth edge or an ambiguous match (multiframe.edge_check_*, check_*). -1 = off.
  int multiframe_levels = 2;
  double multiframe_agreement = 0.35;
  double multiframe_factor = 3.0;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// What the densifier reads beside its own section.
struct DensifierContext {
  QuadtreeFastConfig features;  // min_threshold: the corners' FAST threshold; border_px: none nearer the border
  RoiGroupingConfig grouping;   // groups of seeds; grouping.min_points: a group that is a ROI already
  LkTrackerConfig tracking;     // tracking.max_tracks and the LK parameters of the multi-frame check
  MultiFrameTestConfig multiframe;
  bool use_epipolar_test = true;
  bool use_depth_test = true;
};

class Densifier {
 public:
  Densifier(const DensifyOptions& options, const DensifierContext& context, const StereoCalibration& calibration);

  // Adds the densified points of `frame` (prev_left / prev_right: the previous frame) to result.points and to the
  // tracks' histories; the dynamic ones to `dynamic`. The seeds are `dynamic` on entry.
  void densify(const StereoFrame& frame, const cv::Mat& prev_left, const cv::Mat& prev_right, PointTracks& tracks,
               DynamicPoints& dynamic, DetectorResult& result);

 private:
  // The seed points among `dynamic` into seed_*; false when they are fewer than min_seeds.
  bool select_seeds(const DetectorResult& result, const PointTracks& tracks, const DynamicPoints& dynamic);
  // Whether group g of seeds needs points: not a ROI already, and not beside enough dynamic points to be one.
  bool needs_points(const DynamicGroup& g, const DynamicPoints& dynamic) const;
  // The median offset of the group's seeds' multi-frame reference observations from where static points at their
  // current disparity would have been; false when fewer than min_seeds have one.
  bool group_reference_motion(const DynamicGroup& g, const DetectorResult& result, const PointTracks& tracks,
                              cv::Point2f& motion);
  // FAST corners of the previous frame around the group, away from the tracks and each other, into extra_prev_.
  void add_corners(const DynamicGroup& g, const cv::Mat& prev_left, const cv::Rect& inner, const DetectorResult& result,
                   const PointTracks& tracks);
  // The multi-frame test of the densified points, into extra_mf_ / extra_mf_px_.
  void test_multiframe(const StereoFrame& frame, const DetectorResult& result, PointTracks& tracks);
  // ... its LK from this frame into the reference image, starting at the predictions (mf_cur_, mf_pred_ -> mf_ref_,
  // mf_back_, statuses).
  void track_into_reference(const cv::Mat& cur_left, const cv::Mat& ref_left);
  // ... and its decision for the point mf_index_[k], found at mf_ref_[k].
  bool moved_with_group(std::size_t k, const StereoFrame& frame, const DetectorResult& result, PointTracks& tracks);

  DensifyOptions options_;
  DensifierContext context_;
  StereoCalibration calibration_;

  // Per call.
  std::vector<cv::Point2f> seed_pts_;
  std::vector<float> seed_disp_;
  std::vector<int> seed_index_;
  std::vector<cv::KeyPoint> keypoints_;
  std::vector<cv::Point2f> extra_prev_, extra_cur_;  // the densified points in the previous and this frame
  std::vector<uint8_t> extra_ok_;
  std::vector<float> extra_prev_disp_, extra_cur_disp_;
  std::vector<cv::Point2f> extra_group_motion_;  // per densified point: its group's reference motion ...
  std::vector<uint8_t> extra_group_valid_;       // ... when known
  std::vector<uint8_t> extra_mf_;                // per densified point: dynamic by the multi-frame check
  std::vector<double> extra_mf_px_;              // ... its offset (-1: not tested)
  std::vector<float> mf_vx_, mf_vy_;
  std::vector<cv::Point2f> mf_cur_, mf_ref_, mf_back_, mf_pred_;
  std::vector<int> mf_index_;
  std::vector<uint8_t> mf_status_, mf_back_status_;
  std::vector<float> mf_errors_;
  std::vector<cv::Mat> mf_cur_pyramid_, mf_ref_pyramid_;
};

}  // namespace agvslam::dynamic
