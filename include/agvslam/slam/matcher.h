#pragma once
// Descriptor matching between frames, keyframes and map points (ORB-SLAM2's ORBmatcher, stereo).
//
// Thresholds are ORB-SLAM2's: a match needs a Hamming distance <= 100 (projection searches, where geometry has
// already narrowed the candidates) or <= 50 (searches without a pose prior and fusion); the rotation-consistency
// check keeps the matches whose keypoint angle difference falls in the three most populated of 30 bins.
//
// The bag-of-words searches (ORB-SLAM2's SearchByBoW) compare only features that pass through the same vocabulary
// node at the direct index's level (KeyFrame::bow.features, Frame::bow_features); both sides must have their BoW
// computed with the same vocabulary and level. Brute-force and epipolar-segment variants remain for maps without
// a vocabulary (and as references in tests and benchmarks).
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

  // Bag of words: the keyframe's map points against the frame's keypoints in the same vocabulary node (distance
  // <= 50, best-to-second ratio, rotation consistency; ORB-SLAM2's SearchByBoW(KeyFrame, Frame)). Fills matches
  // (per frame keypoint, null = none). Returns the count.
  int search_by_bow(const KeyFrame& kf, const Frame& frame, float ratio, std::vector<MapPointPtr>& matches);

  // Bag of words between two keyframes' map points (ORB-SLAM2's SearchByBoW(KeyFrame, KeyFrame), for loop
  // detection): matches12[i1] = kf2's point matched with kf1's keypoint i1 (null = none). Returns the count.
  int search_by_bow(const KeyFrame& kf1, const KeyFrame& kf2, float ratio, std::vector<MapPointPtr>& matches12);

  // Relocalisation: projects the keyframe's map points (not in `already`: per frame keypoint, the matches so far;
  // a point already matched somewhere in the frame is skipped) into the frame with its current pose and matches
  // them within radius_px x scale, levels predicted +-1, distance <= max_distance, rotation consistency (ORB-SLAM2's
  // SearchByProjection(Frame, KeyFrame, ...)). New matches go into frame.map_points. Returns their count.
  int search_keyframe_projection(Frame& frame, const KeyFrame& kf, float radius_px, int max_distance);

  // Loop closing: projects `points` into kf with the pose T_c_w (the loop-corrected one) and matches them with
  // keypoints that have no entry in `matched` yet (ORB-SLAM2's SearchByProjection(KeyFrame, Sim3, ...)); levels
  // predicted -1..0, distance <= 50. matched has one entry per kf keypoint. Returns the number of new matches.
  int search_loop_projection(const KeyFrame& kf, const SE3d& T_c_w, const std::vector<MapPointPtr>& points,
                             float radius_px, std::vector<MapPointPtr>& matched);

  // Loop verification (ORB-SLAM2's SearchBySim3 with scale 1): with T_c1_c2 (kf2's camera in kf1's), projects
  // kf1's points into kf2 and kf2's into kf1 and keeps mutual best matches (distance <= 100) for kf1 keypoints
  // without an entry in matches12. Returns the number of new matches.
  int search_by_se3(const KeyFrame& kf1, const KeyFrame& kf2, const SE3d& T_c1_c2, float radius_px,
                    std::vector<MapPointPtr>& matches12);

  // Loop fusion (ORB-SLAM2's Fuse(KeyFrame, Sim3, ...)): projects `points` with T_c_w into kf; where the best
  // keypoint (distance <= 50) already has a point, replace[k] receives it (the caller replaces it by points[k]);
  // otherwise points[k] gains the observation. replace is resized to points.size(). Returns the number fused.
  int fuse_with_pose(KeyFrame& kf, const SE3d& T_c_w, const std::vector<MapPointPtr>& points, float radius_px,
                     std::vector<MapPointPtr>& replace);

  // Bag-of-words variant of search_for_triangulation (ORB-SLAM2's SearchForTriangulation): keypoints without map
  // points in the same vocabulary node, distance <= 50, within 3.84 sigma^2 of the epipolar line, away from the
  // epipole unless one has stereo, rotation consistency.
  int search_for_triangulation_bow(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F12,
                                   std::vector<std::pair<int, int>>& matches);

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
  // Clears the matches at the rotation outliers; returns how many it cleared.
  int drop_rotation_outliers(std::vector<MapPointPtr>& matches);

  static constexpr int kHistogramBins = 30;
  std::vector<int> histogram_[kHistogramBins];
  std::vector<int> candidates_;
  std::vector<int> best_dist_;
  std::vector<int> best_index_;
  std::vector<int> stamp_;
  std::vector<int> rejected_;
  std::vector<uint8_t> taken_;
};

// ORB-SLAM2's RadiusByViewingCos: 2.5 when the point is seen almost head-on (cos > 0.998), 4 otherwise.
inline float radius_by_viewing_cos(float view_cos) { return view_cos > 0.998f ? 2.5f : 4.0f; }

}  // namespace agvslam::slam
