#include "agvslam/slam/system.h"
#include "agvslam/core/clock.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "agvslam/core/error.h"

namespace agvslam::slam {

namespace {

using Clock = std::chrono::steady_clock;

StereoIntrinsics intrinsics_of(const FrameGeometry& g) {
  return {g.camera.fx, g.camera.fy, g.camera.cx, g.camera.cy, g.bf};
}

}  // namespace

std::shared_ptr<const place::Vocabulary> load_vocabulary(const place::PlaceConfig& place_config) {
  return std::make_shared<const place::Vocabulary>(place::Vocabulary::load(place_config.vocabulary_file));
}

const char* to_string(MapMode mode) { return mode == MapMode::kMapping ? "mapping" : "localisation"; }

MapMode parse_map_mode(const std::string& text, const std::string& option) {
  if (text == "map" || text == "mapping") return MapMode::kMapping;
  if (text == "localise" || text == "localisation" || text == "localize" || text == "localization") {
    return MapMode::kLocalisation;
  }
  throw InputError(option, text, "expected localise (track in the map without changing it) or map (extend it)");
}

System::System(const StereoCalibration& calibration, const SystemConfig& config)
    : config_(config),
      calibration_(calibration),
      geometry_(std::make_shared<const FrameGeometry>(
          FrameGeometry::make(calibration.left, calibration.baseline_m, config.slam.tracking.close_depth_baselines,
                              config.orb.n_levels, config.orb.scale_factor))),
      extractor_(config.orb),
      stereo_matcher_(config.stereo, calibration) {
  config_.slam.validate("SystemConfig.slam");
  config_.orb.validate("SystemConfig.orb");
  config_.stereo.validate("SystemConfig.stereo");
  if (!calibration.left.valid() || calibration.baseline_m <= 0) {
    throw InputError("SystemConfig", "calibration", "expected a valid rectified camera and a positive baseline");
  }
  if (!(config_.frame_rate_hz > 0)) throw InputError("SystemConfig", "frame_rate_hz", "expected a positive rate (Hz)");
  if (!(config_.test_mapping_step_delay_ms >= 0 && config_.test_mapping_step_delay_ms <= 10000)) {
    throw InputError("SystemConfig", "test_mapping_step_delay_ms", "expected 0 to 10000 ms");
  }
  if (config_.vocabulary) {
    try {
      place_ = std::make_shared<PlaceRecognition>(config_.vocabulary, config_.direct_index_level);
    } catch (const std::invalid_argument& e) {
      throw InputError("SystemConfig", "vocabulary / direct_index_level", e.what());
    }
  }
  mapper_ = std::make_unique<LocalMapping>(config_.slam, map_, intrinsics_of(*geometry_));
  mapper_->set_test_step_delay_ms(config_.test_mapping_step_delay_ms);
  if (place_) mapper_->set_place_recognition(place_);
  if (place_ && config_.slam.loop_closing.enabled) {
    loop_ = std::make_unique<LoopClosing>(config_.slam, map_, *mapper_, place_, intrinsics_of(*geometry_));
    mapper_->set_keyframe_sink([this](const KeyFramePtr& kf) { loop_->insert(kf); });
  }
  tracking_ = std::make_unique<Tracking>(config_.slam, geometry_, map_, *mapper_, config_.frame_rate_hz);
  if (place_) tracking_->set_place_recognition(place_);
  if (config_.threaded_mapping) {
    mapper_->start();
    if (loop_) loop_->start();
  }
}

System::~System() { shutdown(); }

std::vector<std::string> System::describe() const {
  std::vector<std::string> lines = config_.slam.describe();
  lines.push_back(config_.orb.describe());
  lines.push_back(config_.stereo.describe());
  char buf[160];
  std::snprintf(
      buf, sizeof(buf), "system: %.1f Hz camera, local mapping %s, loop closing %s, mode %s", config_.frame_rate_hz,
      config_.threaded_mapping ? "in its own thread" : "in the tracking thread (deterministic)",
      loop_ ? (config_.threaded_mapping ? "in its own thread" : "in the tracking thread") : "off", to_string(mode_));
  lines.emplace_back(buf);
  if (place_) {
    lines.push_back("place recognition: vocabulary " + place_->vocabulary().describe() + ", direct index level " +
                    std::to_string(place_->direct_index_level()));
  } else {
    lines.emplace_back("place recognition: none (no vocabulary): no relocalisation by bag of words, no loop closing");
  }
  return lines;
}

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  if (loop_) loop_->stop();
  mapper_->stop();
}

void System::request_reset() {
  std::lock_guard<std::mutex> lock(reset_mutex_);
  reset_requested_ = true;
}

void System::reset_now() {
  if (loop_) loop_->reset();
  // Kept until the map is cleared: their points, in the map, point back at them.
  const std::vector<KeyFramePtr> dropped = mapper_->reset();
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    tracking_->reset();
    map_.clear();
    if (place_) place_->clear();
  }
}

void System::start_new_map() {
  if (!config_.earlier_maps_folder.empty()) {
    const std::string path = config_.earlier_maps_folder + "/map_" + std::to_string(map_id_) + ".agvmap";
    try {
      save_map(path);
      std::lock_guard<std::mutex> lock(earlier_files_mutex_);
      earlier_map_files_.push_back(path);
    } catch (const InputError& e) {
      std::lock_guard<std::mutex> lock(earlier_files_mutex_);
      earlier_map_errors_.emplace_back(e.what());
    }
  }
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    for (const TrajectoryEntry& e : trajectory_) {
      SE3d T_c_w;
      if (!map_.resolve_pose(e.reference_kf_id, e.T_c_r, T_c_w)) continue;
      earlier_maps_trajectory_.push_back({e.t_ns, T_c_w.inverse()});
      earlier_maps_ids_.push_back(map_id_);
    }
  }
  trajectory_.clear();
  reset_now();
  ++map_id_;
}

void System::settle() {
  mapper_->wait_until_idle();
  if (loop_) {
    loop_->wait_until_idle();
    mapper_->wait_until_idle();
  }
}

void System::wait_for_mapping() { settle(); }

MapFileContext System::file_context() const {
  return MapFileContext::from(*geometry_, place_ ? place_->vocabulary_id() : 0, config_.direct_index_level);
}

void System::set_mode(MapMode mode) {
  mode_ = mode;
  tracking_->set_localisation_only(mode == MapMode::kLocalisation);
}

MapSaveStats System::save_map(const std::string& path, const MapWriteHooks& hooks) {
  MapSaveStats st;
  auto t0 = Clock::now();
  settle();
  st.wait_ms = ms_since(t0);
  std::string bytes;
  {
    t0 = Clock::now();
    auto pause = mapper_->pause();
    std::lock_guard<std::mutex> lock(map_.mutex());
    bytes = encode_map(map_, file_context());
    st.keyframes = map_.keyframe_count();
    st.map_points = map_.map_point_count();
    st.encode_ms = ms_since(t0);
  }
  st.bytes = bytes.size();
  t0 = Clock::now();
  save_map_file(path, bytes, hooks);
  st.write_ms = ms_since(t0);
  return st;
}

MapLoadStats System::load_map(const std::string& path, MapMode mode) {
  MapLoadStats st;
  auto t0 = Clock::now();
  const std::string bytes = read_map_file(path);
  st.read_ms = ms_since(t0);
  st.bytes = bytes.size();
  // Decoded into a private map first: any error leaves the current map as it is.
  t0 = Clock::now();
  Map incoming;
  decode_map(bytes, path, file_context(), geometry_, incoming);
  st.decode_ms = ms_since(t0);
  t0 = Clock::now();
  if (place_) {
    for (const KeyFramePtr& kf : incoming.keyframes()) place_->compute(*kf);
  }
  st.bow_ms = ms_since(t0);
  if (loop_) loop_->reset();
  // Kept until the map is replaced: their points, in the map, point back at them.
  const std::vector<KeyFramePtr> dropped = mapper_->reset();
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    tracking_->start_relocalising();
    map_.take_from(incoming);
    if (place_) {
      place_->clear();
      for (const KeyFramePtr& kf : map_.keyframes()) place_->on_keyframe_inserted(*kf);
    }
    st.keyframes = map_.keyframe_count();
    st.map_points = map_.map_point_count();
  }
  trajectory_.clear();
  earlier_maps_trajectory_.clear();
  earlier_maps_ids_.clear();
  set_mode(mode);
  return st;
}

TrackResult System::track_stereo(int64_t t_ns, const cv::Mat& left, const cv::Mat& right, const cv::Mat& dynamic_mask) {
  const auto t_start = Clock::now();
  const double cpu_start = thread_cpu_ms();
  TrackResult r;
  r.t_ns = t_ns;
  r.frame_id = next_frame_id_++;
  if (shut_down_) throw std::logic_error("System::track_stereo after shutdown()");
  {
    std::lock_guard<std::mutex> lock(reset_mutex_);
    if (reset_requested_) {
      reset_requested_ = false;
      reset_now();
      r.counts.reset = true;
    }
  }

  auto t0 = Clock::now();
  extractor_.extract(left, dynamic_mask, keypoints_);
  r.timings.extract_ms = ms_since(t0);
  t0 = Clock::now();
  stereo_matcher_.match(extractor_, keypoints_, right, depth_);
  r.timings.stereo_ms = ms_since(t0);

  frame_.assign(r.frame_id, t_ns, geometry_, keypoints_.keypoints, keypoints_.descriptors, depth_.u_right_px,
                depth_.depth_m);
  TrackingCounts counts;
  r.state = tracking_->track(frame_, r.timings, counts, FrameImages{left, right, dynamic_mask});
  if (counts.retired.total() > 0) {
    std::lock_guard<std::mutex> lock(retired_mutex_);
    retired_ += counts.retired;
  }
  const bool was_reset = r.counts.reset;
  r.counts = counts;
  r.counts.reset = r.counts.reset || was_reset;

  if (r.state == TrackingState::kOk) take_pose(r);
  if (counts.reset) reset_now();
  if (counts.new_map) {
    // The frame that waited out the loss initialises the new map at once (its features are still here).
    start_new_map();
    frame_.assign(r.frame_id, t_ns, geometry_, keypoints_.keypoints, keypoints_.descriptors, depth_.u_right_px,
                  depth_.depth_m);
    TrackingCounts init_counts;
    TrackTimings init_timings;
    r.state = tracking_->track(frame_, init_timings, init_counts, FrameImages{left, right, dynamic_mask});
    r.counts.method = init_counts.method;
    r.counts.inliers = init_counts.inliers;
    r.counts.new_keyframe = init_counts.new_keyframe;
    r.timings.keyframe_ms += init_timings.keyframe_ms;
    if (r.state == TrackingState::kOk) take_pose(r);
  }
  r.map_id = map_id_;
  if (!config_.threaded_mapping) {
    const auto t_map = Clock::now();
    mapper_->process_pending();
    if (loop_) loop_->process_pending();
    r.timings.inline_mapping_ms = ms_since(t_map);
  }
  if (loop_) {
    r.loops_closed = loop_->stats().loops_closed;
    r.global_ba_running = loop_->global_ba_running();
  }
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    r.keyframes = map_.keyframe_count();
    r.map_points = map_.map_point_count();
  }
  r.mapping_queue = mapper_->queue_length();
  r.timings.total_ms = ms_since(t_start);
  r.timings.total_cpu_ms = thread_cpu_ms() - cpu_start;
  return r;
}

void System::take_pose(TrackResult& r) {
  const Frame& f = tracking_->last_frame();
  r.pose_valid = true;
  r.T_w_c = f.T_w_c();
  r.inlier_keypoints_px.clear();
  r.inlier_keypoints_px.reserve(f.size());
  for (std::size_t i = 0; i < f.size(); ++i)
    if (f.map_points[i] && !f.outlier[i]) r.inlier_keypoints_px.push_back(f.keypoints[i].pt);
  if (f.reference_keyframe) trajectory_.push_back({r.t_ns, f.reference_keyframe->id, tracking_->last_relative_pose()});
}

std::vector<std::string> System::earlier_map_files() const {
  std::lock_guard<std::mutex> lock(earlier_files_mutex_);
  return earlier_map_files_;
}

std::vector<std::string> System::earlier_map_errors() const {
  std::lock_guard<std::mutex> lock(earlier_files_mutex_);
  return earlier_map_errors_;
}

RetirementCounts System::retirement_counts() const {
  std::lock_guard<std::mutex> lock(retired_mutex_);
  return retired_;
}

Trajectory System::trajectory(std::vector<uint32_t>* map_ids) {
  Trajectory out = earlier_maps_trajectory_;
  if (map_ids) *map_ids = earlier_maps_ids_;
  out.reserve(out.size() + trajectory_.size());
  std::lock_guard<std::mutex> lock(map_.mutex());
  for (const TrajectoryEntry& e : trajectory_) {
    SE3d T_c_w;
    if (!map_.resolve_pose(e.reference_kf_id, e.T_c_r, T_c_w)) continue;
    out.push_back({e.t_ns, T_c_w.inverse()});
    if (map_ids) map_ids->push_back(map_id_);
  }
  return out;
}

}  // namespace agvslam::slam
