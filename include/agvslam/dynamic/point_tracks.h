#pragma once
// The detector's point tracks over frames and the per-point motion tests (paper 004 III.A plus the depth and
// multi-frame tests): LK of the tracks into each frame (forward-backward checked), their disparity, the epipolar,
// depth-consistency and multi-frame tests, the tracks' histories, and after each frame the tracks that continue and
// the quadtree FAST corners that fill the places no track covers. Points added beside the tracks (densification,
// the left band's driving seeds) are tested and appended here too.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/epipolar.h"
#include "agvslam/dynamic/multiframe_test.h"
#include "agvslam/dynamic/quadtree_fast.h"
#include "agvslam/stereo/sparse_stereo.h"

namespace agvslam::dynamic {

// The frame's dynamic points, in the order they were flagged: image position, disparity and row of
// DetectorResult::points. Grouping, densification and coasting read and extend it.
struct DynamicPoints {
  std::vector<cv::Point2f> px;
  std::vector<float> disparity_px;
  std::vector<int> index;

  std::size_t size() const { return px.size(); }
  void clear();
  void add(const TrackedPoint& p, int point_index);
};

// What PointTracks needs from params/dynamic.yaml (its stages' own sections and the two detector.use_* switches).
struct PointTracksConfig {
  QuadtreeFastConfig features;
  LkTrackerConfig tracking;
  EpipolarTestConfig epipolar;
  DepthTestConfig depth_test;
  MultiFrameTestConfig multiframe;
  bool use_epipolar_test = true;
  bool use_depth_test = true;
};

class PointTracks {
 public:
  // calibration: of the rectified frames; sparse: the point matcher (stereo.yaml sparse).
  PointTracks(const PointTracksConfig& config, const StereoCalibration& calibration,
              const stereo::SparseStereoConfig& sparse);

  // Forgets every track and the previous frame's pyramid.
  void reset();
  // Whether the previous frame left tracks to follow, and the size of that frame (empty: none).
  bool has_tracks() const { return !prev_pts_.empty(); }
  cv::Size previous_size() const { return prev_pyramid_.empty() ? cv::Size() : prev_pyramid_.front().size(); }

  // The LK pyramid of this frame's left image (timings.pyramid_ms).
  void build_pyramid(const cv::Mat& left, StageTimings& timings);
  // LK of the tracks into `frame`, their disparities (from full_disparity_px when not empty, else the sparse
  // matcher), the epipolar, depth and multi-frame tests into result.epipolar / depth / multiframe, result.lk_levels
  // and the timings; the tracks' histories move to this frame.
  void track_and_test(const StereoFrame& frame, DetectorResult& result);
  // result.points from the tests (one per track); the dynamic ones into `dynamic`.
  void collect_points(DetectorResult& result, DynamicPoints& dynamic) const;

  // A point this frame adds beside the tracks, followed from prev_px to cur_px: the frame's epipolar and depth tests
  // on it; its multi-frame result comes from the caller.
  TrackedPoint test_new_point(const DetectorResult& result, const cv::Point2f& prev_px, const cv::Point2f& cur_px,
                              float prev_disparity_px, float cur_disparity_px, double multiframe_px,
                              bool dynamic_multiframe) const;
  // Appends such a point to result.points and to the track histories (and, when dynamic, to `dynamic`).
  void append_new_point(const TrackedPoint& p, DetectorResult& result, DynamicPoints& dynamic);
  // The union of the enabled tests (detector.use_epipolar_test, use_depth_test) on a point's flags.
  bool flagged_by_enabled_tests(const TrackedPoint& p) const;

  // LK of `prev_px` from the previous frame's pyramid into this frame's, on `levels` levels.
  void track_points(const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& cur_px, std::vector<uint8_t>& ok,
                    int levels);
  // The sparse matcher's disparity at `px` of a stereo pair (0 = none).
  float match_disparity(const cv::Mat& left, const cv::Mat& right, const cv::Point2f& px);
  // The multi-frame test's depth-edge and stereo checks of a point of `frame` with this disparity
  // (multiframe.edge_check_*, check_*): true when its window straddles a depth edge or its match is missing or
  // ambiguous.
  bool on_depth_edge_or_ambiguous(const StereoFrame& frame, const cv::Point2f& px, float disparity_px);

  // After the frame's mask: the tracks that held continue (densified ones only when dynamic, or with
  // keep_static_densified), and this frame's quadtree corners fill the places no track covers (timings.features_ms,
  // point_disparity_ms). Then tracks() are this frame's positions.
  void replenish(const StereoFrame& frame, DetectorResult& result, bool keep_static_densified);
  // This frame's pyramid becomes the previous one.
  void end_frame() { std::swap(prev_pyramid_, cur_pyramid_); }

  // The tracks' positions in the previous frame (before track_and_test) or this one (after replenish).
  const std::vector<cv::Point2f>& tracks() const { return prev_pts_; }
  const TrackHistory& history() const { return history_; }
  const DepthConsistencyTest& depth_test() const { return depth_test_; }
  LkTracker& lk() { return tracker_; }
  const std::vector<cv::Mat>& prev_pyramid() const { return prev_pyramid_; }
  const std::vector<cv::Mat>& cur_pyramid() const { return cur_pyramid_; }

 private:
  void measure_disparities(const StereoFrame& frame, const std::vector<cv::Point2f>& px,
                           const std::vector<uint8_t>* usable, const cv::Mat& full_disparity_px,
                           std::vector<float>& out);
  // Where each track's LK search starts: where the motion prior puts it as a static point, when that is far enough
  // from its previous position (tracking.predict_min_px); false when no track needs it.
  bool predicted_starts();
  // Follows the tracks into this frame and chooses the next frame's LK levels from their largest motion (from where
  // each search started).
  void follow_tracks(DetectorResult& result);
  // Drops the tracks whose match is ambiguous under this frame's motion (depth_test.leaving_margin_px, slip_*).
  void drop_ambiguous_tracks(const StereoFrame& frame, DetectorResult& result);
  // The histories' step to this frame, then the multi-frame test and its depth-edge check.
  void test_multiframe(const StereoFrame& frame, DetectorResult& result);
  // The tracks kept into the next frame (prev_pts_ and the histories).
  void retain_tracks(const DetectorResult& result, bool keep_static_densified);
  // This frame's quadtree corners at least tracking.min_track_distance_px from every track, into new_pts_.
  void select_new_corners(const cv::Mat& left);

  PointTracksConfig config_;
  StereoCalibration calibration_;
  QuadtreeFast features_;
  LkTracker tracker_;
  EpipolarTest epipolar_;
  DepthConsistencyTest depth_test_;
  MultiFrameTest multiframe_;
  TrackHistory history_;  // the tracks' last observations; row i = prev_pts_[i] (then result.points[i])
  stereo::SparseStereoMatcher sparse_;
  stereo::SparseStereoMatcher check_sparse_;  // larger window, stricter uniqueness (multiframe.check_*)

  std::vector<cv::Mat> prev_pyramid_, cur_pyramid_;
  std::vector<cv::Point2f> prev_pts_;     // the tracks in the previous frame
  std::vector<float> prev_disparity_px_;  // their disparity there (0 = none)
  std::vector<cv::Point2f> cur_pts_;      // ... followed into this frame
  std::vector<uint8_t> tracked_;
  std::vector<float> cur_disparity_px_;
  double last_max_motion_px_ = -1;  // the previous frame's largest track motion (-1: unknown), for its LK levels
  // The last frame's ego-motion (previous -> current camera) from the depth test, the prior of the next frame's
  // LK starts (tracking.predict_min_px); none after a frame without one.
  SE3d T_motion_prior_ = SE3d::Identity();
  bool has_motion_prior_ = false;
  std::vector<cv::Point2f> lk_start_;            // where each track's search starts (empty: at its old position)
  std::vector<std::vector<std::size_t>> split_;  // tracks searched from the old position / from a prediction
  std::vector<cv::Point2f> part_prev_, part_start_, part_cur_;
  std::vector<uint8_t> part_ok_;

  // Scratch of replenish().
  std::vector<uint8_t> consistent_, keep_;
  std::vector<Corner> corners_;
  std::vector<cv::Point2f> new_pts_;
  std::vector<float> new_disp_;
  std::vector<int> cell_start_, cell_fill_;  // the tracks binned for the new corners' distance test
  std::vector<cv::Point2f> cell_points_;
};

}  // namespace agvslam::dynamic
