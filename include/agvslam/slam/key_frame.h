#pragma once
// A keyframe: a frame kept in the map, with its map points, its covisibility edges (keyframes sharing at least
// 15 map points, weighted by their count), its place in the spanning tree, and a slot for the bag-of-words
// vector that the place-recognition module attaches.
//
// Threads: read and written with the Map's mutex held (see map_point.h), except the `mapping` and `track`
// scratch. Keyframes refer to each other by raw pointer; KeyFrame::set_bad removes every reference to itself
// (covisibility, spanning tree, map points) before the map drops it.
//
// Serialisation (map_io.h): id, frame id, time, pose, keypoints, descriptors, stereo (u_right, depth), map point
// ids per keypoint, parent id, loop-edge ids and the covisibility lists are saved as they are; the bag of words is
// recomputed with the vocabulary the file names.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/core/se3.h"
#include "agvslam/slam/frame.h"

namespace agvslam::slam {

class Map;

// Bag-of-words data of a keyframe (place::Vocabulary::transform of its descriptors; see place_recognition.h).
struct BowData {
  place::BowVector words;         // L1-normalised TF-IDF vector
  place::FeatureVector features;  // direct index: vocabulary node (at features.level) -> keypoint indices
  uint64_t vocabulary_id = 0;     // identity of the vocabulary that produced it, 0 = not computed
  bool computed() const { return vocabulary_id != 0; }
};

struct MapFileAccess;

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(uint64_t id, const Frame& frame);

  const uint64_t id;
  const uint64_t frame_id;
  const int64_t t_ns;
  const FrameGeometryPtr geometry;

  // Features (copied from the frame; constant).
  const std::vector<cv::KeyPoint> keypoints;
  const cv::Mat descriptors;
  const std::vector<float> u_right;
  const std::vector<float> depth;
  FeatureGrid grid;

  std::size_t size() const { return keypoints.size(); }
  const uint8_t* descriptor(std::size_t i) const { return descriptors.ptr<uint8_t>(static_cast<int>(i)); }
  bool has_depth(std::size_t i) const { return depth[i] > 0; }
  bool is_close(std::size_t i) const { return depth[i] > 0 && depth[i] < geometry->close_depth_m; }
  Eigen::Vector3d unproject_stereo(std::size_t i) const;

  // Pose.
  void set_pose(const SE3d& T_c_w);
  const SE3d& T_c_w() const { return T_c_w_; }
  const SE3d& T_w_c() const { return T_w_c_; }
  Eigen::Vector3d center_w() const { return T_w_c_.translation(); }

  // Map points per keypoint (null = none).
  const std::vector<MapPointPtr>& map_points() const { return map_points_; }
  const MapPointPtr& map_point(std::size_t i) const { return map_points_[i]; }
  void add_map_point(const MapPointPtr& point, std::size_t index) { map_points_[index] = point; }
  void erase_map_point_match(std::size_t index) { map_points_[index].reset(); }
  void erase_map_point_match(const MapPoint* point);
  void replace_map_point_match(std::size_t index, const MapPointPtr& point) { map_points_[index] = point; }
  // Keypoints that observed a retired map point (an object that moved away): they never carry a map point again,
  // so neither fusion nor triangulation brings the object back from keyframes made while it stood there.
  void retire_keypoint(std::size_t index);
  bool keypoint_retired(std::size_t index) const { return !retired_.empty() && retired_[index] != 0; }
  std::size_t retired_keypoint_count() const;
  // Map points that are not bad and are seen by at least min_observations keyframes.
  int tracked_map_points(int min_observations) const;

  // Covisibility graph.
  void update_connections();  // recomputes the edges from the map points (ORB-SLAM2's UpdateConnections)
  void add_connection(KeyFrame* kf, int weight);
  void erase_connection(KeyFrame* kf);
  std::vector<KeyFrame*> best_covisibles(std::size_t n) const;
  const std::vector<KeyFrame*>& covisibles() const { return ordered_neighbours_; }  // best first
  // Every keyframe sharing at least one map point (also below the edge threshold), with the count.
  const std::vector<std::pair<KeyFrame*, int>>& connections() const { return connections_; }
  std::vector<KeyFrame*> covisibles_with_weight(int min_weight) const;
  int weight(const KeyFrame* kf) const;

  // Spanning tree and loop edges.
  KeyFrame* parent() const { return parent_; }
  // Pose relative to the parent at the moment the keyframe was removed (trajectory output for frames whose
  // reference keyframe was culled follows these up to a keyframe in the map, as ORB-SLAM2 does).
  const SE3d& T_c_parent() const { return T_c_parent_; }
  const std::vector<KeyFrame*>& children() const { return children_; }
  void change_parent(KeyFrame* kf);
  void add_child(KeyFrame* kf);
  void erase_child(KeyFrame* kf);
  const std::vector<KeyFrame*>& loop_edges() const { return loop_edges_; }
  void add_loop_edge(KeyFrame* kf);

  BowData bow;
  // Computes `bow` (no-op when already computed with this vocabulary and level).
  void compute_bow(const place::Vocabulary& vocabulary, int direct_index_level);

  bool bad() const { return bad_; }
  // The map's first keyframe (the world origin; no parent, never culled).
  void mark_origin() { origin_ = true; }
  bool is_origin() const { return origin_; }
  // Keyframes that loop closing is working with are protected from culling; release_not_erase() lifts the
  // protection unless the keyframe has loop edges (which protect it for good, as in ORB-SLAM2).
  void set_not_erase(bool value) { not_erase_ = value; }
  void release_not_erase() { not_erase_ = !loop_edges_.empty(); }
  bool not_erase() const { return not_erase_; }
  // Removes the keyframe from the graph: its map points lose the observation, covisibility edges are erased, its
  // children are re-attached to the spanning tree, and the map forgets it. The origin keyframe is never removed.
  void set_bad(Map& map);

  // Local-mapping-thread scratch.
  struct MappingScratch {
    uint64_t ba_local_for_kf = UINT64_MAX;
    uint64_t ba_fixed_for_kf = UINT64_MAX;
    uint64_t fuse_target_for_kf = UINT64_MAX;
  } mapping;
  // Tracking-thread scratch.
  struct TrackScratch {
    uint64_t local_for_frame = UINT64_MAX;
  } track;

 private:
  friend struct MapFileAccess;  // map_io.cpp restores the graph exactly as saved
  void update_best_covisibles();

  SE3d T_c_w_ = SE3d::Identity();
  SE3d T_w_c_ = SE3d::Identity();
  std::vector<MapPointPtr> map_points_;
  std::vector<uint8_t> retired_;  // per keypoint, allocated on the first retirement
  std::vector<std::pair<KeyFrame*, int>> connections_;
  std::vector<KeyFrame*> ordered_neighbours_;
  std::vector<int> ordered_weights_;
  KeyFrame* parent_ = nullptr;
  SE3d T_c_parent_ = SE3d::Identity();
  std::vector<KeyFrame*> children_;
  std::vector<KeyFrame*> loop_edges_;
  bool first_connection_ = true;
  bool bad_ = false;
  bool not_erase_ = false;
  bool origin_ = false;
};

}  // namespace agvslam::slam
