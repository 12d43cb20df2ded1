#pragma once
// The map: keyframes and map points, owned by shared_ptr, with one mutex that every thread holds while it reads
// or changes the graph (ORB-SLAM2's mMutexMapUpdate; finer locks are not worth their bugs at this map size: the
// local mapper releases it while Ceres solves and between its steps, so tracking waits at most one step).
//
// Memory stays bounded on long runs over the same area because keyframe culling removes keyframes whose points
// are seen by enough others, map-point culling removes unconfirmed points, and mapping.max_keyframes (when set)
// caps the count. Removed objects are freed as soon as no frame holds them.

#include <cstdint>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

struct MapCounts {
  std::size_t keyframes = 0;
  std::size_t map_points = 0;
  std::size_t observations = 0;  // keyframe-point links
  std::size_t memory_bytes = 0;  // estimate of what the map holds (keypoints, descriptors, points)
};

class Map {
 public:
  Map() = default;
  ~Map();
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  std::mutex& mutex() { return mutex_; }

  // All of the following require mutex() to be held by the caller.
  uint64_t new_keyframe_id() { return next_keyframe_id_++; }
  uint64_t new_map_point_id() { return next_map_point_id_++; }
  void add_keyframe(const KeyFramePtr& kf);
  void add_map_point(const MapPointPtr& point);
  void erase_keyframe(const KeyFrame* kf);
  void erase_map_point(const MapPoint* point);
  KeyFramePtr keyframe(uint64_t id) const;
  MapPointPtr map_point(uint64_t id) const;
  std::vector<KeyFramePtr> keyframes() const;   // sorted by id
  std::vector<MapPointPtr> map_points() const;  // sorted by id
  std::size_t keyframe_count() const { return keyframes_.size(); }
  std::size_t map_point_count() const { return map_points_.size(); }
  MapCounts counts() const;
  // The first keyframe (the world frame's origin); never culled.
  uint64_t origin_keyframe_id() const { return origin_id_; }
  // Changed on events that move many poses at once (reset, loop closure, map load).
  uint64_t big_change_index() const { return big_change_; }
  void notify_big_change() { ++big_change_; }

  // Where a removed keyframe was relative to its parent, so that poses stored relative to it can still be
  // resolved (a few dozen bytes per removed keyframe).
  void record_removed_keyframe(uint64_t id, uint64_t parent_id, const SE3d& T_c_parent);
  // T_c_w of a pose given relative to keyframe kf_id (T_c_r), following removed keyframes to their parents.
  // False when the chain ends nowhere (after a reset).
  bool resolve_pose(uint64_t kf_id, const SE3d& T_c_r, SE3d& T_c_w) const;

  // Removes everything, breaking the references between keyframes and points so that all of it is freed.
  void clear();
  // Replaces the contents with other's (a map read from a file), which is left empty; counts as a big change.
  void take_from(Map& other);

 private:
  friend struct MapFileAccess;  // map_io.cpp reads and restores the counters and removed-keyframe records
  std::mutex mutex_;
  std::unordered_map<uint64_t, KeyFramePtr> keyframes_;
  std::unordered_map<uint64_t, MapPointPtr> map_points_;
  struct RemovedKeyFrame {
    uint64_t parent_id;
    SE3d T_c_parent;
  };
  std::unordered_map<uint64_t, RemovedKeyFrame> removed_;
  uint64_t next_keyframe_id_ = 0;
  uint64_t next_map_point_id_ = 0;
  uint64_t origin_id_ = UINT64_MAX;
  uint64_t big_change_ = 0;
};

}  // namespace agvslam::slam
