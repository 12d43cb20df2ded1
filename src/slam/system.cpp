#include "agvslam/slam/system.h"

#include <chrono>
#include <cstdio>

#include "agvslam/core/error.h"

namespace agvslam::slam {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

StereoIntrinsics intrinsics_of(const FrameGeometry& g) {
  return {g.camera.fx, g.camera.fy, g.camera.cx, g.camera.cy, g.bf};
}

}  // namespace

System::System(const StereoCalibration& calibration, const SystemConfig& config)
    : config_(config),
      calibration_(calibration),
      geometry_(std::make_shared<const FrameGeometry>(FrameGeometry::make(
          calibration.left, calibration.baseline_m, config.slam.tracking.close_depth_baselines, config.orb.n_levels,
          config.orb.scale_factor))),
      extractor_(config.orb),
      stereo_matcher_(config.stereo, calibration) {
  config_.slam.validate("SystemConfig.slam");
  config_.orb.validate("SystemConfig.orb");
  config_.stereo.validate("SystemConfig.stereo");
  if (!calibration.left.valid() || calibration.baseline_m <= 0) {
    throw InputError("SystemConfig", "calibration", "expected a valid rectified camera and a positive baseline");
  }
  if (!(config_.frame_rate_hz > 0)) throw InputError("SystemConfig", "frame_rate_hz", "expected a positive rate (Hz)");
  mapper_ = std::make_unique<LocalMapping>(config_.slam, map_, intrinsics_of(*geometry_));
  tracking_ = std::make_unique<Tracking>(config_.slam, geometry_, map_, *mapper_, config_.frame_rate_hz);
  if (config_.threaded_mapping) mapper_->start();
}

System::~System() { shutdown(); }

std::vector<std::string> System::describe() const {
  std::vector<std::string> lines = config_.slam.describe();
  lines.push_back(config_.orb.describe());
  lines.push_back(config_.stereo.describe());
  char buf[160];
  std::snprintf(buf, sizeof(buf), "system: %.1f Hz camera, local mapping %s", config_.frame_rate_hz,
                config_.threaded_mapping ? "in its own thread" : "in the tracking thread (deterministic)");
  lines.emplace_back(buf);
  return lines;
}

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  mapper_->stop();
}

void System::request_reset() {
  std::lock_guard<std::mutex> lock(reset_mutex_);
  reset_requested_ = true;
}

void System::reset_now() {
  mapper_->reset();
  {
    std::lock_guard<std::mutex> lock(map_.mutex());
    tracking_->reset();
    map_.clear();
  }
}

void System::set_place_recognition(const std::shared_ptr<PlaceRecognition>& place) {
  mapper_->set_place_recognition(place);
  tracking_->set_place_recognition(place);
}

void System::wait_for_mapping() { mapper_->wait_until_idle(); }

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
  r.state = tracking_->track(frame_, r.timings, counts);
  const bool was_reset = r.counts.reset;
  r.counts = counts;
  r.counts.reset = r.counts.reset || was_reset;

  if (r.state == TrackingState::kOk) {
    const Frame& f = tracking_->last_frame();
    r.pose_valid = true;
    r.T_w_c = f.T_w_c();
    if (f.reference_keyframe) {
      trajectory_.push_back({t_ns, f.reference_keyframe->id, tracking_->last_relative_pose()});
    }
  }
  if (counts.reset) reset_now();
  if (!config_.threaded_mapping) {
    const auto t_map = Clock::now();
    mapper_->process_pending();
    r.timings.inline_mapping_ms = ms_since(t_map);
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

Trajectory System::trajectory() {
  Trajectory out;
  out.reserve(trajectory_.size());
  std::lock_guard<std::mutex> lock(map_.mutex());
  for (const TrajectoryEntry& e : trajectory_) {
    SE3d T_c_w;
    if (!map_.resolve_pose(e.reference_kf_id, e.T_c_r, T_c_w)) continue;
    out.push_back({e.t_ns, T_c_w.inverse()});
  }
  return out;
}

}  // namespace agvslam::slam
