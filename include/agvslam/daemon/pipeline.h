#pragma once
// agvslamd's threads and the queues between them:
//
//   capture   FrameSource::grab -> CapturedFrame
//      |      capture queue (pipeline.capture_queue frames; newest wins, drops counted; lossless for a dataset at
//      v      rate 0 or played losslessly)
//   detector  DynamicDetector on the frame (pipeline.dynamic detector; skipped with off), one frame ahead of
//      |      tracking
//      |      detected queue (1 frame, waits: the capture queue is where frames are dropped)
//      v
//   tracking  slam::System::track_stereo -> PoseSampleBuilder -> OutputItem; the processing loop whose
//      |      liveness the systemd watchdog watches
//      |      output queue (pipeline.output_queue samples, newest wins)
//      v
//   outputs   PoseOutputs::publish (DDS pose/odom/status, CAN, trajectory, JSON log); heartbeat status samples
//             (state lost) every heartbeat_ms while nothing arrives (camera lost, tracking stalled)
//
// Every loop waits with a time-out (pipeline.poll_ms) and stamps a heartbeat, so alive() tells whether all of
// them still turn. stop() closes the capture queue: what was captured is processed and published (drain), then
// the threads end; the source is closed, files flushed.
//
// agvslam-run drives the same pipeline over a dataset (its outputs disabled): PipelineOptions adds tracking with
// the dataset's ground-truth masks, a hook that sees every tracked frame, and letting mapping finish at the end.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "agvslam/core/bounded_queue.h"
#include "agvslam/core/stats.h"
#include "agvslam/daemon/daemon_config.h"
#include "agvslam/daemon/frame_source.h"
#include "agvslam/daemon/pose_builder.h"
#include "agvslam/daemon/pose_outputs.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/semantic/semantic_masker.h"

namespace agvslam::daemon {

struct PipelineStats {
  uint64_t captured = 0;         // frames the source delivered
  uint64_t processed = 0;        // frames tracked (any result)
  uint64_t tracked = 0;          // of which state ok
  uint64_t lost = 0;             // of which lost
  uint64_t dropped_queue = 0;    // dropped in the capture queue (processing too slow)
  uint64_t dropped_source = 0;   // lost by the source itself (V4L2 sequence gaps, unpaired)
  uint64_t dropped_outputs = 0;  // samples dropped in the output queue
  uint64_t published = 0;        // samples handed to the outputs (heartbeats included)
  uint64_t heartbeats = 0;
  double fps = 0;                  // processed frames per second over the last second
  std::string state = "starting";  // tracking state of the last frame (or "lost (camera)", ...)
  std::size_t keyframes = 0, map_points = 0;
  // Milliseconds over the last 4096 frames: median / p99 / max.
  double latency_p50_ms = 0, latency_p99_ms = 0, latency_max_ms = 0;  // capture -> handed to the outputs
  double detector_p50_ms = 0, tracking_p50_ms = 0, tracking_p99_ms = 0;
  SourceStats source;
  OutputStats outputs;
  std::string one_line() const;  // systemd STATUS= and the periodic log line
};

// One frame as tracking left it, for a caller that follows every frame (agvslam-run's statistics).
struct TrackedFrame {
  const CapturedFrame& captured;
  const cv::Mat& mask;  // the dynamic mask tracking used (detector or ground truth; empty: none)
  const StageTimes& times;
  const slam::TrackResult& result;
};

// What a caller other than agvslamd changes; the defaults are agvslamd's behaviour.
struct PipelineOptions {
  // Track with the frames' ground-truth masks (CapturedFrame::ground_truth_mask) instead of a detector's
  // (pipeline.dynamic off).
  bool ground_truth_masks = false;
  // Called in the tracking thread after every frame, before its sample goes to the outputs.
  std::function<void(const TrackedFrame&)> on_tracked;
  // wait(): local mapping and loop closing finish every queued keyframe before the SLAM stops, so the final map
  // and trajectory include them.
  bool settle_mapping = false;
};

class Pipeline {
 public:
  // Builds the SLAM system, detector and outputs (no thread yet). Throws on an output that cannot be opened.
  // `config` must outlive the pipeline.
  Pipeline(const DaemonConfig& config, const SourceSetup& setup, std::unique_ptr<FrameSource> source,
           PipelineOptions options = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  void start();
  // Asks every thread to finish after draining what was captured; returns at once. wait() joins them.
  void request_stop();
  void wait();
  // After wait(), in mapping mode with map.file and map.save_on_stop: writes the map atomically (temporary file,
  // fsync, rename). nullopt when there is nothing to save (no file, localisation mode, an empty map). Throws
  // InputError naming the file when it cannot be written (the previous file is then intact).
  std::optional<slam::MapSaveStats> save_map();
  // True once the source reported its end (dataset played once) and everything was published.
  bool finished() const { return finished_.load(); }
  // True when a thread failed (its exception is in error()).
  bool failed() const { return failed_.load(); }
  std::string error() const;

  // Every loop turned within `max_age` (the systemd watchdog's test).
  bool alive(std::chrono::milliseconds max_age) const;
  // Samples of processed frames (not heartbeats) handed to the outputs so far (READY=1 waits for the first).
  uint64_t frames_published() const { return frames_published_.load(); }
  PipelineStats stats() const;
  // The SLAM (agvslam-run loads a map into it before start() and reads its results after wait()).
  slam::System& system() { return *system_; }
  // Called from the tracking loop after every frame and every poll time-out (the systemd watchdog hook).
  void set_processing_hook(std::function<void()> hook) { processing_hook_ = std::move(hook); }

 private:
  struct DetectedFrame;
  void capture_loop();
  void detector_loop();
  void tracking_loop();
  void outputs_loop();
  void fail(const std::string& where, const std::exception& e);
  void beat(std::atomic<int64_t>& slot) const;
  double fps_locked(int64_t now_mono_ns) const;  // frames processed in the last second (stats_mutex_ held)

  const DaemonConfig& config_;
  SourceSetup setup_;
  PipelineOptions options_;
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<slam::System> system_;
  std::unique_ptr<dynamic::DynamicDetector> detector_;  // used by the detector thread only
  // The semantic stage beside the detector (stages.semantic), fused into its mask; null: geometry alone.
  std::unique_ptr<semantic::SemanticMasker> semantic_;
  // What tracking tells the semantic stage's keyframe rules: keyframes in the map, and a relocalisation not yet
  // passed on.
  std::atomic<uint64_t> keyframes_in_map_{0};
  std::atomic<bool> relocalised_{false};
  std::unique_ptr<PoseOutputs> outputs_;
  PoseSampleBuilder builder_;

  BoundedQueue<CapturedFrame> capture_queue_;
  std::unique_ptr<BoundedQueue<DetectedFrame>> detected_queue_;
  BoundedQueue<OutputItem> output_queue_;

  std::thread capture_thread_, detector_thread_, tracking_thread_, outputs_thread_;
  std::atomic<bool> stop_{false}, finished_{false}, failed_{false};
  std::atomic<bool> tracking_done_{false}, source_ended_{false};
  bool final_written_ = false;
  std::atomic<int64_t> beat_capture_{0}, beat_detector_{0}, beat_tracking_{0}, beat_outputs_{0};
  std::atomic<uint64_t> frames_published_{0};
  std::function<void()> processing_hook_;

  mutable std::mutex stats_mutex_;
  PipelineStats stats_;
  RollingSeries latency_ms_, detector_ms_, tracking_ms_;  // the last 4096 frames
  std::vector<int64_t> recent_frames_mono_ns_;            // ring of processing times for fps
  std::size_t recent_next_ = 0;
  std::string error_;
};

}  // namespace agvslam::daemon
