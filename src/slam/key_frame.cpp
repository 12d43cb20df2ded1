#include "agvslam/slam/key_frame.h"

#include <algorithm>
#include <set>
#include <unordered_map>

#include "agvslam/place/vocabulary.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

namespace {
constexpr int kCovisibilityMinWeight = 15;  // ORB-SLAM2: an edge needs at least 15 shared map points
}

KeyFrame::KeyFrame(uint64_t kf_id, const Frame& frame)
    : id(kf_id),
      frame_id(frame.id),
      t_ns(frame.t_ns),
      geometry(frame.geometry),
      keypoints(frame.keypoints),
      descriptors(frame.descriptors.clone()),
      u_right(frame.u_right),
      depth(frame.depth),
      grid(frame.grid),
      map_points_(frame.map_points) {
  set_pose(frame.T_c_w());
  if (frame.has_bow) {
    bow.words = frame.bow;
    bow.features = frame.bow_features;
    bow.vocabulary_id = frame.bow_vocabulary_id;
  }
}

void KeyFrame::compute_bow(const place::Vocabulary& vocabulary, int direct_index_level) {
  if (bow.computed() && bow.vocabulary_id == vocabulary.identity() && bow.features.level == direct_index_level) return;
  vocabulary.transform(descriptors, bow.words, bow.features, direct_index_level);
  bow.vocabulary_id = vocabulary.identity();
}

Eigen::Vector3d KeyFrame::unproject_stereo(std::size_t i) const {
  const cv::Point2f& pt = keypoints[i].pt;
  return T_w_c_ * geometry->camera.unproject({pt.x, pt.y}, depth[i]);
}

void KeyFrame::set_pose(const SE3d& T_c_w) {
  T_c_w_ = T_c_w;
  T_w_c_ = T_c_w.inverse();
}

void KeyFrame::erase_map_point_match(const MapPoint* point) {
  const int idx = point->index_in(this);
  if (idx >= 0) map_points_[static_cast<std::size_t>(idx)].reset();
}

void KeyFrame::retire_keypoint(std::size_t index) {
  if (retired_.empty()) retired_.assign(keypoints.size(), 0);
  retired_[index] = 1;
  map_points_[index].reset();
}

std::size_t KeyFrame::retired_keypoint_count() const {
  return static_cast<std::size_t>(std::count(retired_.begin(), retired_.end(), uint8_t{1}));
}

int KeyFrame::tracked_map_points(int min_observations) const {
  int n = 0;
  for (const MapPointPtr& p : map_points_) {
    if (!p || p->bad()) continue;
    if (min_observations > 0 && p->observation_count() < min_observations) continue;
    ++n;
  }
  return n;
}

void KeyFrame::update_connections() {
  std::unordered_map<KeyFrame*, int> counter;
  for (const MapPointPtr& p : map_points_) {
    if (!p || p->bad()) continue;
    for (const Observation& o : p->observations()) {
      if (o.keyframe == this || o.keyframe->bad()) continue;
      ++counter[o.keyframe];
    }
  }
  if (counter.empty()) return;
  int max_weight = 0;
  KeyFrame* max_kf = nullptr;
  std::vector<std::pair<int, KeyFrame*>> pairs;
  for (const auto& [kf, w] : counter) {
    if (w > max_weight || (w == max_weight && max_kf != nullptr && kf->id < max_kf->id)) {
      max_weight = w;
      max_kf = kf;
    }
    if (w >= kCovisibilityMinWeight) {
      pairs.emplace_back(w, kf);
      kf->add_connection(this, w);
    }
  }
  if (pairs.empty()) {
    pairs.emplace_back(max_weight, max_kf);
    max_kf->add_connection(this, max_weight);
  }
  // Strongest first; ties by id so the order does not depend on pointer values.
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id < b.second->id;
  });
  connections_.clear();
  for (const auto& [kf, w] : counter) connections_.emplace_back(kf, w);
  ordered_neighbours_.clear();
  ordered_weights_.clear();
  for (const auto& [w, kf] : pairs) {
    ordered_neighbours_.push_back(kf);
    ordered_weights_.push_back(w);
  }
  if (first_connection_ && !origin_) {
    // The spanning tree: the parent is the keyframe sharing the most points.
    first_connection_ = false;
    parent_ = ordered_neighbours_.front();
    parent_->add_child(this);
  }
}

void KeyFrame::add_connection(KeyFrame* kf, int w) {
  bool found = false;
  for (auto& c : connections_) {
    if (c.first == kf) {
      if (c.second == w) return;
      c.second = w;
      found = true;
      break;
    }
  }
  if (!found) connections_.emplace_back(kf, w);
  update_best_covisibles();
}

void KeyFrame::erase_connection(KeyFrame* kf) {
  const auto it = std::find_if(connections_.begin(), connections_.end(), [&](const auto& c) { return c.first == kf; });
  if (it == connections_.end()) return;
  connections_.erase(it);
  update_best_covisibles();
}

void KeyFrame::update_best_covisibles() {
  std::vector<std::pair<int, KeyFrame*>> pairs;
  pairs.reserve(connections_.size());
  for (const auto& [kf, w] : connections_) pairs.emplace_back(w, kf);
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id < b.second->id;
  });
  ordered_neighbours_.clear();
  ordered_weights_.clear();
  for (const auto& [w, kf] : pairs) {
    ordered_neighbours_.push_back(kf);
    ordered_weights_.push_back(w);
  }
}

std::vector<KeyFrame*> KeyFrame::best_covisibles(std::size_t n) const {
  const std::size_t k = std::min(n, ordered_neighbours_.size());
  return {ordered_neighbours_.begin(), ordered_neighbours_.begin() + static_cast<std::ptrdiff_t>(k)};
}

std::vector<KeyFrame*> KeyFrame::covisibles_with_weight(int min_weight) const {
  std::vector<KeyFrame*> out;
  for (std::size_t k = 0; k < ordered_neighbours_.size() && ordered_weights_[k] >= min_weight; ++k) {
    out.push_back(ordered_neighbours_[k]);
  }
  return out;
}

int KeyFrame::weight(const KeyFrame* kf) const {
  for (const auto& [other, w] : connections_) {
    if (other == kf) return w;
  }
  return 0;
}

void KeyFrame::change_parent(KeyFrame* kf) {
  parent_ = kf;
  if (kf) kf->add_child(this);
}

void KeyFrame::add_child(KeyFrame* kf) {
  if (std::find(children_.begin(), children_.end(), kf) == children_.end()) children_.push_back(kf);
}

void KeyFrame::erase_child(KeyFrame* kf) {
  const auto it = std::find(children_.begin(), children_.end(), kf);
  if (it != children_.end()) children_.erase(it);
}

void KeyFrame::add_loop_edge(KeyFrame* kf) {
  not_erase_ = true;
  if (std::find(loop_edges_.begin(), loop_edges_.end(), kf) == loop_edges_.end()) loop_edges_.push_back(kf);
}

void KeyFrame::set_bad(Map& map) {
  if (bad_ || origin_ || id == map.origin_keyframe_id() || not_erase_) return;
  const KeyFramePtr self = shared_from_this();
  if (parent_) {
    T_c_parent_ = T_c_w_ * parent_->T_w_c();
    map.record_removed_keyframe(id, parent_->id, T_c_parent_);
  }
  for (const auto& [kf, w] : connections_) kf->erase_connection(this);
  for (std::size_t i = 0; i < map_points_.size(); ++i) {
    if (map_points_[i]) {
      const MapPointPtr p = map_points_[i];
      p->erase_observation(this, map);
    }
  }
  connections_.clear();
  ordered_neighbours_.clear();
  ordered_weights_.clear();

  // Re-attach the children (ORB-SLAM2): repeatedly pick the (child, candidate parent) pair with the highest
  // covisibility weight, where candidates are the parent and the children already re-attached.
  std::set<KeyFrame*> parent_candidates;
  if (parent_) parent_candidates.insert(parent_);
  std::vector<KeyFrame*> children = children_;
  while (!children.empty()) {
    int best_w = -1;
    KeyFrame* best_child = nullptr;
    KeyFrame* best_parent = nullptr;
    for (KeyFrame* child : children) {
      if (child->bad()) continue;
      for (KeyFrame* cand : child->covisibles()) {
        if (parent_candidates.count(cand) == 0) continue;
        const int w = child->weight(cand);
        if (w > best_w) {
          best_w = w;
          best_child = child;
          best_parent = cand;
        }
      }
    }
    if (best_child == nullptr) break;
    best_child->change_parent(best_parent);
    parent_candidates.insert(best_child);
    children.erase(std::find(children.begin(), children.end(), best_child));
  }
  // Children without a covisible candidate go to this keyframe's parent.
  for (KeyFrame* child : children) child->change_parent(parent_);
  if (parent_) parent_->erase_child(this);
  children_.clear();
  bad_ = true;
  map.erase_keyframe(this);
}

}  // namespace agvslam::slam
