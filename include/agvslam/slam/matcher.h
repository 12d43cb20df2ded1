#pragma once
// Descriptor matching between frames, keyframes and map points (ORB-SLAM2's ORBmatcher, stereo).
//
// Thresholds are ORB-SLAM2's: a match needs a Hamming distance <= 100 (projection searches, where geometry has
// already narrowed the candidates) or <= 50 (searches without a pose prior and fusion); the rotation-consistency
// check keeps the matches whose keypoint angle difference falls in the three most populated of 30 bins.
//
// The searches that ORB-SLAM2 runs with the bag-of-words vocabulary (reference keyframe, triangulation) are
// replaced here by a brute-force ratio test and an epipolar-segment search; issue 5's vocabulary can take
// over once keyframes carry BowData.
//
// All functions expect the Map's mutex to be held by the caller.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "agvslam/slam/frame.h"
#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

class Map;

constexpr int kMatchThresholdHigh = 100;
constexpr int kMatchThresholdLow = 50;

// Reusable buffers of the matcher (one per thread: no per-call allocation once sizes settle).
class Matcher {
 public:
  // Projects the last frame's (inlier) map points into `current` with its predicted pose and matches them within
  // radius_px x scale of the level (ORB-SLAM2's SearchByProjection(Frame, Frame) with the stereo forward/backward
  // level rule and the right-image check). ratio < 1 adds a best-to-second-best test (for wide windows).
  // Returns the number of new matches.
  int search_last_frame(Frame& current, const Frame& last, float radius_px, bool check_orientation, float ratio = 1.0f);

  // Local map points (with track scratch filled by Frame::is_in_frustum) into the frame, within radius_factor x
  // the viewing-angle window x scale, best-to-second ratio 0.8 at the same level (ORB-SLAM2's
  // SearchByProjection(Frame, vector<MapPoint*>)).
  int search_local_points(Frame& frame, const std::vector<MapPoint*>& points, float radius_factor);

  // Brute force: the keyframe's map points against all of the frame's keypoints (distance <= 50, Lowe ratio,
  // rotation consistency). Fills matches (per frame keypoint, null = none). Returns the count.
  int search_keyframe_brute_force(const KeyFrame& kf, const Frame& frame, float ratio,
                                  std::vector<MapPointPtr>& matches);

  // Keypoints of kf1 and kf2 without map points that agree with the epipolar geometry (F12: x1^T F12 x2 = 0):
  // each kf1 keypoint is searched along the segment of its epipolar line in kf2 that its depth range allows (the
  // stereo depth +- 2 px of disparity when it has one). Pairs (index in kf1, index in kf2).
  int search_for_triangulation(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F12,
                               std::vector<std::pair<int, int>>& matches);

  // Projects the points into kf and fuses them with what is there (ORB-SLAM2's Fuse): a point lands on an
  // unmatched keypoint as a new observation, or replaces / is replaced by the keypoint's point (the one with
  // more views survives). Returns the number fused.
  int fuse(KeyFrame& kf, const std::vector<MapPointPtr>& points, float radius_factor, Map& map);

 private:
  void reset_rotation_histogram();
  void add_to_histogram(float angle_diff_deg, int index);
  // Indices of matches outside the three most populated bins.
  void rotation_outliers(std::vector<int>& out) const;

  static constexpr int kHistogramBins = 30;
  std::vector<int> histogram_[kHistogramBins];
  std::vector<int> candidates_;
  std::vector<int> best_dist_;
  std::vector<int> best_index_;
  std::vector<int> stamp_;
  std::vector<int> rejected_;
};

// ORB-SLAM2's RadiusByViewingCos: 2.5 when the point is seen almost head-on (cos > 0.998), 4 otherwise.
inline float radius_by_viewing_cos(float view_cos) { return view_cos > 0.998f ? 2.5f : 4.0f; }

}  // namespace agvslam::slam
