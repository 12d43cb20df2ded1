#include "run_frame_log.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace agvslam::apps::run_tool {

ProgressBar::ProgressBar(std::size_t total) : total_(total), tty_(isatty(STDERR_FILENO) != 0), start_(Clock::now()) {}

void ProgressBar::update(std::size_t done, const char* state, std::size_t keyframes, bool force) {
  const auto now = Clock::now();
  const double since_draw = std::chrono::duration<double>(now - last_draw_).count();
  if (!force && since_draw < (tty_ ? 0.2 : 10.0)) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fps = elapsed > 0 ? static_cast<double>(done) / elapsed : 0;
  constexpr int kWidth = 30;
  const int filled = total_ > 0 ? static_cast<int>(kWidth * done / total_) : kWidth;
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::fprintf(stderr, "%s[%s] %zu/%zu %.1f fps  state %-12s keyframes %zu%s", tty_ ? "\r" : "", bar.c_str(), done,
               total_, fps, state, keyframes, tty_ ? "   " : "\n");
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (tty_) std::fprintf(stderr, "\n");
}

void FrameLog::start() {
  progress_.emplace(total_frames_);
  t_start_ = t_prev_frame_ = t_last_frame_ = Clock::now();
}

void FrameLog::add(const daemon::TrackedFrame& f) {
  const slam::TrackResult& r = f.result;
  count(f.captured, r);
  add_timings(f, r);
  const int moving_inliers = score_moving_inliers(f.captured.ground_truth_mask, r);
  add_record(f, moving_inliers);
  progress_->update(frames, slam::to_string(r.state), r.keyframes);
  t_last_frame_ = Clock::now();
}

double FrameLog::finish() {
  progress_->update(frames, "done", keyframes, true);
  progress_->finish();
  return std::chrono::duration<double>(t_last_frame_ - t_start_).count();
}

void FrameLog::count(const daemon::CapturedFrame& c, const slam::TrackResult& r) {
  const long step = static_cast<long>(frames);
  ++frames;
  const bool ok = r.state == slam::TrackingState::kOk;
  if (ok && first_tracked < 0) first_tracked = step;
  if (c.blank && c.lap == 0) blank_end_step_ = step;
  if (blank_end_step_ >= 0 && blank_recovered_after < 0 && !c.blank && ok)
    blank_recovered_after = step - blank_end_step_ - 1;
  if (static_cast<std::size_t>(c.source_index) == last_) {
    laps_keyframes.push_back(r.keyframes);
    laps_points.push_back(r.map_points);
  }
  if (ok) ++tracked;
  if (r.state == slam::TrackingState::kLost) ++lost;
  if (r.counts.reset) ++resets;
  if (r.counts.recovered) ++recovered;
  if (r.counts.new_map) ++new_maps;
  if (r.counts.keyframe_waited) ++keyframe_waits;
  last_state = slam::to_string(r.state);
  keyframes = r.keyframes;
  max_queue = std::max(max_queue, r.mapping_queue);
}

void FrameLog::add_timings(const daemon::TrackedFrame& f, const slam::TrackResult& r) {
  const auto now = Clock::now();
  const double interval_ms = std::chrono::duration<double, std::milli>(now - t_prev_frame_).count();
  t_prev_frame_ = now;
  series["extract"].add(r.timings.extract_ms);
  series["stereo"].add(r.timings.stereo_ms);
  series["map_wait"].add(r.timings.map_wait_ms);
  series["frame"].add(r.timings.frame_ms);
  series["local_map"].add(r.timings.local_map_ms);
  series["retire"].add(r.timings.retire_ms);
  series["retire_cpu"].add(r.timings.retire_cpu_ms);
  series["keyframe"].add(r.timings.keyframe_ms);
  if (r.counts.keyframe_waited) series["keyframe_wait"].add(r.timings.keyframe_wait_ms);
  if (inline_mapping_) series["inline_mapping"].add(r.timings.inline_mapping_ms);
  series["tracking"].add(r.timings.total_ms);
  series["tracking_cpu"].add(r.timings.total_cpu_ms);
  series["read"].add(f.captured.read_ms);
  if (f.times.detector_ms >= 0) {
    series["detector"].add(f.times.detector_ms);
    series["frontend_sum"].add(f.times.detector_ms + r.timings.total_ms);
    series["detector_cpu"].add(f.times.detector_cpu_ms);
    series["frontend_cpu"].add(f.times.detector_cpu_ms + r.timings.total_cpu_ms);
  }
  if (frames > 1) series["frame_interval"].add(interval_ms);
}

int FrameLog::score_moving_inliers(const cv::Mat& gt_mask, const slam::TrackResult& r) {
  if (gt_mask.empty() || !r.pose_valid || r.inlier_keypoints_px.empty()) return -1;
  int moving = 0;
  for (const cv::Point2f& pt : r.inlier_keypoints_px) {
    const int x = std::clamp(static_cast<int>(std::lround(pt.x)), 0, gt_mask.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(pt.y)), 0, gt_mask.rows - 1);
    if (gt_mask.at<uint8_t>(y, x) != 0) ++moving;
  }
  moving_inliers_total += static_cast<std::size_t>(moving);
  inliers_total += r.inlier_keypoints_px.size();
  moving_inlier_fraction.push_back(static_cast<double>(moving) / static_cast<double>(r.inlier_keypoints_px.size()));
  return moving;
}

void FrameLog::add_record(const daemon::TrackedFrame& f, int moving_inliers) {
  const slam::TrackResult& r = f.result;
  per_frame.push_back(
      {{"frame", f.captured.source_index},
       {"lap", f.captured.lap},
       {"blank", f.captured.blank},
       {"loops", r.loops_closed},
       {"t_ns", f.captured.frame.t_ns},
       {"state", slam::to_string(r.state)},
       {"map_id", r.map_id},
       {"new_map", r.counts.new_map},
       {"keyframe_wait_ms", r.counts.keyframe_waited ? r.timings.keyframe_wait_ms : 0.0},
       {"features", r.counts.features},
       {"stereo_features", r.counts.stereo_features},
       {"method", r.counts.method},
       {"frame_matches", r.counts.frame_matches},
       {"inliers", r.counts.inliers},
       {"keyframe", r.counts.new_keyframe},
       {"keyframes", r.keyframes},
       {"map_points", r.map_points},
       {"mapping_queue", r.mapping_queue},
       {"mask_pixels", f.mask.empty() ? 0 : cv::countNonZero(f.mask)},
       {"moving_inliers", moving_inliers},
       {"p_w_c", r.pose_valid ? nlohmann::json::array(
                                    {r.T_w_c.translation().x(), r.T_w_c.translation().y(), r.T_w_c.translation().z()})
                              : nlohmann::json()},
       {"tracking_ms", r.timings.total_ms},
       {"detector_ms", f.times.detector_ms}});
}

}  // namespace agvslam::apps::run_tool
