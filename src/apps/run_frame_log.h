#pragma once
// agvslam-run's per-frame figures: counts, per-stage times, the pose inliers on ground-truth moving objects and one
// JSON record per frame, gathered in the pipeline's tracking thread, with a progress bar on stderr.

#include <chrono>
#include <cstddef>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/stats.h"
#include "agvslam/daemon/pipeline.h"
#include "agvslam/slam/system.h"

namespace agvslam::apps::run_tool {

using Clock = std::chrono::steady_clock;

// Frames done, frame rate and tracking state on stderr: redrawn in place on a terminal (5 Hz), a line every 10 s
// otherwise (logs).
class ProgressBar {
 public:
  explicit ProgressBar(std::size_t total);
  void update(std::size_t done, const char* state, std::size_t keyframes, bool force = false);
  void finish();

 private:
  std::size_t total_;
  bool tty_;
  Clock::time_point start_, last_draw_{};
};

// The per-frame figures of the run, gathered in the pipeline's tracking thread (add()) and read once it ended.
class FrameLog {
 public:
  // Stages in the order of the timing table.
  static constexpr const char* kStageOrder[] = {
      "extract",    "stereo",       "map_wait",      "frame",          "local_map",      "retire",
      "retire_cpu", "keyframe",     "keyframe_wait", "inline_mapping", "tracking",       "tracking_cpu",
      "detector",   "detector_cpu", "frontend_sum",  "frontend_cpu",   "frame_interval", "read"};

  FrameLog(bool inline_mapping, std::size_t last, std::size_t total_frames)
      : inline_mapping_(inline_mapping), last_(last), total_frames_(total_frames) {}

  // Just before the first frame: the clocks of the progress bar, the frame interval and the wall time start.
  void start();
  void add(const daemon::TrackedFrame& f);
  // The progress bar's last line; the time from the start to the last frame (s).
  double finish();

  std::size_t frames = 0, tracked = 0, lost = 0, resets = 0, recovered = 0, max_queue = 0, keyframes = 0;
  std::size_t new_maps = 0;         // maps started after a long loss (tracking.new_map_after_lost_s)
  std::size_t keyframe_waits = 0;   // frames that waited for room in local mapping's queue
  std::string last_state;           // of the last frame
  long first_tracked = -1;          // frames processed before the first pose
  long blank_recovered_after = -1;  // frames after the blank until a pose
  std::vector<std::size_t> laps_keyframes, laps_points;
  // Inliers of the pose on ground-truth moving objects (what the dynamic masks are there to prevent).
  std::vector<double> moving_inlier_fraction;
  std::size_t moving_inliers_total = 0, inliers_total = 0;
  std::map<std::string, Series> series;  // per-stage times (ms)
  nlohmann::json per_frame = nlohmann::json::array();

 private:
  void count(const daemon::CapturedFrame& c, const slam::TrackResult& r);
  void add_timings(const daemon::TrackedFrame& f, const slam::TrackResult& r);
  // The pose's inliers on ground-truth moving pixels; -1 when not scored (no mask or no pose).
  int score_moving_inliers(const cv::Mat& gt_mask, const slam::TrackResult& r);
  void add_record(const daemon::TrackedFrame& f, int moving_inliers);

  const bool inline_mapping_;
  const std::size_t last_, total_frames_;
  std::optional<ProgressBar> progress_;
  long blank_end_step_ = -1;  // step of the last blanked frame (first lap)
  Clock::time_point t_start_, t_prev_frame_, t_last_frame_;
};

}  // namespace agvslam::apps::run_tool
