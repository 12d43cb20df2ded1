#include "agvslam/slam/map.h"

#include <algorithm>

namespace agvslam::slam {

Map::~Map() { clear(); }

void Map::add_keyframe(const KeyFramePtr& kf) {
  if (keyframes_.empty() && origin_id_ == UINT64_MAX) {
    origin_id_ = kf->id;
    kf->mark_origin();
  }
  keyframes_[kf->id] = kf;
}

void Map::add_map_point(const MapPointPtr& point) { map_points_[point->id] = point; }

void Map::erase_keyframe(const KeyFrame* kf) { keyframes_.erase(kf->id); }

void Map::erase_map_point(const MapPoint* point) { map_points_.erase(point->id); }

KeyFramePtr Map::keyframe(uint64_t id) const {
  const auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second;
}

MapPointPtr Map::map_point(uint64_t id) const {
  const auto it = map_points_.find(id);
  return it == map_points_.end() ? nullptr : it->second;
}

std::vector<KeyFramePtr> Map::keyframes() const {
  std::vector<KeyFramePtr> out;
  out.reserve(keyframes_.size());
  for (const auto& [id, kf] : keyframes_) out.push_back(kf);
  std::sort(out.begin(), out.end(), [](const KeyFramePtr& a, const KeyFramePtr& b) { return a->id < b->id; });
  return out;
}

std::vector<MapPointPtr> Map::map_points() const {
  std::vector<MapPointPtr> out;
  out.reserve(map_points_.size());
  for (const auto& [id, p] : map_points_) out.push_back(p);
  std::sort(out.begin(), out.end(), [](const MapPointPtr& a, const MapPointPtr& b) { return a->id < b->id; });
  return out;
}

MapCounts Map::counts() const {
  MapCounts c;
  c.keyframes = keyframes_.size();
  c.map_points = map_points_.size();
  std::size_t bytes = 0;
  for (const auto& [id, kf] : keyframes_) {
    bytes += sizeof(KeyFrame) +
             kf->size() * (sizeof(cv::KeyPoint) + 32 + 2 * sizeof(float) + sizeof(MapPointPtr) + sizeof(int));
  }
  for (const auto& [id, p] : map_points_) {
    c.observations += p->observations().size();
    bytes += sizeof(MapPoint) + p->observations().size() * sizeof(Observation);
  }
  c.memory_bytes = bytes;
  return c;
}

void Map::record_removed_keyframe(uint64_t id, uint64_t parent_id, const SE3d& T_c_parent) {
  removed_[id] = {parent_id, T_c_parent};
}

bool Map::resolve_pose(uint64_t kf_id, const SE3d& T_c_r, SE3d& T_c_w) const {
  SE3d T = T_c_r;
  uint64_t id = kf_id;
  for (std::size_t guard = 0; guard <= removed_.size() + 1; ++guard) {
    const auto it = keyframes_.find(id);
    if (it != keyframes_.end()) {
      T_c_w = T * it->second->T_c_w();
      return true;
    }
    const auto r = removed_.find(id);
    if (r == removed_.end()) return false;
    T = T * r->second.T_c_parent;
    id = r->second.parent_id;
  }
  return false;
}

void Map::clear() {
  // Break the keyframe -> point shared_ptr links and the raw back-links (a point that a frame still holds must not
  // point at a freed keyframe), so everything is freed.
  std::vector<MapPointPtr> points;
  points.reserve(map_points_.size());
  for (const auto& [id, p] : map_points_) points.push_back(p);
  for (const MapPointPtr& p : points) p->set_bad(*this);
  for (auto& [id, kf] : keyframes_) {
    for (std::size_t i = 0; i < kf->size(); ++i) kf->erase_map_point_match(i);
  }
  keyframes_.clear();
  map_points_.clear();
  removed_.clear();
  origin_id_ = UINT64_MAX;
  ++big_change_;
}

void Map::take_from(Map& other) {
  clear();
  keyframes_ = std::move(other.keyframes_);
  map_points_ = std::move(other.map_points_);
  removed_ = std::move(other.removed_);
  next_keyframe_id_ = other.next_keyframe_id_;
  next_map_point_id_ = other.next_map_point_id_;
  origin_id_ = other.origin_id_;
  other.keyframes_.clear();
  other.map_points_.clear();
  other.removed_.clear();
  other.origin_id_ = UINT64_MAX;
  ++big_change_;
}

}  // namespace agvslam::slam
