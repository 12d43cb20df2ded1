#include "agvslam/slam/tracking.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <unordered_map>

#include <opencv2/calib3d.hpp>

#include "agvslam/slam/local_mapping.h"
#include "agvslam/slam/map.h"

namespace agvslam::slam {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kInitialising:
      return "initialising";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
  }
  return "?";
}

Tracking::Tracking(const SlamConfig& config, FrameGeometryPtr geometry, Map& map, LocalMapping& mapper,
                   double frame_rate_hz)
    : config_(config),
      geometry_(std::move(geometry)),
      intrinsics_{geometry_->camera.fx, geometry_->camera.fy, geometry_->camera.cx, geometry_->camera.cy,
                  geometry_->bf},
      map_(map),
      mapper_(mapper),
      retirement_(config.retirement, intrinsics_) {
  const int rate = std::max(1, static_cast<int>(std::lround(frame_rate_hz)));
  max_frames_ = config_.tracking.keyframe_max_frames > 0 ? config_.tracking.keyframe_max_frames : rate;
  min_frames_ = config_.tracking.keyframe_min_frames;
}

void Tracking::reset() {
  state_ = TrackingState::kInitialising;
  current_ = Frame();
  last_frame_ = Frame();
  reference_kf_.reset();
  has_velocity_ = false;
  lost_frames_ = 0;
  lost_usable_ns_ = 0;
  last_lost_t_ns_ = 0;
  previous_inliers_ = 0;
  local_keyframes_.clear();
  local_points_.clear();
  map_loaded_ = false;
  last_recovery_frame_id_ = 0;
}

void Tracking::start_relocalising() {
  reset();
  state_ = TrackingState::kLost;
  map_loaded_ = true;
}

TrackingState Tracking::track(Frame& frame, TrackTimings& timings, TrackingCounts& counts, const FrameImages& images) {
  std::swap(current_, frame);
  counts.features = static_cast<int>(current_.size());
  counts.stereo_features =
      static_cast<int>(std::count_if(current_.depth.begin(), current_.depth.end(), [](float d) { return d > 0; }));

  const auto t_wait = Clock::now();
  std::unique_lock<std::mutex> lock(map_.mutex());
  timings.map_wait_ms = ms_since(t_wait);

  if (state_ == TrackingState::kInitialising) {
    const auto t0 = Clock::now();
    if (stereo_initialisation()) {
      state_ = TrackingState::kOk;
      counts.new_keyframe = true;
      counts.method = "init";
      counts.inliers = current_.tracked_count();
    }
    timings.keyframe_ms = ms_since(t0);
    if (state_ == TrackingState::kOk) {
      last_T_c_r_ = SE3d::Identity();
      std::swap(last_frame_, current_);
    }
    return state_;
  }

  const auto t_frame = Clock::now();
  bool ok = false;
  int matches = 0;
  const bool was_lost = state_ == TrackingState::kLost;
  if (!was_lost) {
    check_replaced_in_last_frame();
    if (has_velocity_ && current_.id >= last_recovery_frame_id_ + 2) {
      ok = track_with_motion_model(matches);
      counts.method = "motion_model";
    }
    if (!ok && reference_kf_ && !reference_kf_->bad()) {
      ok = track_reference_keyframe(*reference_kf_, last_frame_.T_c_w(), matches);
      counts.method = "reference";
    }
  } else {
    ok = recover(matches, counts);
    if (ok) {
      counts.recovered = true;
      last_recovery_frame_id_ = current_.id;
    }
  }
  counts.frame_matches = matches;
  timings.frame_ms = ms_since(t_frame);

  current_.reference_keyframe = reference_kf_;
  if (ok) {
    const auto t_local = Clock::now();
    ok = track_local_map(inliers_);
    counts.inliers = inliers_;
    timings.local_map_ms = ms_since(t_local);
  }

  if (ok) {
    state_ = TrackingState::kOk;
    lost_frames_ = 0;
    lost_usable_ns_ = 0;
    last_lost_t_ns_ = 0;
    if (last_frame_.has_pose() && !was_lost) {
      velocity_ = current_.T_c_w() * last_frame_.T_w_c();
      has_velocity_ = true;
      velocity_dt_ns_ = current_.t_ns - last_frame_.t_ns;
    } else {
      has_velocity_ = false;
    }
    const auto t_retire = Clock::now();
    const double cpu_retire = thread_cpu_ms();
    retire_moved_points(images, counts);
    timings.retire_cpu_ms = thread_cpu_ms() - cpu_retire;
    timings.retire_ms = ms_since(t_retire);
    const auto t_kf = Clock::now();
    const KeyframeNeed need = need_new_keyframe();
    bool make_keyframe = need == KeyframeNeed::kNow;
    if (need == KeyframeNeed::kWhenQueueHasRoom) {
      // Local mapping needs the map mutex to take a keyframe off its queue: released while waiting. The local map's
      // raw pointers may dangle afterwards; the next frame rebuilds them.
      local_keyframes_.clear();
      local_points_.clear();
      lock.unlock();
      const auto t_room = Clock::now();
      // Near loss: few inliers now, or at their decline since the last frame (the same ratio again) few next frame.
      const int predicted = previous_inliers_ > inliers_ ? inliers_ * inliers_ / previous_inliers_ : inliers_;
      const bool weak = predicted < 2 * config_.tracking.min_local_map_inliers;
      make_keyframe = mapper_.wait_for_room(weak ? config_.tracking.keyframe_queue_wait_weak_ms
                                                 : config_.tracking.keyframe_queue_wait_ms);
      timings.keyframe_wait_ms = ms_since(t_room);
      lock.lock();
      counts.keyframe_waited = true;
    }
    if (make_keyframe) {
      create_new_keyframe();
      counts.new_keyframe = true;
    }
    timings.keyframe_ms = ms_since(t_kf);
    previous_inliers_ = make_keyframe ? 0 : inliers_;  // a new keyframe renews the inliers: no decline to measure
    // Outliers may go to a new keyframe (local BA decides), but the next frame does not use them.
    for (std::size_t i = 0; i < current_.size(); ++i) {
      if (current_.map_points[i] && current_.outlier[i]) current_.map_points[i].reset();
    }
  } else {
    state_ = TrackingState::kLost;
    has_velocity_ = false;
    previous_inliers_ = 0;
    ++lost_frames_;
    if (!map_loaded_ && !localisation_only_ && lost_frames_ >= config_.tracking.reset_after_lost_frames &&
        map_.keyframe_count() <= static_cast<std::size_t>(config_.tracking.reset_max_keyframes)) {
      // Lost right after initialisation: start again (the caller's System clears the map).
      counts.reset = true;
    }
    // Relocalisation's time runs only on frames that could start a map (a covered camera shows nothing to
    // relocalise with): after new_map_after_lost_s of them, a new map from this frame (the caller's System keeps
    // the old trajectory).
    const bool usable = can_initialise();
    if (usable && last_lost_t_ns_ > 0) lost_usable_ns_ += current_.t_ns - last_lost_t_ns_;
    last_lost_t_ns_ = current_.t_ns;
    const double new_map_after_s = config_.tracking.new_map_after_lost_s;
    if (!counts.reset && !map_loaded_ && !localisation_only_ && new_map_after_s > 0 && usable &&
        1e-9 * static_cast<double>(lost_usable_ns_) >= new_map_after_s) {
      counts.new_map = true;
    }
  }
  if (!current_.reference_keyframe) current_.reference_keyframe = reference_kf_;
  // The last frame keeps its pose only when tracked (a lost frame's pose is meaningless).
  if (state_ == TrackingState::kOk) {
    last_T_c_r_ = current_.T_c_w() * current_.reference_keyframe->T_w_c();
    std::swap(last_frame_, current_);
  }
  return state_;
}

bool Tracking::can_initialise() const {
  int with_depth = 0;
  for (float d : current_.depth) with_depth += d > 0 ? 1 : 0;
  return static_cast<int>(current_.size()) > config_.tracking.min_init_features &&
         with_depth >= config_.tracking.min_init_stereo;
}

bool Tracking::stereo_initialisation() {
  if (!can_initialise()) return false;
  current_.set_pose(SE3d::Identity());
  auto kf = std::make_shared<KeyFrame>(map_.new_keyframe_id(), current_);
  map_.add_keyframe(kf);
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (current_.depth[i] <= 0) continue;
    auto point =
        std::make_shared<MapPoint>(map_.new_map_point_id(), current_.unproject_stereo(i), kf.get(), current_.id);
    point->add_observation(kf.get(), static_cast<int>(i));
    kf->add_map_point(point, i);
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
    map_.add_map_point(point);
    current_.map_points[i] = point;
  }
  reference_kf_ = kf;
  current_.reference_keyframe = kf;
  last_keyframe_frame_id_ = current_.id;
  last_keyframe_center_w_ = current_.T_w_c().translation();
  local_keyframes_.assign(1, kf.get());
  local_points_.clear();
  for (const MapPointPtr& p : kf->map_points()) {
    if (p) local_points_.push_back(p.get());
  }
  mapper_.try_insert(kf);
  return true;
}

void Tracking::check_replaced_in_last_frame() {
  for (MapPointPtr& p : last_frame_.map_points) {
    if (!p) continue;
    // Follow the replacement chain (fusion may have replaced a point more than once).
    while (p && p->replaced()) p = p->replaced();
    if (p && p->bad()) p.reset();
  }
}

int Tracking::optimize_current_pose() {
  observations_.clear();
  observation_keypoint_.clear();
  for (std::size_t i = 0; i < current_.size(); ++i) {
    const MapPointPtr& p = current_.map_points[i];
    if (!p) continue;
    PoseObservation o;
    o.p_w = p->p_w;
    o.uv_px = {current_.keypoints[i].pt.x, current_.keypoints[i].pt.y};
    o.u_right_px = current_.u_right[i];
    o.inv_sigma2 = geometry_->inv_level_sigma2[static_cast<std::size_t>(current_.keypoints[i].octave)];
    observations_.push_back(o);
    observation_keypoint_.push_back(static_cast<int>(i));
  }
  SE3d T = current_.T_c_w();
  const MotionOnlyStats stats = optimize_pose(intrinsics_, config_.optimizer, observations_, observation_outlier_, T);
  if (stats.rounds > 0 && is_valid_pose(T)) current_.set_pose(T);
  std::fill(current_.outlier.begin(), current_.outlier.end(), 0);
  for (std::size_t k = 0; k < observation_keypoint_.size(); ++k) {
    current_.outlier[static_cast<std::size_t>(observation_keypoint_[k])] =
        observation_outlier_.empty() ? 1 : observation_outlier_[k];
  }
  return stats.inliers;
}

int Tracking::discard_outliers() {
  int in_map = 0;
  for (std::size_t i = 0; i < current_.size(); ++i) {
    MapPointPtr& p = current_.map_points[i];
    if (!p) continue;
    if (current_.outlier[i]) {
      p->track.last_frame_seen = current_.id;
      p.reset();
      current_.outlier[i] = 0;
    } else if (!p->observations().empty()) {
      ++in_map;
    }
  }
  return in_map;
}

SE3d Tracking::predicted_motion() const {
  const int64_t dt_ns = current_.t_ns - last_frame_.t_ns;
  if (velocity_dt_ns_ <= 0 || dt_ns <= 0) return velocity_;
  const double ratio = static_cast<double>(dt_ns) / static_cast<double>(velocity_dt_ns_);
  if (std::abs(ratio - 1.0) < 0.05) return velocity_;  // the usual case: one camera period each
  // Constant velocity in time, not per frame: a frame the pipeline dropped (or a camera that skipped one) leaves
  // twice the motion to the next. At most 5 periods ahead (a longer gap is not constant velocity any more).
  return se3_exp(std::min(ratio, 5.0) * se3_log(velocity_));
}

bool Tracking::track_with_motion_model(int& matches) {
  // The last frame's pose relative to its reference keyframe follows local BA's corrections of that keyframe
  // (ORB-SLAM2's UpdateLastFrame).
  const KeyFramePtr& last_ref = last_frame_.reference_keyframe;
  if (last_ref && !last_ref->bad()) last_frame_.set_pose(last_T_c_r_ * last_ref->T_c_w());
  current_.set_pose(predicted_motion() * last_frame_.T_c_w());
  std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
  const float radius = static_cast<float>(config_.tracking.motion_model_radius_px);
  matches = matcher_.search_last_frame(current_, last_frame_, radius, true);
  if (matches < config_.tracking.min_motion_model_matches) {
    std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
    matches = matcher_.search_last_frame(current_, last_frame_, 2 * radius, true);
  }
  int in_map = 0;
  if (matches >= config_.tracking.min_motion_model_matches) {
    optimize_current_pose();
    in_map = discard_outliers();
  }
  // Beyond ORB-SLAM2: when the model was poor (an abrupt turn or stop: the vehicle's angular velocity changes
  // within a frame), most points fall outside the window and the pose rests on a few, partly wrong matches.
  // Search again from the predicted pose with a window wide enough for a few degrees of unexpected rotation,
  // with a ratio test against repetitive structure, and keep the better of the two results.
  const int last_tracked = last_frame_.tracked_count();
  if (in_map < last_tracked / 2) {
    const SE3d T_first = current_.T_c_w();
    const std::vector<MapPointPtr> matches_first = current_.map_points;
    current_.set_pose(predicted_motion() * last_frame_.T_c_w());
    std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
    const int wide = matcher_.search_last_frame(current_, last_frame_, 4 * radius, true, 0.8f);
    int in_map_wide = 0;
    if (wide >= config_.tracking.min_motion_model_matches) {
      optimize_current_pose();
      in_map_wide = discard_outliers();
    }
    if (in_map_wide > in_map) {
      in_map = in_map_wide;
      matches = wide;
    } else {
      current_.set_pose(T_first);
      current_.map_points = matches_first;
    }
  }
  return in_map >= config_.tracking.min_frame_inliers;
}

bool Tracking::track_reference_keyframe(const KeyFrame& kf, const SE3d& T_c_w_guess, int& matches) {
  const float ratio = static_cast<float>(config_.tracking.reference_ratio);
  if (place_ && config_.tracking.bow_matching) {
    // ORB-SLAM2's TrackReferenceKeyFrame: only features in the same vocabulary node are compared. A keyframe that
    // local mapping has not inserted yet gets its BoW here (map mutex held).
    place_->compute(current_);
    place_->compute(const_cast<KeyFrame&>(kf));
    matches = matcher_.search_by_bow(kf, current_, ratio, matches_);
  } else {
    matches = matcher_.search_keyframe_brute_force(kf, current_, ratio, matches_);
  }
  if (matches < config_.tracking.min_reference_matches) return false;
  current_.map_points = matches_;
  current_.set_pose(T_c_w_guess);
  optimize_current_pose();
  const int in_map = discard_outliers();
  return in_map >= config_.tracking.min_frame_inliers;
}

bool Tracking::recover(int& matches, TrackingCounts& counts) {
  counts.method = "relocalisation";
  if (relocalise(matches, counts)) return true;
  // Then the last reference keyframe and its best neighbours, each from its own pose (short losses, maps
  // without a vocabulary). A loaded map has no last reference: only relocalisation applies.
  counts.method = "recovery";
  if (map_loaded_ && !reference_kf_) return false;
  if (!reference_kf_ || reference_kf_->bad()) {
    // The reference was culled while lost: take the newest keyframe of the map.
    const auto kfs = map_.keyframes();
    if (kfs.empty()) return false;
    reference_kf_ = kfs.back();
  }
  std::vector<KeyFrame*> candidates{reference_kf_.get()};
  for (KeyFrame* kf : reference_kf_->best_covisibles(4)) candidates.push_back(kf);
  for (KeyFrame* kf : candidates) {
    if (kf->bad()) continue;
    std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
    if (track_reference_keyframe(*kf, kf->T_c_w(), matches)) {
      reference_kf_ = kf->shared_from_this();
      return true;
    }
  }
  std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
  return false;
}

void Tracking::drop_outlier_matches() {
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (current_.map_points[i] && current_.outlier[i]) current_.map_points[i].reset();
    current_.outlier[i] = 0;
  }
}

bool Tracking::relocalise(int& matches, TrackingCounts& counts) {
  if (!place_ || map_.keyframe_count() == 0) return false;
  const RelocalisationConfig& rc = config_.relocalisation;
  const std::vector<KeyFrame*> candidates =
      place_->relocalisation_candidates(current_, map_, static_cast<std::size_t>(rc.max_candidates));
  counts.relocalisation_candidates = static_cast<int>(candidates.size());
  const PinholeCamera& cam = geometry_->camera;
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  std::vector<cv::Point3d> object_points;
  std::vector<cv::Point2d> image_points;
  std::vector<int> keypoint_of;
  std::vector<int> inliers;
  for (KeyFrame* kf : candidates) {
    if (kf->bad()) continue;
    place_->compute(*kf);
    const int n = matcher_.search_by_bow(*kf, current_, static_cast<float>(rc.bow_ratio), matches_);
    if (n < rc.min_bow_matches) continue;
    object_points.clear();
    image_points.clear();
    keypoint_of.clear();
    for (std::size_t i = 0; i < matches_.size(); ++i) {
      if (!matches_[i]) continue;
      const Eigen::Vector3d& p = matches_[i]->p_w;
      object_points.emplace_back(p.x(), p.y(), p.z());
      image_points.emplace_back(current_.keypoints[i].pt.x, current_.keypoints[i].pt.y);
      keypoint_of.push_back(static_cast<int>(i));
    }
    cv::Mat rvec, tvec;
    inliers.clear();
    bool solved = false;
    try {
      solved = cv::solvePnPRansac(object_points, image_points, K, cv::noArray(), rvec, tvec, false, rc.pnp_iterations,
                                  static_cast<float>(rc.pnp_reprojection_px), 0.99, inliers, cv::SOLVEPNP_EPNP);
    } catch (const cv::Exception&) {
      solved = false;  // degenerate configuration
    }
    if (!solved || static_cast<int>(inliers.size()) < rc.min_pnp_inliers) continue;
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d R_c_w;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R_c_w(r, c) = R(r, c);
    }
    const SE3d T_c_w = make_se3(Eigen::Quaterniond(R_c_w).normalized(),
                                Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
    if (!is_valid_pose(T_c_w)) continue;
    std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
    for (const int k : inliers) {
      const std::size_t i = static_cast<std::size_t>(keypoint_of[static_cast<std::size_t>(k)]);
      current_.map_points[i] = matches_[i];
    }
    current_.set_pose(T_c_w);
    int good = optimize_current_pose();
    if (good < rc.min_pnp_inliers) continue;
    drop_outlier_matches();
    if (good < rc.min_inliers) {
      // More matches by projecting the candidate's points with the estimated pose (ORB-SLAM2: 10 px, then 3 px).
      int added = matcher_.search_keyframe_projection(current_, *kf, static_cast<float>(rc.projection_radius_px), 100);
      if (good + added >= rc.min_inliers) {
        good = optimize_current_pose();
        if (good > 30 && good < rc.min_inliers) {
          drop_outlier_matches();
          added = matcher_.search_keyframe_projection(current_, *kf, 3.0f, 64);
          if (good + added >= rc.min_inliers) good = optimize_current_pose();
        }
        drop_outlier_matches();
      }
    }
    if (good >= rc.min_inliers) {
      matches = good;
      reference_kf_ = kf->shared_from_this();
      return true;
    }
  }
  std::fill(current_.map_points.begin(), current_.map_points.end(), nullptr);
  return false;
}

void Tracking::update_local_map() {
  // Keyframes that see the frame's points, weighted by how many.
  std::unordered_map<KeyFrame*, int> counter;
  for (MapPointPtr& p : current_.map_points) {
    if (!p) continue;
    if (p->bad()) {
      p.reset();
      continue;
    }
    for (const Observation& o : p->observations()) ++counter[o.keyframe];
  }
  local_keyframes_.clear();
  KeyFrame* best = nullptr;
  int best_count = 0;
  for (const auto& [kf, n] : counter) {
    if (kf->bad()) continue;
    if (n > best_count || (n == best_count && best && kf->id < best->id)) {
      best_count = n;
      best = kf;
    }
    local_keyframes_.push_back(kf);
    kf->track.local_for_frame = current_.id;
  }
  std::sort(local_keyframes_.begin(), local_keyframes_.end(),
            [](const KeyFrame* a, const KeyFrame* b) { return a->id < b->id; });
  // Neighbours: ORB-SLAM2 adds one new neighbour, child and the parent per keyframe.
  const std::size_t max_kfs = static_cast<std::size_t>(config_.tracking.max_local_keyframes);
  const std::size_t first_order = local_keyframes_.size();
  for (std::size_t k = 0; k < first_order && local_keyframes_.size() < max_kfs; ++k) {
    KeyFrame* kf = local_keyframes_[k];
    for (KeyFrame* n : kf->best_covisibles(10)) {
      if (!n->bad() && n->track.local_for_frame != current_.id) {
        n->track.local_for_frame = current_.id;
        local_keyframes_.push_back(n);
        break;
      }
    }
    for (KeyFrame* c : kf->children()) {
      if (!c->bad() && c->track.local_for_frame != current_.id) {
        c->track.local_for_frame = current_.id;
        local_keyframes_.push_back(c);
        break;
      }
    }
    KeyFrame* parent = kf->parent();
    if (parent && !parent->bad() && parent->track.local_for_frame != current_.id) {
      parent->track.local_for_frame = current_.id;
      local_keyframes_.push_back(parent);
    }
  }
  if (best) {
    reference_kf_ = best->shared_from_this();
    current_.reference_keyframe = reference_kf_;
  }
  // Their points.
  local_points_.clear();
  for (KeyFrame* kf : local_keyframes_) {
    for (const MapPointPtr& p : kf->map_points()) {
      if (!p || p->bad() || p->track.reference_for_frame == current_.id) continue;
      p->track.reference_for_frame = current_.id;
      local_points_.push_back(p.get());
    }
  }
}

void Tracking::search_local_points() {
  for (MapPointPtr& p : current_.map_points) {
    if (!p) continue;
    if (p->bad()) {
      p.reset();
      continue;
    }
    p->increase_visible();
    p->track.last_frame_seen = current_.id;
    p->track.in_view = false;
  }
  int to_match = 0;
  for (MapPoint* p : local_points_) {
    if (p->track.last_frame_seen == current_.id || p->bad()) {
      p->track.in_view = false;
      continue;
    }
    if (current_.is_in_frustum(*p, 0.5)) {
      p->increase_visible();
      ++to_match;
    }
  }
  if (to_match > 0) {
    const float th = static_cast<float>(config_.tracking.local_map_radius) *
                     (current_.id < last_recovery_frame_id_ + 2 ? 5.0f : 1.0f);
    matcher_.search_local_points(current_, local_points_, th);
  }
}

bool Tracking::track_local_map(int& inliers) {
  update_local_map();
  search_local_points();
  optimize_current_pose();
  inliers = 0;
  pose_matches_.clear();
  for (std::size_t i = 0; i < current_.size(); ++i) {
    MapPointPtr& p = current_.map_points[i];
    if (!p) continue;
    pose_matches_.push_back({p, static_cast<int>(i)});
    if (!current_.outlier[i]) {
      p->increase_found();
      if (!p->observations().empty()) ++inliers;
    } else {
      p.reset();  // stereo: outliers are dropped at once (ORB-SLAM2)
      current_.outlier[i] = 0;
    }
  }
  const int needed =
      current_.id < last_recovery_frame_id_ + static_cast<uint64_t>(max_frames_) && last_recovery_frame_id_ > 0
          ? std::max(50, config_.tracking.min_local_map_inliers)
          : config_.tracking.min_local_map_inliers;
  return inliers >= needed;
}

void Tracking::retire_moved_points(const FrameImages& images, TrackingCounts& counts) {
  if (localisation_only_) return;
  counts.retired = retirement_.update(current_, pose_matches_, local_points_, images, map_);
  pose_matches_.clear();
  if (counts.retired.total() == 0) return;
  for (MapPointPtr& p : current_.map_points) {
    if (p && p->bad()) p.reset();
  }
}

Tracking::KeyframeNeed Tracking::need_new_keyframe() {
  if (!reference_kf_ || localisation_only_) return KeyframeNeed::kNo;
  const std::size_t n_kfs = map_.keyframe_count();
  if (current_.id < last_recovery_frame_id_ + static_cast<uint64_t>(max_frames_) && last_recovery_frame_id_ > 0 &&
      n_kfs > static_cast<std::size_t>(max_frames_)) {
    return KeyframeNeed::kNo;
  }
  const int min_obs = n_kfs <= 2 ? 2 : 3;
  const int ref_matches = reference_kf_->tracked_map_points(min_obs);
  const bool mapper_idle = mapper_.idle();

  int tracked_close = 0, untracked_close = 0;
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (!current_.is_close(i)) continue;
    if (current_.map_points[i] && !current_.outlier[i]) {
      ++tracked_close;
    } else {
      ++untracked_close;
    }
  }
  const bool need_close = tracked_close < config_.tracking.keyframe_close_tracked &&
                          untracked_close > config_.tracking.keyframe_close_untracked;
  const double ref_ratio = n_kfs < 2 ? 0.4 : config_.tracking.keyframe_ref_ratio;
  const bool c1a = current_.id >= last_keyframe_frame_id_ + static_cast<uint64_t>(max_frames_);
  const bool c1b = current_.id >= last_keyframe_frame_id_ + static_cast<uint64_t>(min_frames_) && mapper_idle;
  const bool weak = inliers_ < ref_matches * 0.25;
  const bool c1c = weak || need_close;
  const bool c2 = (inliers_ < ref_matches * ref_ratio || need_close) && inliers_ > 15;
  // A stop (beyond ORB-SLAM2): the camera has come to rest keyframe_stop_distance_m or more from where the last
  // keyframe was made. Slowing down keeps most of the reference's points in view, so c2 would make none, and the
  // place where an AGV stops (a station, the start of a loop) is where the map must hold a keyframe.
  const TrackingConfig& tc = config_.tracking;
  bool stopped = false;
  if (tc.keyframe_stop_distance_m > 0 && has_velocity_ && velocity_dt_ns_ > 0) {
    const double speed_mps = velocity_.translation().norm() / (1e-9 * static_cast<double>(velocity_dt_ns_));
    stopped = speed_mps <= tc.keyframe_stop_speed_mps &&
              (current_.T_w_c().translation() - last_keyframe_center_w_).norm() >= tc.keyframe_stop_distance_m;
  }
  if (!((c1a || c1b || c1c) && c2) && !stopped) return KeyframeNeed::kNo;
  if (KeyFrame* old_kf = weak ? nullptr : revisited_keyframe()) {
    // The place is already in the map from an earlier pass: track against that keyframe instead of adding one.
    reference_kf_ = old_kf->shared_from_this();
    current_.reference_keyframe = reference_kf_;
    return KeyframeNeed::kNo;
  }
  if (mapper_idle) return KeyframeNeed::kNow;
  mapper_.interrupt_ba();
  if (mapper_.queue_length() < static_cast<std::size_t>(config_.mapping.queue_capacity)) return KeyframeNeed::kNow;
  return config_.tracking.keyframe_queue_wait_weak_ms > 0 ? KeyframeNeed::kWhenQueueHasRoom : KeyframeNeed::kNo;
}

KeyFrame* Tracking::revisited_keyframe() const {
  const TrackingConfig& tc = config_.tracking;
  if (tc.keyframe_revisit_distance_m <= 0 || inliers_ <= 0) return nullptr;
  const int64_t min_age_ns = static_cast<int64_t>(tc.keyframe_revisit_min_age_s * 1e9);
  const SE3d& T_w_c = current_.T_w_c();
  const Eigen::Vector3d axis = T_w_c.linear().col(2);
  const double cos_max = std::cos(tc.keyframe_revisit_angle_deg * M_PI / 180.0);
  KeyFrame* best = nullptr;
  int best_shared = 0;
  for (KeyFrame* k : local_keyframes_) {
    if (k->bad() || current_.t_ns - k->t_ns < min_age_ns) continue;
    const SE3d& T_w_k = k->T_w_c();
    if ((T_w_k.translation() - T_w_c.translation()).norm() > tc.keyframe_revisit_distance_m) continue;
    if (T_w_k.linear().col(2).dot(axis) < cos_max) continue;
    int shared = 0;
    for (std::size_t i = 0; i < current_.size(); ++i) {
      const MapPointPtr& p = current_.map_points[i];
      if (p && !current_.outlier[i] && p->is_in(k)) ++shared;
    }
    if (shared > best_shared) {
      best_shared = shared;
      best = k;
    }
  }
  return best && best_shared >= tc.keyframe_revisit_shared * inliers_ ? best : nullptr;
}

void Tracking::create_new_keyframe() {
  auto kf = std::make_shared<KeyFrame>(map_.new_keyframe_id(), current_);
  // New map points from the closest stereo keypoints without one: all close ones, at least keyframe_max_new_points.
  std::vector<std::pair<float, std::size_t>> by_depth;
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (current_.depth[i] > 0) by_depth.emplace_back(current_.depth[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  int n_points = 0;
  for (const auto& [z, i] : by_depth) {
    MapPointPtr& existing = current_.map_points[i];
    bool create = !existing;
    if (existing && existing->observations().empty()) {
      existing.reset();
      create = true;
    }
    if (create) {
      auto point =
          std::make_shared<MapPoint>(map_.new_map_point_id(), current_.unproject_stereo(i), kf.get(), current_.id);
      point->add_observation(kf.get(), static_cast<int>(i));
      kf->add_map_point(point, i);
      point->compute_distinctive_descriptor();
      point->update_normal_and_depth();
      map_.add_map_point(point);
      current_.map_points[i] = point;
    }
    ++n_points;
    if (z > geometry_->close_depth_m && n_points > config_.tracking.keyframe_max_new_points) break;
  }
  if (!mapper_.try_insert(kf)) {
    // The mapper's queue is full: the keyframe is dropped, and so are the points it just created.
    for (std::size_t i = 0; i < current_.size(); ++i) {
      const MapPointPtr& p = kf->map_point(i);
      if (p && p->observations().size() == 1 && p->is_in(kf.get())) {
        current_.map_points[i].reset();
        p->set_bad(map_);
      }
    }
    return;
  }
  reference_kf_ = kf;
  current_.reference_keyframe = kf;
  last_keyframe_frame_id_ = current_.id;
  last_keyframe_center_w_ = current_.T_w_c().translation();
}

}  // namespace agvslam::slam
