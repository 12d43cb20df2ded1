#include "agvslam/slam/map_point.h"

#include <algorithm>
#include <limits>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map.h"

namespace agvslam::slam {

MapPoint::MapPoint(uint64_t point_id, const Eigen::Vector3d& position_w, KeyFrame* reference, uint64_t frame_id)
    : id(point_id),
      first_keyframe_id(reference ? reference->id : UINT64_MAX),
      first_frame_id(frame_id),
      p_w(position_w),
      reference_keyframe(reference) {}

MapPoint::MapPoint(uint64_t point_id, const Eigen::Vector3d& position_w, uint64_t first_kf_id, uint64_t frame_id)
    : id(point_id), first_keyframe_id(first_kf_id), first_frame_id(frame_id), p_w(position_w) {}

int MapPoint::index_in(const KeyFrame* kf) const {
  for (const Observation& o : observations_) {
    if (o.keyframe == kf) return o.index;
  }
  return -1;
}

void MapPoint::add_observation(KeyFrame* kf, int index) {
  if (is_in(kf)) return;
  observations_.push_back({kf, index});
  n_obs_ += kf->u_right[static_cast<std::size_t>(index)] >= 0 ? 2 : 1;
}

void MapPoint::erase_observation(KeyFrame* kf, Map& map) {
  bool erased = false;
  for (std::size_t k = 0; k < observations_.size(); ++k) {
    if (observations_[k].keyframe != kf) continue;
    n_obs_ -= kf->u_right[static_cast<std::size_t>(observations_[k].index)] >= 0 ? 2 : 1;
    observations_.erase(observations_.begin() + static_cast<std::ptrdiff_t>(k));
    erased = true;
    break;
  }
  if (!erased) return;
  if (reference_keyframe == kf) reference_keyframe = observations_.empty() ? nullptr : observations_.front().keyframe;
  if (n_obs_ <= 2) set_bad(map);
}

void MapPoint::set_bad(Map& map) {
  if (bad_) return;
  bad_ = true;
  // Keep this object alive while it unlinks itself (the map and keyframes may hold the last references).
  const MapPointPtr self = shared_from_this();
  std::vector<Observation> obs;
  obs.swap(observations_);
  n_obs_ = 0;
  for (const Observation& o : obs) o.keyframe->erase_map_point_match(static_cast<std::size_t>(o.index));
  map.erase_map_point(this);
}

void MapPoint::replace(const MapPointPtr& other, Map& map) {
  if (!other || other.get() == this || bad_) return;
  const MapPointPtr self = shared_from_this();
  std::vector<Observation> obs;
  obs.swap(observations_);
  n_obs_ = 0;
  bad_ = true;
  replaced_ = other;
  for (const Observation& o : obs) {
    if (!other->is_in(o.keyframe)) {
      o.keyframe->replace_map_point_match(static_cast<std::size_t>(o.index), other);
      other->add_observation(o.keyframe, o.index);
    } else {
      o.keyframe->erase_map_point_match(static_cast<std::size_t>(o.index));
    }
  }
  other->increase_found(found);
  other->increase_visible(visible);
  other->compute_distinctive_descriptor();
  map.erase_map_point(this);
}

void MapPoint::compute_distinctive_descriptor() {
  const std::size_t n = observations_.size();
  if (n == 0) return;
  if (n == 1) {
    const KeyFrame* kf = observations_[0].keyframe;
    std::copy_n(kf->descriptor(static_cast<std::size_t>(observations_[0].index)), 32, descriptor.begin());
    return;
  }
  // Small fixed buffers: points rarely have more than a few dozen observations.
  std::vector<const uint8_t*> descs(n);
  for (std::size_t k = 0; k < n; ++k) {
    descs[k] = observations_[k].keyframe->descriptor(static_cast<std::size_t>(observations_[k].index));
  }
  std::vector<int> dist(n * n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      const int d = hamming_distance(descs[a], descs[b]);
      dist[a * n + b] = d;
      dist[b * n + a] = d;
    }
  }
  int best_median = std::numeric_limits<int>::max();
  std::size_t best = 0;
  std::vector<int> row(n);
  for (std::size_t a = 0; a < n; ++a) {
    std::copy_n(dist.begin() + static_cast<std::ptrdiff_t>(a * n), n, row.begin());
    std::nth_element(row.begin(), row.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = a;
    }
  }
  std::copy_n(descs[best], 32, descriptor.begin());
}

void MapPoint::update_normal_and_depth() {
  if (observations_.empty() || reference_keyframe == nullptr) return;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const Observation& o : observations_) {
    const Eigen::Vector3d d = p_w - o.keyframe->center_w();
    const double len = d.norm();
    if (len > 0) normal += d / len;
  }
  const double len = normal.norm();
  if (len > 0) normal_w = normal / len;
  const int ref_index = index_in(reference_keyframe);
  if (ref_index < 0) return;
  const FrameGeometry& g = *reference_keyframe->geometry;
  const double dist = (p_w - reference_keyframe->center_w()).norm();
  const int level = reference_keyframe->keypoints[static_cast<std::size_t>(ref_index)].octave;
  const double level_scale = g.scale_factors[static_cast<std::size_t>(std::clamp(level, 0, g.n_levels - 1))];
  max_distance_m = static_cast<float>(dist * level_scale);
  min_distance_m = static_cast<float>(max_distance_m / g.scale_factors[static_cast<std::size_t>(g.n_levels - 1)]);
}

}  // namespace agvslam::slam
