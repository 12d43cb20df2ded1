#include "agvslam/slam/local_mapping.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <unordered_map>

#include "agvslam/slam/map.h"
#include "agvslam/slam/triangulation.h"

namespace agvslam::slam {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

LocalMapping::LocalMapping(const SlamConfig& config, Map& map, const StereoIntrinsics& intrinsics)
    : config_(config),
      map_(map),
      intrinsics_(intrinsics),
      worker_(static_cast<std::size_t>(config.mapping.queue_capacity), KeyframeWorker::WhenFull::kRefuseNew,
              [this](const KeyFramePtr& kf) { process(kf); }) {}

LocalMapping::~LocalMapping() { stop(); }

void LocalMapping::start() { worker_.start(); }

void LocalMapping::stop() {
  abort_ba_.store(true);
  worker_.stop();
}

bool LocalMapping::try_insert(const KeyFramePtr& kf) {
  if (worker_.push(kf) == KeyframeWorker::Pushed::kRefused) {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.keyframes_skipped;
    return false;
  }
  abort_ba_.store(true);
  return true;
}

std::size_t LocalMapping::queue_length() const { return worker_.size(); }

bool LocalMapping::idle() const { return worker_.idle(); }

void LocalMapping::process_pending() { worker_.process_pending(); }

void LocalMapping::wait_until_idle() { worker_.wait_until_idle(); }

std::vector<KeyFramePtr> LocalMapping::reset() {
  std::vector<KeyFramePtr> dropped = worker_.clear();
  abort_ba_.store(true);
  std::lock_guard<std::mutex> work(worker_.work_mutex());  // the keyframe in progress finishes
  recent_points_.clear();
  for (KeyFramePtr& kf : worker_.clear()) dropped.push_back(std::move(kf));
  return dropped;
}

bool LocalMapping::wait_for_room(double timeout_ms) {
  abort_ba_.store(true);
  return worker_.wait_for_room(timeout_ms);
}

LocalMappingStats LocalMapping::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

std::vector<KeyframeMappingTimes> LocalMapping::timing_history() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return history_;
}

void LocalMapping::process(const KeyFramePtr& kf) {
  abort_ba_.store(false);
  LocalMappingStats s;
  const auto t_start = Clock::now();
  auto more_waiting = [&] { return !worker_.empty(); };
  {
    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(map_.mutex());
    process_new_keyframe(*kf);
    s.insert_ms = ms_since(t0);
  }
  test_step_delay(false);
  if (kf->bad()) return;
  {
    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(map_.mutex());
    cull_recent_points(*kf);
    s.culling_ms = ms_since(t0);
  }
  test_step_delay(false);
  {
    const auto t0 = Clock::now();
    create_new_map_points(*kf);
    s.triangulation_ms = ms_since(t0);
  }
  test_step_delay(false);
  if (!more_waiting()) {
    const auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(map_.mutex());
    search_in_neighbours(*kf);
    s.fusion_ms = ms_since(t0);
    test_step_delay(false);
  }
  if (!more_waiting()) {
    const auto t0 = Clock::now();
    local_bundle_adjustment(*kf);
    test_step_delay(true);
    s.ba_ms = ms_since(t0);
    const auto t1 = Clock::now();
    {
      std::lock_guard<std::mutex> lock(map_.mutex());
      cull_keyframes(*kf);
    }
    test_step_delay(false);
    s.kf_culling_ms = ms_since(t1);
  }
  s.total_ms = ms_since(t_start);
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.keyframes_processed;
    stats_.insert_ms = s.insert_ms;
    stats_.culling_ms = s.culling_ms;
    stats_.triangulation_ms = s.triangulation_ms;
    stats_.fusion_ms = s.fusion_ms;
    stats_.ba_ms = s.ba_ms;
    stats_.kf_culling_ms = s.kf_culling_ms;
    stats_.total_ms = s.total_ms;
    history_.push_back(
        {kf->id, s.insert_ms, s.culling_ms, s.triangulation_ms, s.fusion_ms, s.ba_ms, s.kf_culling_ms, s.total_ms});
  }
  if (sink_) sink_(kf);
}

void LocalMapping::test_step_delay(bool abortable) const {
  if (test_step_delay_ms_ <= 0) return;
  const auto until = Clock::now() + std::chrono::duration<double, std::milli>(test_step_delay_ms_);
  while (Clock::now() < until) {
    if (abortable && abort_ba_.load()) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void LocalMapping::process_new_keyframe(KeyFrame& kf) {
  for (std::size_t i = 0; i < kf.size(); ++i) {
    const MapPointPtr p = kf.map_point(i);
    if (!p) continue;
    if (p->bad()) {
      // A point retired while this keyframe waited: the keyframe saw the moved object too.
      if (p->retired()) {
        kf.retire_keypoint(i);
      } else {
        kf.erase_map_point_match(i);
      }
      continue;
    }
    if (!p->is_in(&kf)) {
      p->add_observation(&kf, static_cast<int>(i));
      p->update_normal_and_depth();
      p->compute_distinctive_descriptor();
    } else if (p->index_in(&kf) != static_cast<int>(i)) {
      // The frame matched this point at two keypoints: the keyframe keeps the one the point records.
      kf.erase_map_point_match(i);
    } else if (p->first_keyframe_id == kf.id) {
      // Created by tracking for this keyframe (close stereo points): watch it in the culling test.
      recent_points_.push_back(p);
    }
  }
  kf.update_connections();
  map_.add_keyframe(kf.shared_from_this());
  if (place_) place_->on_keyframe_inserted(kf);
}

void LocalMapping::cull_recent_points(const KeyFrame& kf) {
  const int min_obs = config_.mapping.map_point_min_observations;
  uint64_t culled = 0;
  for (auto it = recent_points_.begin(); it != recent_points_.end();) {
    MapPoint& p = **it;
    const uint64_t age = kf.id >= p.first_keyframe_id ? kf.id - p.first_keyframe_id : 0;
    if (p.bad()) {
      it = recent_points_.erase(it);
    } else if (p.found_ratio() < config_.mapping.map_point_min_found_ratio) {
      p.set_bad(map_);
      ++culled;
      it = recent_points_.erase(it);
    } else if (age >= 2 && p.observations().size() < static_cast<std::size_t>(min_obs)) {
      p.set_bad(map_);
      ++culled;
      it = recent_points_.erase(it);
    } else if (age >= 3) {
      it = recent_points_.erase(it);
    } else {
      ++it;
    }
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.points_culled += culled;
}

void LocalMapping::create_new_map_points(KeyFrame& kf) {
  std::vector<KeyFrame*> neighbours;
  SE3d T1_c_w;
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    neighbours = kf.best_covisibles(static_cast<std::size_t>(config_.mapping.triangulation_neighbours));
    T1_c_w = kf.T_c_w();
  }
  const FrameGeometry& g = *kf.geometry;
  const PinholeCamera& cam = g.camera;
  Eigen::Matrix3d K;
  K << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1;
  const double ratio_factor = 1.5 * g.scale_factor;
  std::vector<std::pair<int, int>> matches;
  uint64_t created = 0;

  for (KeyFrame* kf2 : neighbours) {
    // One neighbour per lock: tracking gets the map between neighbours.
    std::lock_guard<std::mutex> lock(map_.mutex());
    if (kf.bad() || kf2->bad()) continue;
    const Eigen::Vector3d c1 = kf.center_w(), c2 = kf2->center_w();
    if ((c2 - c1).norm() < g.baseline_m) continue;  // stereo already covers this baseline
    const SE3d T2_c_w = kf2->T_c_w();
    const Eigen::Matrix3d F12 = fundamental_from_poses(T1_c_w, T2_c_w, K);
    if (place_ && config_.mapping.triangulation_bow) {
      // ORB-SLAM2's SearchForTriangulation: candidates from the vocabulary's direct index. kf2's BoW exists (it
      // was inserted before); kf's was computed in process_new_keyframe.
      place_->compute(kf);
      place_->compute(*kf2);
      matcher_.search_for_triangulation_bow(kf, *kf2, F12, matches);
    } else {
      matcher_.search_for_triangulation(kf, *kf2, F12, matches);
    }
    for (const auto& [i1, i2] : matches) {
      const std::size_t s1 = static_cast<std::size_t>(i1), s2 = static_cast<std::size_t>(i2);
      if (kf.map_point(s1) || kf2->map_point(s2)) continue;
      if (kf.keypoint_retired(s1) || kf2->keypoint_retired(s2)) continue;  // saw an object that has moved
      const cv::KeyPoint& kp1 = kf.keypoints[s1];
      const cv::KeyPoint& kp2 = kf2->keypoints[s2];
      const bool stereo1 = kf.u_right[s1] >= 0, stereo2 = kf2->u_right[s2] >= 0;
      const Eigen::Vector2d x1((kp1.pt.x - cam.cx) / cam.fx, (kp1.pt.y - cam.cy) / cam.fy);
      const Eigen::Vector2d x2((kp2.pt.x - cam.cx) / cam.fx, (kp2.pt.y - cam.cy) / cam.fy);
      const Eigen::Vector3d ray1 = T1_c_w.linear().transpose() * Eigen::Vector3d(x1.x(), x1.y(), 1.0);
      const Eigen::Vector3d ray2 = T2_c_w.linear().transpose() * Eigen::Vector3d(x2.x(), x2.y(), 1.0);
      const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
      const double cos_stereo1 = stereo1 ? std::cos(2.0 * std::atan2(g.baseline_m / 2.0, kf.depth[s1])) : 2.0;
      const double cos_stereo2 = stereo2 ? std::cos(2.0 * std::atan2(g.baseline_m / 2.0, kf2->depth[s2])) : 2.0;
      const double cos_stereo = std::min(cos_stereo1, cos_stereo2);

      Eigen::Vector3d p_w;
      if (cos_rays < cos_stereo && cos_rays > 0 && (stereo1 || stereo2 || cos_rays < 0.9998)) {
        if (!triangulate_linear(x1, x2, T1_c_w, T2_c_w, p_w)) continue;
      } else if (stereo1 && cos_stereo1 < cos_stereo2) {
        p_w = kf.unproject_stereo(s1);
      } else if (stereo2 && cos_stereo2 < cos_stereo1) {
        p_w = kf2->unproject_stereo(s2);
      } else {
        continue;  // no parallax
      }
      // In front of both cameras, and reprojecting within the chi-square bounds.
      const Eigen::Vector3d p1 = T1_c_w * p_w, p2 = T2_c_w * p_w;
      if (p1.z() <= 0 || p2.z() <= 0) continue;
      const double inv_sigma2_1 = g.inv_level_sigma2[static_cast<std::size_t>(kp1.octave)];
      const double inv_sigma2_2 = g.inv_level_sigma2[static_cast<std::size_t>(kp2.octave)];
      const double chi1 = reprojection_chi2(intrinsics_, p1, {kp1.pt.x, kp1.pt.y}, kf.u_right[s1], inv_sigma2_1);
      const double chi2 = reprojection_chi2(intrinsics_, p2, {kp2.pt.x, kp2.pt.y}, kf2->u_right[s2], inv_sigma2_2);
      if (chi1 > (stereo1 ? 7.8 : 5.991) || chi2 > (stereo2 ? 7.8 : 5.991)) continue;
      // Scale consistency: the distance ratio agrees with the pyramid levels' ratio.
      const double dist1 = (p_w - c1).norm(), dist2 = (p_w - c2).norm();
      if (dist1 == 0 || dist2 == 0) continue;
      const double ratio_dist = dist2 / dist1;
      const double ratio_octave =
          g.scale_factors[static_cast<std::size_t>(kp1.octave)] / g.scale_factors[static_cast<std::size_t>(kp2.octave)];
      if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) continue;

      auto point = std::make_shared<MapPoint>(map_.new_map_point_id(), p_w, &kf, kf.frame_id);
      point->add_observation(&kf, i1);
      point->add_observation(kf2, i2);
      kf.add_map_point(point, s1);
      kf2->add_map_point(point, s2);
      point->compute_distinctive_descriptor();
      point->update_normal_and_depth();
      map_.add_map_point(point);
      recent_points_.push_back(point);
      ++created;
    }
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.points_created += created;
}

void LocalMapping::search_in_neighbours(KeyFrame& kf) {
  if (kf.bad()) return;
  std::vector<KeyFrame*> targets;
  for (KeyFrame* n : kf.best_covisibles(static_cast<std::size_t>(config_.mapping.fusion_neighbours))) {
    if (n->bad() || n->mapping.fuse_target_for_kf == kf.id) continue;
    targets.push_back(n);
    n->mapping.fuse_target_for_kf = kf.id;
  }
  const std::size_t first_order = targets.size();
  for (std::size_t k = 0; k < first_order; ++k) {
    for (KeyFrame* n2 : targets[k]->best_covisibles(static_cast<std::size_t>(config_.mapping.fusion_second_order))) {
      if (n2->bad() || n2->mapping.fuse_target_for_kf == kf.id || n2 == &kf) continue;
      targets.push_back(n2);
      n2->mapping.fuse_target_for_kf = kf.id;
    }
  }
  const float radius = static_cast<float>(config_.mapping.fusion_radius);
  uint64_t fused = 0;
  // The keyframe's points into the targets.
  const std::vector<MapPointPtr> own = kf.map_points();
  for (KeyFrame* t : targets) fused += static_cast<uint64_t>(matcher_.fuse(*t, own, radius, map_));
  // The targets' points into the keyframe.
  std::vector<MapPointPtr> candidates;
  for (KeyFrame* t : targets) {
    for (const MapPointPtr& p : t->map_points()) {
      if (!p || p->bad() || p->mapping.fuse_candidate_for_kf == kf.id) continue;
      p->mapping.fuse_candidate_for_kf = kf.id;
      candidates.push_back(p);
    }
  }
  fused += static_cast<uint64_t>(matcher_.fuse(kf, candidates, radius, map_));
  for (const MapPointPtr& p : kf.map_points()) {
    if (p && !p->bad()) {
      p->compute_distinctive_descriptor();
      p->update_normal_and_depth();
    }
  }
  kf.update_connections();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.points_fused += fused;
}

void LocalMapping::local_bundle_adjustment(KeyFrame& kf) {
  BaProblem problem;
  std::vector<KeyFramePtr> pose_kfs;    // problem.poses[k] <-> pose_kfs[k]
  std::vector<MapPointPtr> point_refs;  // problem.points_w[k] <-> point_refs[k]
  struct ObsRef {
    KeyFrame* kf;
    int index;
  };
  std::vector<ObsRef> obs_refs;
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    if (kf.bad() || map_.keyframe_count() <= 2) return;
    std::vector<KeyFrame*> local{&kf};
    kf.mapping.ba_local_for_kf = kf.id;
    for (KeyFrame* n : kf.covisibles()) {
      if (local.size() >= static_cast<std::size_t>(config_.mapping.max_local_ba_keyframes)) break;
      if (n->bad()) continue;
      n->mapping.ba_local_for_kf = kf.id;
      local.push_back(n);
    }
    std::unordered_map<const KeyFrame*, int> pose_index;
    auto add_pose = [&](KeyFrame* k, bool fixed) {
      pose_index[k] = static_cast<int>(problem.poses.size());
      problem.poses.push_back({k->T_c_w(), fixed || k->is_origin()});
      pose_kfs.push_back(k->shared_from_this());
    };
    for (KeyFrame* k : local) add_pose(k, false);
    for (KeyFrame* k : local) {
      for (const MapPointPtr& p : k->map_points()) {
        if (!p || p->bad() || p->mapping.ba_local_for_kf == kf.id) continue;
        p->mapping.ba_local_for_kf = kf.id;
        const int point_index = static_cast<int>(problem.points_w.size());
        problem.points_w.push_back(p->p_w);
        point_refs.push_back(p);
        for (const Observation& o : p->observations()) {
          KeyFrame* ok = o.keyframe;
          if (ok->bad()) continue;
          auto it = pose_index.find(ok);
          if (it == pose_index.end()) {
            // Keyframes that see local points but are not local are fixed (ORB-SLAM2).
            add_pose(ok, true);
            it = pose_index.find(ok);
          }
          const cv::KeyPoint& kp = ok->keypoints[static_cast<std::size_t>(o.index)];
          BaProblem::Observation ob;
          ob.pose = it->second;
          ob.point = point_index;
          ob.uv_px = {kp.pt.x, kp.pt.y};
          ob.u_right_px = ok->u_right[static_cast<std::size_t>(o.index)];
          ob.inv_sigma2 = ok->geometry->inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
          problem.observations.push_back(ob);
          obs_refs.push_back({ok, o.index});
        }
      }
    }
  }
  if (problem.observations.empty()) return;

  // Ceres works on the copy while tracking uses the map.
  const BaStats stats =
      solve_bundle_adjustment(problem, intrinsics_, config_.optimizer, config_.mapping.local_ba_iterations_first,
                              config_.mapping.local_ba_iterations_second, &abort_ba_);

  std::lock_guard<std::mutex> lock(map_.mutex());
  uint64_t removed = 0;
  for (std::size_t k = 0; k < problem.observations.size(); ++k) {
    if (!problem.observations[k].outlier) continue;
    const MapPointPtr& p = point_refs[static_cast<std::size_t>(problem.observations[k].point)];
    KeyFrame* ok = obs_refs[k].kf;
    if (p->bad() || ok->bad() || p->index_in(ok) != obs_refs[k].index) continue;
    ok->erase_map_point_match(static_cast<std::size_t>(obs_refs[k].index));
    p->erase_observation(ok, map_);
    ++removed;
  }
  for (std::size_t k = 0; k < problem.poses.size(); ++k) {
    if (!problem.poses[k].fixed && !pose_kfs[k]->bad() && is_valid_pose(problem.poses[k].T_c_w)) {
      pose_kfs[k]->set_pose(problem.poses[k].T_c_w);
    }
  }
  for (std::size_t k = 0; k < point_refs.size(); ++k) {
    if (point_refs[k]->bad() || !problem.points_w[k].allFinite()) continue;
    point_refs[k]->p_w = problem.points_w[k];
    point_refs[k]->update_normal_and_depth();
  }
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  ++stats_.ba_runs;
  if (stats.aborted) ++stats_.ba_aborted;
  stats_.ba_outliers += removed;
}

void LocalMapping::cull_keyframes(KeyFrame& kf) {
  if (kf.bad()) return;
  const int observers_needed = config_.mapping.keyframe_redundancy_observers;
  uint64_t culled = 0;
  std::vector<KeyFrame*> local = kf.covisibles();
  // Most redundant first would need two passes; ORB-SLAM2's order (covisibility) is kept.
  for (KeyFrame* k : local) {
    if (k->bad() || k->is_origin() || k->not_erase()) continue;
    const FrameGeometry& g = *k->geometry;
    int n_points = 0, redundant = 0;
    for (std::size_t i = 0; i < k->size(); ++i) {
      const MapPointPtr& p = k->map_point(i);
      if (!p || p->bad()) continue;
      if (!(k->depth[i] > 0 && k->depth[i] <= g.close_depth_m)) continue;  // stereo: close points only
      ++n_points;
      if (p->observations().size() <= static_cast<std::size_t>(observers_needed)) continue;
      const int level = k->keypoints[i].octave;
      int observers = 0;
      for (const Observation& o : p->observations()) {
        if (o.keyframe == k) continue;
        const int other_level = o.keyframe->keypoints[static_cast<std::size_t>(o.index)].octave;
        if (other_level <= level + 1) {
          if (++observers >= observers_needed) break;
        }
      }
      if (observers >= observers_needed) ++redundant;
    }
    if (n_points > 0 && redundant > config_.mapping.keyframe_redundancy * n_points) {
      if (place_) place_->on_keyframe_erased(*k);
      k->set_bad(map_);
      ++culled;
    }
  }
  // Hard cap (off by default): remove the least useful covisible keyframes beyond it.
  const std::size_t cap = static_cast<std::size_t>(config_.mapping.max_keyframes);
  if (cap > 0 && map_.keyframe_count() > cap) {
    for (auto it = local.rbegin(); it != local.rend() && map_.keyframe_count() > cap; ++it) {
      KeyFrame* k = *it;
      if (k->bad() || k->is_origin() || k->not_erase() || k == &kf) continue;
      if (place_) place_->on_keyframe_erased(*k);
      k->set_bad(map_);
      ++culled;
    }
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.keyframes_culled += culled;
}

}  // namespace agvslam::slam
