#include "agvslam/slam/loop_closing.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <unordered_set>

#include "agvslam/slam/local_mapping.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/pose_graph.h"

namespace agvslam::slam {

namespace {

using Clock = std::chrono::steady_clock;

// Loop-detection diagnostics on stderr (candidates, matches, confirmations) when AGVSLAM_LOOP_DEBUG is set.
bool loop_debug() {
  static const bool on = std::getenv("AGVSLAM_LOOP_DEBUG") != nullptr;
  return on;
}
unsigned long long ull(uint64_t v) { return static_cast<unsigned long long>(v); }

double rotation_angle_deg(const Eigen::Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

bool intersects(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] < b[j]) {
      ++i;
    } else if (b[j] < a[i]) {
      ++j;
    } else {
      return true;
    }
  }
  return false;
}

// The 3-D matches between kf1's map points and the matched points of kf2 (matches12[i1], kf2's point): each point
// in its own keyframe's camera, with its keypoint in each image. index_of[k] is the kf1 keypoint of match k.
void collect_matches(const KeyFrame& kf1, const KeyFrame& kf2, const std::vector<MapPointPtr>& matches12,
                     std::vector<PointMatch3d>& out, std::vector<int>& index_of) {
  out.clear();
  index_of.clear();
  const FrameGeometry& g = *kf1.geometry;
  for (std::size_t i1 = 0; i1 < matches12.size(); ++i1) {
    const MapPointPtr& p2 = matches12[i1];
    const MapPointPtr& p1 = kf1.map_point(i1);
    if (!p2 || !p1 || p1->bad() || p2->bad()) continue;
    const int i2 = p2->index_in(&kf2);
    if (i2 < 0) continue;
    const cv::KeyPoint& kp1 = kf1.keypoints[i1];
    const cv::KeyPoint& kp2 = kf2.keypoints[static_cast<std::size_t>(i2)];
    PointMatch3d m;
    m.p1_c = kf1.T_c_w() * p1->p_w;
    m.p2_c = kf2.T_c_w() * p2->p_w;
    m.uv1_px = {kp1.pt.x, kp1.pt.y};
    m.uv2_px = {kp2.pt.x, kp2.pt.y};
    m.inv_sigma2_1 = g.inv_level_sigma2[static_cast<std::size_t>(kp1.octave)];
    m.inv_sigma2_2 = g.inv_level_sigma2[static_cast<std::size_t>(kp2.octave)];
    out.push_back(m);
    index_of.push_back(static_cast<int>(i1));
  }
}

}  // namespace

LoopClosing::LoopClosing(const SlamConfig& config, Map& map, LocalMapping& mapper,
                         std::shared_ptr<PlaceRecognition> place, const StereoIntrinsics& intrinsics)
    : config_(config),
      map_(map),
      mapper_(mapper),
      place_(std::move(place)),
      intrinsics_(intrinsics),
      worker_(static_cast<std::size_t>(config.loop_closing.queue_capacity), KeyframeWorker::WhenFull::kDropOldest,
              [this](const KeyFramePtr& kf) { process(kf); }) {}

LoopClosing::~LoopClosing() { stop(); }

void LoopClosing::start() { worker_.start(); }

void LoopClosing::stop() {
  worker_.stop();
  stop_global_ba();
}

void LoopClosing::insert(const KeyFramePtr& kf) {
  if (worker_.push(kf) == KeyframeWorker::Pushed::kQueuedDroppedOldest) {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.keyframes_dropped;
  }
}

std::size_t LoopClosing::queue_length() const { return worker_.size(); }

void LoopClosing::process_pending() { worker_.process_pending(); }

void LoopClosing::wait_until_idle() {
  worker_.wait_until_idle();
  // The loop thread is idle: no new global BA can start until another keyframe arrives.
  std::lock_guard<std::mutex> work(worker_.work_mutex());
  if (gba_thread_.joinable()) gba_thread_.join();
}

void LoopClosing::reset() {
  static_cast<void>(worker_.clear());  // keyframes local mapping has inserted: the map holds them
  std::lock_guard<std::mutex> work(worker_.work_mutex());
  stop_global_ba();
  consistent_groups_.clear();
  enough_consistent_.clear();
  matched_kf_ = nullptr;
  current_matches_.clear();
  loop_points_.clear();
  last_loop_kf_id_ = 0;
}

LoopClosingStats LoopClosing::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

void LoopClosing::process(const KeyFramePtr& kf) {
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.keyframes_processed;
  }
  const auto t0 = Clock::now();
  if (!detect_loop(*kf)) return;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.consistent_detections;
  }
  LoopEvent event;
  if (!verify_loop(*kf, event)) return;
  event.detect_ms = ms_since(t0);
  correct_loop(*kf, event);
}

bool LoopClosing::detect_loop(KeyFrame& kf) {
  std::lock_guard<std::mutex> lock(map_.mutex());
  if (kf.bad()) return false;
  const LoopClosingConfig& lc = config_.loop_closing;
  const uint64_t gap = static_cast<uint64_t>(lc.min_keyframes_between_loops);
  if (kf.id < last_loop_kf_id_ + gap || map_.keyframe_count() <= gap) return false;
  if (!kf.bow.computed()) place_->compute(kf);

  // The lowest similarity to a covisible neighbour: a loop candidate must look at least as similar.
  float min_score = 1.0f;
  for (KeyFrame* n : kf.covisibles()) {
    if (n->bad()) continue;
    if (!n->bow.computed()) place_->compute(*n);
    min_score = std::min(min_score, static_cast<float>(PlaceRecognition::score(kf, *n)));
  }
  const std::vector<KeyFrame*> candidates = place_->loop_candidates(kf, min_score, map_);
  if (loop_debug()) {
    std::fprintf(stderr, "detect kf %llu f%llu min_score %.4f cands:", ull(kf.id), ull(kf.frame_id), min_score);
    std::vector<MapPointPtr> m12;
    for (KeyFrame* c : candidates) {
      const int n = matcher_.search_by_bow(kf, *c, 0.75f, m12);
      std::fprintf(stderr, " %llu(s%.3f,m%d,pts%d)", ull(c->id), PlaceRecognition::score(kf, *c), n,
                   c->tracked_map_points(0));
    }
    // best overall non-connected
    std::fprintf(stderr, " | kf0:");
    if (auto k0 = map_.keyframe(0)) {
      const int n = matcher_.search_by_bow(kf, *k0, 0.75f, m12);
      std::fprintf(stderr, "s%.3f m%d", PlaceRecognition::score(kf, *k0), n);
    }
    std::fprintf(stderr, "\n");
  }
  enough_consistent_.clear();
  if (candidates.empty()) {
    consistent_groups_.clear();
    return false;
  }
  // Covisibility consistency (ORB-SLAM2): a candidate's group is the candidate and its connected keyframes; it
  // is consistent with a previous group when they share a keyframe.
  std::vector<ConsistentGroup> current_groups;
  std::vector<uint8_t> previous_used(consistent_groups_.size(), 0);
  for (KeyFrame* candidate : candidates) {
    ConsistentGroup group;
    group.keyframes.push_back(candidate->id);
    for (const auto& [other, weight] : candidate->connections()) group.keyframes.push_back(other->id);
    std::sort(group.keyframes.begin(), group.keyframes.end());
    group.keyframes.erase(std::unique(group.keyframes.begin(), group.keyframes.end()), group.keyframes.end());
    bool enough = false, consistent_with_some = false;
    for (std::size_t g = 0; g < consistent_groups_.size(); ++g) {
      if (!intersects(group.keyframes, consistent_groups_[g].keyframes)) continue;
      consistent_with_some = true;
      const int consistency = consistent_groups_[g].consistency + 1;
      if (!previous_used[g]) {
        current_groups.push_back({group.keyframes, consistency});
        previous_used[g] = 1;
      }
      if (consistency >= lc.consistency && !enough) {
        enough_consistent_.push_back({candidate, true});
        enough = true;
      }
    }
    if (!consistent_with_some) {
      group.consistency = 0;
      current_groups.push_back(std::move(group));
    }
    // Not (yet) consistent over time: verified now if enough covisible keyframes confirm it (ORB-SLAM3's check
    // in the covisibility graph), for loops seen by only a keyframe or two.
    if (!enough && (lc.consistency == 0 || lc.covisible_consistency > 0)) {
      enough_consistent_.push_back({candidate, lc.consistency == 0});
    }
  }
  consistent_groups_ = std::move(current_groups);
  if (enough_consistent_.empty()) return false;
  // Temporally consistent candidates first.
  std::stable_sort(enough_consistent_.begin(), enough_consistent_.end(),
                   [](const LoopCandidate& a, const LoopCandidate& b) { return a.consistent && !b.consistent; });
  // Keep the keyframes being verified out of culling until the loop is decided.
  kf.set_not_erase(true);
  for (const LoopCandidate& c : enough_consistent_) c.kf->set_not_erase(true);
  return true;
}

int LoopClosing::covisible_confirmations(const KeyFrame& kf, std::vector<double>* errors) {
  const LoopClosingConfig& lc = config_.loop_closing;
  const FrameGeometry& g = *kf.geometry;
  int confirmed = 0;
  std::vector<MapPointPtr> matched;
  std::vector<PoseObservation> observations;
  std::vector<uint8_t> outlier;
  for (KeyFrame* n : kf.best_covisibles(5)) {
    if (n->bad()) continue;
    const SE3d T_n_w_predicted = n->T_c_w() * kf.T_w_c() * T_cur_w_corrected_;
    matched.assign(n->size(), nullptr);
    const int found = matcher_.search_loop_projection(*n, T_n_w_predicted, loop_points_, 10.0f, matched);
    if (found < lc.min_refined_inliers) continue;
    observations.clear();
    for (std::size_t i = 0; i < matched.size(); ++i) {
      if (!matched[i]) continue;
      PoseObservation o;
      o.p_w = matched[i]->p_w;
      o.uv_px = {n->keypoints[i].pt.x, n->keypoints[i].pt.y};
      o.u_right_px = n->u_right[i];
      o.inv_sigma2 = g.inv_level_sigma2[static_cast<std::size_t>(n->keypoints[i].octave)];
      observations.push_back(o);
    }
    SE3d T = T_n_w_predicted;
    const MotionOnlyStats st = optimize_pose(intrinsics_, config_.optimizer, observations, outlier, T);
    const double moved_m = (T.inverse().translation() - T_n_w_predicted.inverse().translation()).norm();
    const double turned_deg = rotation_angle_deg(T.linear() * T_n_w_predicted.linear().transpose());
    if (errors) errors->push_back(st.inliers >= lc.min_refined_inliers ? moved_m : -1);
    if (st.inliers >= lc.min_refined_inliers && moved_m <= lc.confirmation_max_m &&
        turned_deg <= lc.confirmation_max_deg) {
      ++confirmed;
    }
  }
  return confirmed;
}

void LoopClosing::release_candidates() {
  for (const LoopCandidate& c : enough_consistent_) {
    if (c.kf != matched_kf_) c.kf->release_not_erase();
  }
  enough_consistent_.clear();
}

bool LoopClosing::verify_loop(KeyFrame& kf, LoopEvent& event) {
  std::lock_guard<std::mutex> lock(map_.mutex());
  const LoopClosingConfig& lc = config_.loop_closing;
  matched_kf_ = nullptr;
  auto fail = [&](bool correction) {
    matched_kf_ = nullptr;
    release_candidates();
    kf.release_not_erase();
    current_matches_.clear();
    loop_points_.clear();
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++(correction ? stats_.rejected_correction : stats_.rejected_geometry);
    return false;
  };
  if (kf.bad()) return fail(false);
  std::vector<MapPointPtr> matches12;
  std::vector<PointMatch3d> matches3d;
  std::vector<int> index_of;
  std::vector<uint8_t> outlier;
  for (const LoopCandidate& cand : enough_consistent_) {
    KeyFrame* candidate = cand.kf;
    if (candidate->bad()) continue;
    if (!candidate->bow.computed()) place_->compute(*candidate);
    const int n = matcher_.search_by_bow(kf, *candidate, static_cast<float>(lc.bow_ratio), matches12);
    event.bow_matches = std::max(event.bow_matches, n);
    if (n < lc.min_bow_matches) continue;
    collect_matches(kf, *candidate, matches12, matches3d, index_of);
    const Se3RansacResult ransac = estimate_se3_ransac(intrinsics_, matches3d, lc.ransac_iterations, lc.ransac_chi2,
                                                       lc.min_ransac_inliers, kf.id + 1);
    event.ransac_inliers = std::max(event.ransac_inliers, ransac.inliers);
    if (!ransac.found) continue;
    // Keep the RANSAC inliers, add matches by projection both ways, refine on all of them.
    std::vector<MapPointPtr> verified(kf.size(), nullptr);
    for (std::size_t k = 0; k < matches3d.size(); ++k) {
      if (ransac.inlier[k])
        verified[static_cast<std::size_t>(index_of[k])] = matches12[static_cast<std::size_t>(index_of[k])];
    }
    SE3d T_c1_c2 = ransac.T_c1_c2;
    matcher_.search_by_se3(kf, *candidate, T_c1_c2, static_cast<float>(lc.projection_radius_px), verified);
    collect_matches(kf, *candidate, verified, matches3d, index_of);
    outlier.assign(matches3d.size(), 0);
    const int refined = optimize_relative_pose(intrinsics_, matches3d, lc.ransac_chi2, outlier, T_c1_c2);
    event.refined_inliers = std::max(event.refined_inliers, refined);
    if (refined < lc.min_refined_inliers) continue;
    for (std::size_t k = 0; k < matches3d.size(); ++k) {
      if (outlier[k]) verified[static_cast<std::size_t>(index_of[k])].reset();
    }
    matched_kf_ = candidate;
    matched_consistent_ = cand.consistent;
    T_cur_w_corrected_ = T_c1_c2 * candidate->T_c_w();
    current_matches_ = std::move(verified);
    break;
  }
  if (loop_debug()) {
    std::fprintf(stderr, "loop kf %llu (frame %llu): %zu candidates [", ull(kf.id), ull(kf.frame_id),
                 enough_consistent_.size());
    for (const LoopCandidate& c : enough_consistent_)
      std::fprintf(stderr, " %llu/f%llu%s", ull(c.kf->id), ull(c.kf->frame_id), c.consistent ? "*" : "");
    std::fprintf(stderr, "] bow %d ransac %d refined %d matched %d\n", event.bow_matches, event.ransac_inliers,
                 event.refined_inliers, matched_kf_ ? 1 : 0);
  }
  if (!matched_kf_) return fail(false);

  const SE3d T_w_corrected = T_cur_w_corrected_.inverse();
  event.correction_m = (T_w_corrected.translation() - kf.center_w()).norm();
  event.correction_deg = rotation_angle_deg(T_cur_w_corrected_.linear() * kf.T_w_c().linear());
  if (lc.max_correction_m > 0 && event.correction_m > lc.max_correction_m) return fail(true);

  // The loop keyframe's neighbourhood, projected with the corrected pose.
  std::vector<KeyFrame*> loop_kfs = matched_kf_->covisibles();
  loop_kfs.push_back(matched_kf_);
  std::unordered_set<const MapPoint*> seen;
  loop_points_.clear();
  for (KeyFrame* k : loop_kfs) {
    if (k->bad()) continue;
    for (const MapPointPtr& p : k->map_points()) {
      if (p && !p->bad() && seen.insert(p.get()).second) loop_points_.push_back(p);
    }
  }
  matcher_.search_loop_projection(kf, T_cur_w_corrected_, loop_points_, 10.0f, current_matches_);
  event.total_matches = static_cast<int>(std::count_if(current_matches_.begin(), current_matches_.end(),
                                                       [](const MapPointPtr& p) { return p != nullptr; }));
  if (event.total_matches < lc.min_total_matches) return fail(false);
  if (!matched_consistent_) {
    std::vector<double> errors;
    event.confirmations = covisible_confirmations(kf, &errors);
    if (loop_debug()) {
      std::fprintf(stderr, "  confirm kf %llu -> %llu: total %d, %d confirmations, moved", ull(kf.id),
                   ull(matched_kf_->id), event.total_matches, event.confirmations);
      for (double e : errors) std::fprintf(stderr, " %.4f", e);
      std::fprintf(stderr, "\n");
    }
    if (event.confirmations < lc.covisible_consistency) return fail(false);
  }
  release_candidates();
  event.keyframe_id = kf.id;
  event.loop_keyframe_id = matched_kf_->id;
  event.frame_id = kf.frame_id;
  event.loop_frame_id = matched_kf_->frame_id;
  event.t_ns = kf.t_ns;
  return true;
}

void LoopClosing::correct_loop(KeyFrame& kf, LoopEvent& event) {
  const LoopClosingConfig& lc = config_.loop_closing;
  stop_global_ba();  // before pausing the mapper: the global BA's merge needs it
  const auto t_start = Clock::now();
  auto pause = mapper_.pause();
  std::unique_lock<std::mutex> lock(map_.mutex());
  KeyFrame* loop_kf = matched_kf_;

  // 1. The keyframe's neighbourhood moves with it.
  kf.update_connections();
  std::vector<KeyFrame*> connected;
  for (KeyFrame* k : kf.covisibles()) {
    if (!k->bad()) connected.push_back(k);
  }
  connected.push_back(&kf);
  std::unordered_map<KeyFrame*, SE3d> corrected, non_corrected;
  const SE3d T_w_cur = kf.T_w_c();
  for (KeyFrame* k : connected) {
    non_corrected[k] = k->T_c_w();
    corrected[k] = k == &kf ? T_cur_w_corrected_ : SE3d(k->T_c_w() * T_w_cur * T_cur_w_corrected_);
  }
  std::unordered_map<const MapPoint*, KeyFrame*> corrected_by;
  std::vector<MapPoint*> moved;
  for (KeyFrame* k : connected) {
    const SE3d T_move = corrected[k].inverse() * non_corrected[k];  // world point before -> after
    for (const MapPointPtr& p : k->map_points()) {
      if (!p || p->bad() || corrected_by.count(p.get())) continue;
      p->p_w = T_move * p->p_w;
      corrected_by[p.get()] = k;
      moved.push_back(p.get());
    }
  }
  for (KeyFrame* k : connected) k->set_pose(corrected[k]);
  for (MapPoint* p : moved) p->update_normal_and_depth();
  for (KeyFrame* k : connected) k->update_connections();

  // 2. Fusion: the loop's points replace the keyframe's matched ones, then the loop neighbourhood's points are
  // fused into every corrected keyframe.
  int fused = 0;
  for (std::size_t i = 0; i < current_matches_.size(); ++i) {
    const MapPointPtr& loop_point = current_matches_[i];
    if (!loop_point || loop_point->bad()) continue;
    const MapPointPtr current = kf.map_point(i);
    if (current) {
      if (current != loop_point && !current->bad()) current->replace(loop_point, map_);
    } else if (!loop_point->is_in(&kf) && !kf.keypoint_retired(i)) {
      kf.add_map_point(loop_point, i);
      loop_point->add_observation(&kf, static_cast<int>(i));
      loop_point->compute_distinctive_descriptor();
    }
    ++fused;
  }
  std::vector<MapPointPtr> replace;
  for (KeyFrame* k : connected) {
    if (k->bad()) continue;
    fused += matcher_.fuse_with_pose(*k, corrected[k], loop_points_, 4.0f, replace);
    for (std::size_t j = 0; j < replace.size(); ++j) {
      if (replace[j] && !replace[j]->bad() && !loop_points_[j]->bad()) replace[j]->replace(loop_points_[j], map_);
    }
  }
  event.fused_points = fused;

  // 3. New links created by the fusion (ORB-SLAM2's LoopConnections).
  std::unordered_set<const KeyFrame*> connected_set(connected.begin(), connected.end());
  std::vector<std::pair<KeyFrame*, std::vector<KeyFrame*>>> loop_connections;
  for (KeyFrame* k : connected) {
    if (k->bad()) continue;
    const std::vector<KeyFrame*> previous = k->covisibles();
    k->update_connections();
    std::vector<KeyFrame*> links;
    for (const auto& [other, weight] : k->connections()) {
      if (other->bad() || connected_set.count(other)) continue;
      if (std::find(previous.begin(), previous.end(), other) != previous.end()) continue;
      links.push_back(other);
    }
    if (!links.empty()) loop_connections.emplace_back(k, std::move(links));
  }

  // 4. Essential graph.
  const auto t_graph = Clock::now();
  const std::vector<KeyFramePtr> kfs = map_.keyframes();
  std::unordered_map<const KeyFrame*, int> index;
  PoseGraph graph;
  for (const KeyFramePtr& k : kfs) {
    if (k->bad()) continue;
    index[k.get()] = static_cast<int>(graph.vertices.size());
    graph.vertices.push_back({k->T_c_w(), k.get() == loop_kf});
  }
  auto measured_pose = [&](KeyFrame* k) {
    const auto it = non_corrected.find(k);
    return it != non_corrected.end() ? it->second : k->T_c_w();
  };
  std::unordered_set<uint64_t> inserted;
  auto pair_key = [](const KeyFrame* a, const KeyFrame* b) {
    const uint64_t lo = std::min(a->id, b->id), hi = std::max(a->id, b->id);
    return (hi << 32) ^ lo;
  };
  auto add_edge = [&](KeyFrame* a, KeyFrame* b, const SE3d& T_b_a) {
    const auto ia = index.find(a), ib = index.find(b);
    if (ia == index.end() || ib == index.end()) return;
    graph.edges.push_back({ia->second, ib->second, T_b_a, 1.0});
  };
  for (const auto& [k, links] : loop_connections) {
    for (KeyFrame* other : links) {
      if ((k != &kf || other != loop_kf) && k->weight(other) < lc.essential_min_weight) continue;
      add_edge(k, other, other->T_c_w() * k->T_w_c());  // corrected poses: the new link as the loop sees it
      inserted.insert(pair_key(k, other));
    }
  }
  for (const KeyFramePtr& kp : kfs) {
    KeyFrame* k = kp.get();
    if (k->bad()) continue;
    const SE3d T_w_k = measured_pose(k).inverse();
    KeyFrame* parent = k->parent();
    if (parent && !parent->bad()) add_edge(k, parent, measured_pose(parent) * T_w_k);
    for (KeyFrame* l : k->loop_edges()) {
      if (!l->bad() && l->id < k->id) add_edge(k, l, measured_pose(l) * T_w_k);
    }
    for (KeyFrame* n : k->covisibles_with_weight(lc.essential_min_weight)) {
      if (n == parent || n->bad() || n->id >= k->id) continue;
      if (std::find(k->children().begin(), k->children().end(), n) != k->children().end()) continue;
      if (std::find(k->loop_edges().begin(), k->loop_edges().end(), n) != k->loop_edges().end()) continue;
      if (inserted.count(pair_key(k, n))) continue;
      add_edge(k, n, measured_pose(n) * T_w_k);
    }
  }
  // The loop itself: current keyframe -> loop keyframe, as verified.
  if (!inserted.count(pair_key(&kf, loop_kf))) add_edge(&kf, loop_kf, loop_kf->T_c_w() * kf.T_w_c());
  event.graph_keyframes = graph.vertices.size();
  event.graph_edges = graph.edges.size();
  std::vector<SE3d> before(graph.vertices.size());
  for (std::size_t v = 0; v < graph.vertices.size(); ++v) before[v] = graph.vertices[v].T_c_w;
  optimize_pose_graph(graph, lc.pose_graph_iterations);
  for (const KeyFramePtr& k : kfs) {
    const auto it = index.find(k.get());
    if (it != index.end()) k->set_pose(graph.vertices[static_cast<std::size_t>(it->second)].T_c_w);
  }
  // Every map point follows the keyframe that corrected it, or its reference keyframe.
  for (const MapPointPtr& p : map_.map_points()) {
    if (p->bad()) continue;
    const auto cb = corrected_by.find(p.get());
    const KeyFrame* ref = cb != corrected_by.end() ? cb->second : p->reference_keyframe;
    auto it = ref ? index.find(ref) : index.end();
    if (it == index.end()) {
      for (const Observation& o : p->observations()) {
        it = index.find(o.keyframe);
        if (it != index.end()) break;
      }
    }
    if (it == index.end()) continue;
    const std::size_t v = static_cast<std::size_t>(it->second);
    p->p_w = graph.vertices[v].T_c_w.inverse() * (before[v] * p->p_w);
    p->update_normal_and_depth();
  }
  event.pose_graph_ms = ms_since(t_graph);

  loop_kf->add_loop_edge(&kf);
  kf.add_loop_edge(loop_kf);
  for (KeyFrame* k : connected) {
    if (!k->bad()) k->update_connections();
  }
  last_loop_kf_id_ = kf.id;
  consistent_groups_.clear();
  map_.notify_big_change();
  event.correct_ms = ms_since(t_start);
  current_matches_.clear();
  loop_points_.clear();
  matched_kf_ = nullptr;
  std::size_t event_index = 0;
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.loops_closed;
    stats_.loops.push_back(event);
    event_index = stats_.loops.size() - 1;
  }
  lock.unlock();
  pause.unlock();
  start_global_ba(kf.id, event_index);
}

void LoopClosing::stop_global_ba() {
  if (!gba_thread_.joinable()) return;
  gba_abort_.store(true);
  gba_thread_.join();
  gba_abort_.store(false);
}

void LoopClosing::start_global_ba(uint64_t loop_kf_id, std::size_t event_index) {
  if (!config_.loop_closing.global_ba) return;
  stop_global_ba();
  if (!worker_.running()) {
    run_global_ba(loop_kf_id, event_index);  // deterministic mode: in the caller's thread
    return;
  }
  gba_running_.store(true);
  gba_thread_ = std::thread([this, loop_kf_id, event_index] {
    run_global_ba(loop_kf_id, event_index);
    gba_running_.store(false);
  });
}

void LoopClosing::run_global_ba(uint64_t /*loop_kf_id*/, std::size_t event_index) {
  const auto t0 = Clock::now();
  BaProblem problem;
  std::vector<KeyFramePtr> kfs;
  std::vector<MapPointPtr> points;
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    std::unordered_map<const KeyFrame*, int> index;
    for (const KeyFramePtr& k : map_.keyframes()) {
      if (k->bad()) continue;
      index[k.get()] = static_cast<int>(problem.poses.size());
      problem.poses.push_back({k->T_c_w(), k->is_origin()});
      kfs.push_back(k);
    }
    for (const MapPointPtr& p : map_.map_points()) {
      if (p->bad()) continue;
      const int point_index = static_cast<int>(problem.points_w.size());
      bool any = false;
      for (const Observation& o : p->observations()) {
        const auto it = index.find(o.keyframe);
        if (it == index.end()) continue;
        const cv::KeyPoint& kp = o.keyframe->keypoints[static_cast<std::size_t>(o.index)];
        BaProblem::Observation ob;
        ob.pose = it->second;
        ob.point = point_index;
        ob.uv_px = {kp.pt.x, kp.pt.y};
        ob.u_right_px = o.keyframe->u_right[static_cast<std::size_t>(o.index)];
        ob.inv_sigma2 = o.keyframe->geometry->inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
        problem.observations.push_back(ob);
        any = true;
      }
      if (!any) continue;
      problem.points_w.push_back(p->p_w);
      points.push_back(p);
    }
  }
  if (problem.observations.empty()) return;
  OptimizerConfig oc = config_.optimizer;
  oc.local_ba_dense_schur = false;  // hundreds of keyframes: the sparse Schur complement
  const BaStats ba =
      solve_bundle_adjustment(problem, intrinsics_, oc, config_.loop_closing.global_ba_iterations, 0, &gba_abort_);
  const double solve_ms = ms_since(t0);
  if (ba.aborted || gba_abort_.load()) {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.global_ba_aborted;
    return;
  }

  // Merge with local mapping paused.
  auto pause = mapper_.pause();
  std::lock_guard<std::mutex> lock(map_.mutex());
  const auto t_merge = Clock::now();
  std::unordered_map<KeyFrame*, SE3d> after, before;
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    if (!kfs[k]->bad()) after[kfs[k].get()] = problem.poses[k].T_c_w;
  }
  // Keyframes created during the solve follow their spanning-tree parent.
  const KeyFramePtr origin = map_.keyframe(map_.origin_keyframe_id());
  if (origin && after.count(origin.get())) {
    std::deque<KeyFrame*> open{origin.get()};
    std::unordered_set<const KeyFrame*> visited{origin.get()};
    while (!open.empty()) {
      KeyFrame* k = open.front();
      open.pop_front();
      for (KeyFrame* child : k->children()) {
        if (child->bad() || !visited.insert(child).second) continue;
        if (!after.count(child) && after.count(k)) after[child] = child->T_c_w() * k->T_w_c() * after[k];
        open.push_back(child);
      }
    }
  }
  for (const auto& [k, T] : after) before[k] = k->T_c_w();
  std::unordered_set<const MapPoint*> optimised;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (points[i]->bad() || !problem.points_w[i].allFinite()) continue;
    points[i]->p_w = problem.points_w[i];
    optimised.insert(points[i].get());
  }
  for (const MapPointPtr& p : map_.map_points()) {
    if (p->bad() || optimised.count(p.get())) continue;
    KeyFrame* ref = p->reference_keyframe;
    if (!ref || !after.count(ref)) continue;
    p->p_w = after[ref].inverse() * (before[ref] * p->p_w);
  }
  for (const auto& [k, T] : after) {
    if (is_valid_pose(T)) k->set_pose(T);
  }
  for (const MapPointPtr& p : map_.map_points()) {
    if (!p->bad()) p->update_normal_and_depth();
  }
  map_.notify_big_change();
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  ++stats_.global_ba_runs;
  if (event_index < stats_.loops.size()) {
    stats_.loops[event_index].global_ba_ms = solve_ms;
    stats_.loops[event_index].global_ba_merge_ms = ms_since(t_merge);
  }
}

}  // namespace agvslam::slam
