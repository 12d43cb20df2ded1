#include "agvslam/daemon/pipeline.h"
#include "agvslam/core/clock.h"

#include <spdlog/spdlog.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "agvslam/core/error.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/io/trajectory_io.h"

namespace agvslam::daemon {
namespace {

using drivers::v4l2::monotonic_now_ns;
using Clock = std::chrono::steady_clock;

constexpr std::size_t kFpsRing = 512;

}  // namespace

// ---------------------------------------------------------------------------------------------------------------

std::string PipelineStats::one_line() const {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s, %.1f fps, %llu frames (%llu tracked, %llu lost), dropped %llu (queue %llu, source %llu), "
                "latency p50 %.1f ms p99 %.1f ms, keyframes %zu, map points %zu, camera %s, published %llu "
                "(dds pose %llu, status %llu, can %llu)",
                state.c_str(), fps, static_cast<unsigned long long>(processed),
                static_cast<unsigned long long>(tracked), static_cast<unsigned long long>(lost),
                static_cast<unsigned long long>(dropped_queue + dropped_source),
                static_cast<unsigned long long>(dropped_queue), static_cast<unsigned long long>(dropped_source),
                latency_p50_ms, latency_p99_ms, keyframes, map_points, source.connected ? "ok" : "lost, reopening",
                static_cast<unsigned long long>(published), static_cast<unsigned long long>(outputs.dds_pose.published),
                static_cast<unsigned long long>(outputs.dds_status.published),
                static_cast<unsigned long long>(outputs.can.cycles_sent));
  std::string line = buf;
  if (outputs.odometry_enabled) {
    const drivers::OdometryCheck& c = outputs.odometry_check;
    std::snprintf(buf, sizeof buf,
                  ", odometry %s (ratio %.3f, heading %+.1f deg, speed RMSE %.3f m/s over %.1f s; %llu samples, "
                  "%llu rejected)",
                  drivers::to_string(c.state), c.distance_ratio, c.heading_difference_deg, c.speed_rmse_mps, c.window_s,
                  static_cast<unsigned long long>(outputs.odometry_samples),
                  static_cast<unsigned long long>(outputs.can_odometry.crc_bad + outputs.can_odometry.counter_repeated +
                                                  outputs.can_odometry.too_short));
    line += buf;
  }
  return line;
}

// ---------------------------------------------------------------------------------------------------------------

struct Pipeline::DetectedFrame {
  CapturedFrame captured;
  cv::Mat mask;  // empty: no detector
  StageTimes times;
  int64_t detected_mono_ns = 0;
};

Pipeline::Pipeline(const DaemonConfig& config, const SourceSetup& setup, std::unique_ptr<FrameSource> source,
                   PipelineOptions options)
    : config_(config),
      setup_(setup),
      options_(std::move(options)),
      source_(std::move(source)),
      builder_(config.base_link.T_base_cam() * setup.calibration.T_cam0_rect, config.covariance),
      capture_queue_(static_cast<std::size_t>(config.pipeline.capture_queue),
                     source_->lossless() ? QueuePolicy::kLossless : QueuePolicy::kNewestWins),
      output_queue_(static_cast<std::size_t>(config.pipeline.output_queue), QueuePolicy::kNewestWins),
      recent_frames_mono_ns_(kFpsRing, INT64_MIN) {
  slam::SystemConfig system_config = config.system;
  system_config.frame_rate_hz = setup.slam_rate_hz;
  if (config.place) {
    const auto t0 = std::chrono::steady_clock::now();
    system_config.vocabulary = slam::load_vocabulary(*config.place);
    spdlog::info("agvslamd: vocabulary {} loaded in {:.1f} ms", config.place->vocabulary_file,
                 std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  system_ = std::make_unique<slam::System>(setup.calibration, system_config);
  if (!config.map.file.empty()) {
    if (std::filesystem::exists(config.map.file)) {
      // A file that cannot be loaded is an InputError naming it (agvslamd exits 2); it is never overwritten.
      const slam::MapLoadStats st = system_->load_map(config.map.file, config.map.mode);
      spdlog::info(
          "agvslamd: map {} loaded ({} keyframes, {} map points, {} bytes, {:.0f} ms), mode {}: the first "
          "frames relocalise in it and poses are in its frame",
          config.map.file, st.keyframes, st.map_points, st.bytes, st.read_ms + st.decode_ms + st.bow_ms,
          slam::to_string(config.map.mode));
    } else {
      spdlog::info("agvslamd: map {} does not exist yet: building a new map (saved at stop)", config.map.file);
    }
    if (config.map.mode == slam::MapMode::kMapping && config.map.save_on_stop) {
      // Learn now, not at the end of a shift, that the map cannot be written: the folder must exist (created if
      // it can be) and take a new file.
      const std::filesystem::path folder = std::filesystem::absolute(config.map.file).parent_path();
      std::error_code ec;
      std::filesystem::create_directories(folder, ec);
      const std::filesystem::path probe = folder / (".agvslamd-write-test-" + std::to_string(::getpid()));
      std::FILE* f = std::fopen(probe.c_str(), "wb");
      if (!f) {
        throw InputError(
            config.path, "map.file",
            "expected a file in a writable folder (" + folder.string() + ": " + std::strerror(errno) + ")");
      }
      std::fclose(f);
      std::filesystem::remove(probe, ec);
    }
    system_->set_mode(config.map.mode);
  }
  if (config.pipeline.dynamic == DynamicMode::kDetector) {
    detector_ = std::make_unique<dynamic::DynamicDetector>(setup.calibration, config.detector, config.stereo);
    detected_queue_ = std::make_unique<BoundedQueue<DetectedFrame>>(1, QueuePolicy::kLossless);
    if (config.semantic) {
      try {
        semantic_ = std::make_unique<semantic::SemanticMasker>(
            *config.semantic, std::make_unique<semantic::Segmenter>(config.semantic->model));
      } catch (const InputError& e) {
        spdlog::warn("semantic stage off, the geometric detector alone: {}", e.what());
      }
    }
  }
  outputs_ = std::make_unique<PoseOutputs>(config, config.base_link.T_base_cam() * setup.calibration.T_cam0_rect);
}

Pipeline::~Pipeline() {
  request_stop();
  wait();
}

void Pipeline::start() {
  const int64_t now = monotonic_now_ns();
  for (auto* b : {&beat_capture_, &beat_detector_, &beat_tracking_, &beat_outputs_}) b->store(now);
  outputs_thread_ = std::thread([this] { outputs_loop(); });
  tracking_thread_ = std::thread([this] { tracking_loop(); });
  if (detector_) detector_thread_ = std::thread([this] { detector_loop(); });
  capture_thread_ = std::thread([this] { capture_loop(); });
}

void Pipeline::request_stop() { stop_.store(true); }

std::optional<slam::MapSaveStats> Pipeline::save_map() {
  if (config_.map.file.empty() || config_.map.mode != slam::MapMode::kMapping || !config_.map.save_on_stop) {
    return std::nullopt;
  }
  if (system_->map().keyframe_count() == 0) {
    spdlog::warn("agvslamd: the map is empty (nothing was tracked): {} not written", config_.map.file);
    return std::nullopt;
  }
  return system_->save_map(config_.map.file);
}

void Pipeline::wait() {
  for (std::thread* t : {&capture_thread_, &detector_thread_, &tracking_thread_, &outputs_thread_}) {
    if (t->joinable()) t->join();
  }
  if (!system_) return;
  if (options_.settle_mapping) system_->wait_for_mapping();
  if (!final_written_ && !config_.trajectory.final_file.empty()) {
    final_written_ = true;
    try {
      system_->wait_for_mapping();
      const Trajectory trajectory = system_->trajectory();
      io::write_tum(config_.trajectory.final_file, trajectory);
      spdlog::info("trajectory: {} keyframe-refined poses written to {}", trajectory.size(),
                   config_.trajectory.final_file);
    } catch (const std::exception& e) {
      spdlog::error("trajectory: writing {} failed: {}", config_.trajectory.final_file, e.what());
    }
  }
  system_->shutdown();
}

std::string Pipeline::error() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return error_;
}

void Pipeline::fail(const std::string& where, const std::exception& e) {
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    if (error_.empty()) error_ = where + ": " + e.what();
  }
  spdlog::error("{}: {}", where, e.what());
  failed_.store(true);
  stop_.store(true);
  capture_queue_.close();
  if (detected_queue_) detected_queue_->close();
  output_queue_.close();
}

double Pipeline::fps_locked(int64_t now_mono_ns) const {
  return static_cast<double>(
      std::count_if(recent_frames_mono_ns_.begin(), recent_frames_mono_ns_.end(),
                    [&](int64_t t) { return t != INT64_MIN && now_mono_ns - t <= 1000000000LL; }));
}

void Pipeline::beat(std::atomic<int64_t>& slot) const { slot.store(monotonic_now_ns(), std::memory_order_relaxed); }

bool Pipeline::alive(std::chrono::milliseconds max_age) const {
  const int64_t now = monotonic_now_ns();
  const int64_t limit = static_cast<int64_t>(max_age.count()) * 1000000LL;
  for (const auto* b : {&beat_capture_, &beat_tracking_, &beat_outputs_}) {
    if (now - b->load(std::memory_order_relaxed) > limit) return false;
  }
  if (detector_ && now - beat_detector_.load(std::memory_order_relaxed) > limit) return false;
  return !failed_.load();
}

PipelineStats Pipeline::stats() const {
  PipelineStats s;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    s = stats_;
    s.latency_p50_ms = latency_ms_.quantile(0.5);
    s.latency_p99_ms = latency_ms_.quantile(0.99);
    s.latency_max_ms = latency_ms_.max();
    s.detector_p50_ms = detector_ms_.quantile(0.5);
    s.tracking_p50_ms = tracking_ms_.quantile(0.5);
    s.tracking_p99_ms = tracking_ms_.quantile(0.99);
    s.fps = fps_locked(monotonic_now_ns());
  }
  s.dropped_queue = capture_queue_.dropped();
  s.dropped_source = s.source.dropped;
  s.dropped_outputs = output_queue_.dropped();
  s.outputs = outputs_->stats();
  return s;
}

// ---------------------------------------------------------------------------------------------------------------

void Pipeline::capture_loop() {
  const int poll_ms = config_.pipeline.poll_ms;
  try {
    const OutputsConfig& oc = config_.outputs;
    if (oc.dds_enabled && oc.dds_wait_for_subscribers > 0) {
      const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                               std::chrono::duration<double>(oc.dds_wait_timeout_s));
      bool matched = false;
      while (!stop_.load() && Clock::now() < deadline && !matched) {
        beat(beat_capture_);
        matched = outputs_->wait_for_subscribers(oc.dds_wait_for_subscribers, std::chrono::milliseconds(poll_ms));
      }
      spdlog::info("dds: {} subscriber(s) on every topic{}", oc.dds_wait_for_subscribers,
                   matched ? " matched; capturing" : " not matched in time; capturing anyway");
    }
    bool was_connected = true;
    while (!stop_.load()) {
      beat(beat_capture_);
      CapturedFrame f;
      const FrameSource::Grab g = source_->grab(f, poll_ms);
      SourceStats st = source_->stats();  // the source is used by this thread only
      if (st.connected != was_connected) {
        if (st.connected) {
          spdlog::info("camera: streaming again ({})", st.line);
        } else {
          spdlog::warn("camera: lost, reopening; the outputs report state lost meanwhile ({})", st.line);
        }
        was_connected = st.connected;
      }
      {
        std::lock_guard<std::mutex> lock(stats_mutex_);
        stats_.source = std::move(st);
        if (g == FrameSource::Grab::kFrame) ++stats_.captured;
      }
      if (g == FrameSource::Grab::kEnd) {
        spdlog::info("source: end of the dataset");
        source_ended_.store(true);
        break;
      }
      if (g == FrameSource::Grab::kFrame) {
        f.queued_mono_ns = monotonic_now_ns();
        capture_queue_.push(std::move(f));
      }
    }
  } catch (const std::exception& e) {
    fail("capture", e);
  }
  capture_queue_.close();
}

void Pipeline::detector_loop() {
  const auto poll = std::chrono::milliseconds(config_.pipeline.poll_ms);
  try {
    dynamic::DetectorResult result;
    int previous_dynamic_points = -1;
    uint64_t keyframes_seen = 0;
    for (;;) {
      beat(beat_detector_);
      std::optional<CapturedFrame> f = capture_queue_.pop(poll);
      if (!f) {
        if (capture_queue_.drained()) break;
        continue;
      }
      DetectedFrame d;
      const auto t0 = Clock::now();
      d.times.capture_queue_ms = static_cast<double>(monotonic_now_ns() - f->queued_mono_ns) * 1e-6;
      const double cpu0 = thread_cpu_ms();
      detector_->detect(f->frame, result);
      if (semantic_) {
        semantic::FrameCues cues;
        cues.previous_dynamic_points = previous_dynamic_points;
        cues.relocalised = relocalised_.exchange(false);
        const uint64_t keyframes = keyframes_in_map_.load();
        cues.new_keyframe = keyframes > keyframes_seen;
        keyframes_seen = keyframes;
        semantic_->process(f->frame.index, f->frame.left, &result, cues);
        semantic_->apply_fusion(result.mask);
      }
      previous_dynamic_points = result.dynamic_point_count();
      d.times.detector_cpu_ms = thread_cpu_ms() - cpu0;
      d.times.detector_ms = ms_since(t0);
      d.detected_mono_ns = monotonic_now_ns();
      d.mask = result.mask.image.clone();  // travels with the frame while the detector moves on
      d.captured = std::move(*f);
      if (detected_queue_->push(std::move(d)) == PushResult::kClosed) break;  // a later stage failed
    }
  } catch (const std::exception& e) {
    fail("detector", e);
  }
  detected_queue_->close();
}

void Pipeline::tracking_loop() {
  const auto poll = std::chrono::milliseconds(config_.pipeline.poll_ms);
  try {
    uint64_t processed = 0;
    slam::TrackingState last_state = slam::TrackingState::kInitialising;
    for (;;) {
      beat(beat_tracking_);
      if (processing_hook_) processing_hook_();
      std::optional<DetectedFrame> d;
      if (detected_queue_) {
        d = detected_queue_->pop(poll);
        if (!d && detected_queue_->drained()) break;
      } else {
        std::optional<CapturedFrame> f = capture_queue_.pop(poll);
        if (f) {
          d.emplace();
          d->times.capture_queue_ms = static_cast<double>(monotonic_now_ns() - f->queued_mono_ns) * 1e-6;
          d->captured = std::move(*f);
        } else if (capture_queue_.drained()) {
          break;
        }
      }
      if (!d) continue;

      const CapturedFrame& c = d->captured;
      // The SLAM keeps the dataset's own stamps (the final trajectory compares with its ground truth); a camera
      // frame's stamp is its capture time.
      const int64_t slam_t_ns = c.source_index >= 0 ? c.frame.t_ns : c.capture_t_ns;
      OutputItem item;
      item.times = d->times;
      if (d->detected_mono_ns > 0)
        item.times.detected_queue_ms = static_cast<double>(monotonic_now_ns() - d->detected_mono_ns) * 1e-6;
      const cv::Mat& mask = options_.ground_truth_masks ? c.ground_truth_mask : d->mask;
      const auto t0 = Clock::now();
      const double cpu0 = thread_cpu_ms();
      const slam::TrackResult r = system_->track_stereo(slam_t_ns, c.frame.left, c.frame.right, mask);
      item.times.tracking_cpu_ms = thread_cpu_ms() - cpu0;
      if (semantic_) {
        keyframes_in_map_.store(r.keyframes);
        if (r.state == slam::TrackingState::kOk && last_state == slam::TrackingState::kLost) relocalised_.store(true);
        last_state = r.state;
      }
      const double tracking_ms = ms_since(t0);
      item.times.tracking_ms = tracking_ms;
      ++processed;

      builder_.build(r, c.capture_t_ns, item.sample);
      item.T_w_c = r.T_w_c;
      item.source_index = c.source_index;
      item.source_t_ns = c.source_t_ns;
      drivers::PoseSample& s = item.sample;
      s.frame_index = c.frame.index;
      s.frames_processed = processed;
      const double area = static_cast<double>(c.frame.left.total());
      s.dynamic_pixel_fraction = mask.empty() || area <= 0 ? 0.0F : static_cast<float>(cv::countNonZero(mask) / area);
      {
        std::lock_guard<std::mutex> lock(stats_mutex_);
        const int64_t now = monotonic_now_ns();
        recent_frames_mono_ns_[recent_next_] = now;
        recent_next_ = (recent_next_ + 1) % recent_frames_mono_ns_.size();
        s.fps = static_cast<float>(fps_locked(now));
        s.frames_dropped = capture_queue_.dropped() + stats_.source.dropped;
        stats_.processed = processed;
        if (r.state == slam::TrackingState::kOk) ++stats_.tracked;
        if (r.state == slam::TrackingState::kLost) ++stats_.lost;
        stats_.state = slam::to_string(r.state);
        stats_.keyframes = r.keyframes;
        stats_.map_points = r.map_points;
        tracking_ms_.add(tracking_ms);
        if (d->times.detector_ms >= 0) detector_ms_.add(d->times.detector_ms);
      }
      if (options_.on_tracked) options_.on_tracked(TrackedFrame{c, mask, item.times, r});
      item.times.tracked_mono_ns = monotonic_now_ns();
      output_queue_.push(std::move(item));
    }
  } catch (const std::exception& e) {
    fail("tracking", e);
  }
  tracking_done_.store(true);
  output_queue_.close();
}

void Pipeline::outputs_loop() {
  const auto heartbeat = std::chrono::milliseconds(config_.pipeline.heartbeat_ms);
  const auto poll = std::min(std::chrono::milliseconds(config_.pipeline.poll_ms), heartbeat);
  drivers::PoseSample last;  // the last sample published (heartbeats repeat its pose and counters)
  bool ever_tracked = false;
  auto last_publish = Clock::now();
  try {
    for (;;) {
      beat(beat_outputs_);
      std::optional<OutputItem> item = output_queue_.pop(poll);
      if (item) {
        item->times.output_queue_ms = static_cast<double>(monotonic_now_ns() - item->times.tracked_mono_ns) * 1e-6;
        outputs_->publish(*item);
        last = item->sample;
        if (last.tracking_state == drivers::TrackingState::kTracking) ever_tracked = true;
        last_publish = Clock::now();
        frames_published_.fetch_add(1);
        std::lock_guard<std::mutex> lock(stats_mutex_);
        latency_ms_.add(static_cast<double>(item->sample.latency_ns) * 1e-6);
        ++stats_.published;
        continue;
      }
      if (output_queue_.drained()) break;
      if (Clock::now() - last_publish >= heartbeat) {
        OutputItem hb;
        hb.heartbeat = true;
        hb.sample = last;
        PoseSampleBuilder::build_heartbeat(drivers::dds::realtime_now_ns(), ever_tracked, hb.sample);
        {
          std::lock_guard<std::mutex> lock(stats_mutex_);
          hb.sample.fps = static_cast<float>(fps_locked(monotonic_now_ns()));
          hb.sample.frames_dropped = capture_queue_.dropped() + stats_.source.dropped;
          if (!stats_.source.connected) stats_.state = "lost (camera)";
          ++stats_.published;
          ++stats_.heartbeats;
        }
        outputs_->publish(hb);
        last_publish = Clock::now();
      }
    }
    outputs_->flush(std::chrono::seconds(2));
  } catch (const std::exception& e) {
    fail("outputs", e);
  }
  if (source_ended_.load() && !failed_.load()) finished_.store(true);
}

}  // namespace agvslam::daemon
