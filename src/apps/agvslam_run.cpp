// agvslam-run: the stereo SLAM (paper 004: dynamic regions removed, then ORB-SLAM2-style tracking and mapping)
// over a dataset folder.
//
//   agvslam-run --dataset DIR --out TRAJ [--calib FILE] [--format tum|kitti] [--dynamic detector|gt|off]
//               [--json STATS] [--frames A:B] [--params-slam params/slam.yaml] [--params-features ...]
//               [--params-dynamic ...] [--params-stereo ...] [--mapping thread|inline] [--speed X]
//               [--opencv-threads N] [--params-place params/place.yaml] [--loop on|off]
//               [--save-map FILE] [--load-map FILE --mode localise|map] [--blank A:B] [--repeat N]
//               [--map-dataset DIR]
//
// Reads KITTI-layout folders (also what agvslam-sim writes) and EuRoC ASL folders through agvslam::io. The frames
// are read, and with --dynamic detector their dynamic masks computed, in a second thread one frame ahead of
// tracking (bounded queue of two), so detection of frame k+1 overlaps tracking of frame k. --dynamic gt takes the
// dataset's ground-truth masks (simulator mask_0/), --dynamic off is the plain ORB-SLAM2-like baseline.
//
// --mapping thread runs local mapping in its own thread, as on the vehicle; --mapping inline maps each keyframe
// before the next frame (deterministic: the same input gives the same trajectory; the tracking times then include
// that mapping work, shown separately as inline_mapping: take speed figures with --mapping thread). --speed 1 feeds frames at the
// dataset's rate (the real-time case), 0 as fast as tracking goes.
//
// Writes TRAJ with the pose of every tracked frame (each relative to its reference keyframe, composed with the
// keyframe's final pose, as ORB-SLAM2 saves trajectories); with --format kitti and frames missing, TRAJ.times
// gives the stamps of the written poses (agvslam-eval --times). stdout: first line
//   FRAMES <n> TRACKED <m> KEYFRAMES <k> LOST <l>
// then, with ground truth, `ATE_RMSE_M <x>` (SE(3)-aligned, by time stamp) and the drift, then per-stage timing
// (median / p95 / max ms; wall clock, and *_cpu: the thread's own CPU time, which other load on the machine does
// not inflate). --json adds per-frame records (state, counts, times, mapping queue length).
// A progress bar with the frame rate goes to stderr. Exit status: 0 on success, 2 on bad input (the message names
// the option, file or field), 1 on any other failure.
//
// Place recognition and maps (issue 5): --params-place names the vocabulary (default: the source tree's
// params/place.yaml); --loop off disables loop closing (relocalisation stays). --load-map FILE starts in a saved map
// (--mode localise: track without changing it; map: extend it); the first frames relocalise in it. --save-map FILE
// writes the final map (atomically). --blank A:B replaces frames A..B by black images (a covered camera: forced
// loss). --repeat N plays the frame range N times in a row with continuing time stamps (laps of a loop sequence
// that ends where it starts; the ground truth is repeated alike). stdout then also has
//   LOOPS <n> ...                          loops closed (keyframe -> old keyframe, frame, correction)
//   RELOCALISATION first_tracked <k> [blank_recovered_after <m>]   frames until the first pose / after the blank
// --map-dataset DIR (simulator folders only): the folder the loaded map was made from; the ground truth of this run
// is expressed in that run's world frame (its first left camera) through the simulator's warehouse frame,
// T_w1_c = T_map_cam1(0)^-1 * T_map_cam2(0) * T_w2_c, and `MAP_FRAME_ATE_M <x>` is the RMSE of the estimated
// positions against it without any alignment (the estimate is in the saved map's frame).

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/eval/association.h"
#include "agvslam/eval/metrics.h"
#include "agvslam/features/features_config.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/place/place_config.h"
#include "agvslam/sim/simulator.h"
#include "agvslam/slam/system.h"
#include "agvslam/stereo/stereo_config.h"
#include "tool_main.h"

namespace {

using agvslam::InputError;
namespace slam = agvslam::slam;
namespace dyn = agvslam::dynamic;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

enum class DynamicMode { kDetector, kGroundTruth, kOff };

#ifndef AGVSLAM_PARAMS_DIR
#define AGVSLAM_PARAMS_DIR "params"
#endif

struct Options {
  std::string dataset, calib, out, format = "tum", dynamic = "detector", json, frames, mapping = "thread";
  std::string params_slam, params_features, params_dynamic, params_stereo;
  std::string params_place = AGVSLAM_PARAMS_DIR "/place.yaml";
  std::string loop = "on", save_map, load_map, mode, blank, map_dataset;
  int repeat = 1;
  double speed = 0;
  int opencv_threads = 1;
};

// "A:B" (inclusive) for --blank.
std::pair<std::size_t, std::size_t> parse_blank(const std::string& text) {
  const auto colon = text.find(':');
  std::size_t a = 0, b = 0, used_a = 0, used_b = 0;
  bool ok = colon != std::string::npos && colon > 0 && colon + 1 < text.size();
  if (ok) {
    try {
      a = static_cast<std::size_t>(std::stoull(text.substr(0, colon), &used_a));
      b = static_cast<std::size_t>(std::stoull(text.substr(colon + 1), &used_b));
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok || used_a != colon || used_b != text.size() - colon - 1 || text[0] == '-' || b < a) {
    throw InputError("--blank", text, "expected A:B with 0 <= A <= B (inclusive frame range to black out)");
  }
  return {a, b};
}

// T_w1_w2: the world frame of a simulator run (its first left camera) in the world frame of another run through
// the same warehouse (scenario.json of both; default simulator settings).
agvslam::SE3d simulator_world_offset(const std::string& map_dir, const std::string& run_dir) {
  auto first_camera = [](const std::string& dir) {
    const std::string path = dir + "/scenario.json";
    std::ifstream f(path);
    if (!f) throw InputError("--map-dataset", path, "expected a simulator folder with scenario.json");
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(f);
    } catch (const std::exception& e) {
      throw InputError(path, "", std::string("expected JSON (") + e.what() + ")");
    }
    agvslam::sim::ScenarioOptions so;
    try {
      so.name = j.at("scenario").get<std::string>();
      so.frames = j.at("frames").get<int>();
      so.seed = j.at("seed").get<uint64_t>();
      so.layout_seed = j.at("layout_seed").get<uint64_t>();
      so.start_offset_m = j.at("start_offset_m").get<double>();
    } catch (const std::exception& e) {
      throw InputError(path, "scenario, frames, seed, layout_seed, start_offset_m", std::string("expected them (") + e.what() + ")");
    }
    const agvslam::sim::Simulator sim(agvslam::sim::SimConfig{}, so);
    return std::make_pair(agvslam::SE3d(sim.T_map_cam(0)), so.effective_layout_seed());
  };
  const auto [T_map_c1, layout1] = first_camera(map_dir);
  const auto [T_map_c2, layout2] = first_camera(run_dir);
  if (layout1 != layout2) {
    throw InputError("--map-dataset", map_dir, "expected a run through the same warehouse (layout seed " +
                                                   std::to_string(layout2) + ", that folder has " + std::to_string(layout1) + ")");
  }
  return T_map_c1.inverse() * T_map_c2;
}

struct Series {
  std::vector<double> v;
  void add(double x) { v.push_back(x); }
  double quantile(double q) const {
    if (v.empty()) return 0;
    std::vector<double> s = v;
    const std::size_t k = std::min(s.size() - 1, static_cast<std::size_t>(std::floor(q * static_cast<double>(s.size() - 1) + 0.5)));
    std::nth_element(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(k), s.end());
    return s[k];
  }
  double max() const { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }
  nlohmann::json json() const {
    return {{"median_ms", quantile(0.5)}, {"p95_ms", quantile(0.95)}, {"max_ms", max()}, {"count", v.size()}};
  }
};

// One input frame with its mask (produced by the reader / detector thread).
struct Job {
  std::size_t index = 0;
  agvslam::StereoFrame frame;
  cv::Mat mask;
  cv::Mat gt_mask;           // the dataset's ground-truth moving-object mask when it has one (scores inlier leakage)
  double detector_ms = -1;   // -1: no detector
  double detector_cpu_ms = -1;
  double read_ms = 0;
  int lap = 0;               // --repeat
  bool blank = false;        // --blank
  std::string error;         // an exception in the worker, re-raised by the main thread
  bool end = false;
};

// Bounded queue between the reader/detector thread and tracking.
class JobQueue {
 public:
  explicit JobQueue(std::size_t capacity) : capacity_(capacity) {}
  void push(Job job) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return queue_.size() < capacity_ || cancelled_; });
    if (cancelled_) return;
    queue_.push_back(std::move(job));
    not_empty_.notify_one();
  }
  Job pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return !queue_.empty(); });
    Job job = std::move(queue_.front());
    queue_.pop_front();
    not_full_.notify_one();
    return job;
  }
  void cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    not_full_.notify_all();
  }
  bool cancelled() {
    std::lock_guard<std::mutex> lock(mutex_);
    return cancelled_;
  }

 private:
  std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<Job> queue_;
  bool cancelled_ = false;
};

class ProgressBar {
 public:
  explicit ProgressBar(std::size_t total) : total_(total), tty_(isatty(STDERR_FILENO) != 0), start_(Clock::now()) {}
  void update(std::size_t done, const char* state, std::size_t keyframes, bool force = false) {
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
  void finish() {
    if (tty_) std::fprintf(stderr, "\n");
  }

 private:
  std::size_t total_;
  bool tty_;
  Clock::time_point start_, last_draw_{};
};

int run(const Options& o) {
  DynamicMode mode = DynamicMode::kDetector;
  if (o.dynamic == "detector") {
    mode = DynamicMode::kDetector;
  } else if (o.dynamic == "gt") {
    mode = DynamicMode::kGroundTruth;
  } else if (o.dynamic == "off") {
    mode = DynamicMode::kOff;
  } else {
    throw InputError("--dynamic", o.dynamic, "expected detector, gt or off");
  }
  const agvslam::io::TrajectoryFormat format = agvslam::io::parse_trajectory_format(o.format, "--format");
  if (format == agvslam::io::TrajectoryFormat::kEuroc) throw InputError("--format", o.format, "expected tum or kitti");
  if (o.mapping != "thread" && o.mapping != "inline") throw InputError("--mapping", o.mapping, "expected thread or inline");
  if (!(o.speed >= 0)) throw InputError("--speed", std::to_string(o.speed), "expected a factor >= 0 (0: as fast as possible)");
  if (o.opencv_threads < 1 || o.opencv_threads > 64) {
    throw InputError("--opencv-threads", std::to_string(o.opencv_threads), "expected an integer in [1, 64]");
  }
  cv::setNumThreads(o.opencv_threads);
  if (o.loop != "on" && o.loop != "off") throw InputError("--loop", o.loop, "expected on or off");
  if (o.repeat < 1 || o.repeat > 100) throw InputError("--repeat", std::to_string(o.repeat), "expected an integer in [1, 100]");
  slam::MapMode map_mode = slam::MapMode::kMapping;
  if (!o.mode.empty()) {
    if (o.load_map.empty()) throw InputError("--mode", o.mode, "expected only with --load-map");
    map_mode = slam::parse_map_mode(o.mode, "--mode");
  } else if (!o.load_map.empty()) {
    throw InputError("--load-map", o.load_map, "expected --mode localise or --mode map with it");
  }
  if (!o.map_dataset.empty() && o.load_map.empty()) throw InputError("--map-dataset", o.map_dataset, "expected only with --load-map");
  std::optional<std::pair<std::size_t, std::size_t>> blank;
  if (!o.blank.empty()) blank = parse_blank(o.blank);
  if (!o.save_map.empty()) {
    // Checked now rather than after the whole run.
    std::filesystem::path folder = std::filesystem::path(o.save_map).parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec)) {
      throw InputError("--save-map", o.save_map, "expected a file in an existing folder (" + folder.string() + " is not one)");
    }
  }

  const auto dataset = agvslam::io::open_dataset(o.dataset, o.calib);
  std::size_t first = 0, last = 0;
  agvslam::io::parse_frame_range(o.frames, dataset->size(), "--frames", o.frames, first, last);
  // With ground-truth masks (simulator folders) every mode scores the pose's inliers against them.
  const bool has_gt_masks = !dataset->ground_truth_mask(first).empty();
  if (mode == DynamicMode::kGroundTruth && !has_gt_masks) {
    throw InputError("--dynamic", "gt", "expected a dataset with ground-truth masks (mask_0/, as agvslam-sim writes); " +
                                            dataset->root() + " has none");
  }

  slam::SystemConfig config;
  if (!o.params_slam.empty()) config.slam = slam::load_slam_config(o.params_slam);
  if (!o.params_features.empty()) {
    const agvslam::features::FeaturesConfig f = agvslam::features::load_features_config(o.params_features);
    config.orb = f.orb;
    config.stereo = f.stereo_matching;
  }
  config.frame_rate_hz = dataset->rate_hz();
  config.threaded_mapping = o.mapping == "thread";
  const agvslam::place::PlaceConfig place_config = agvslam::place::load_place_config(o.params_place);
  config.vocabulary = slam::load_vocabulary(place_config);
  config.direct_index_level = place_config.direct_index_level;
  if (o.loop == "off") config.slam.loop_closing.enabled = false;
  std::optional<agvslam::SE3d> T_w1_w2;
  if (!o.map_dataset.empty()) T_w1_w2 = simulator_world_offset(o.map_dataset, o.dataset);
  dyn::DynamicDetectorConfig dynamic_config;
  agvslam::stereo::StereoConfig stereo_config;
  if (mode == DynamicMode::kDetector) {
    if (!o.params_dynamic.empty()) dynamic_config = dyn::load_dynamic_config(o.params_dynamic);
    if (!o.params_stereo.empty()) stereo_config = agvslam::stereo::load_stereo_config(o.params_stereo);
  }

  spdlog::info("agvslam-run: {} dataset {} ({} frames at {:.1f} Hz, using {}..{})", dataset->kind(), dataset->root(),
               dataset->size(), dataset->rate_hz(), first, last);
  spdlog::info("  calibration: {}", dataset->calibration().summary());
  spdlog::info("  dynamic regions: {}", o.dynamic == "detector" ? "detector (paper 004 III.A-B), one frame ahead in a second thread"
                                        : o.dynamic == "gt"     ? "ground-truth masks (mask_0/)"
                                                                : "off (ORB-SLAM2-like baseline)");
  spdlog::info("  mapping: {}, speed {}, OpenCV threads per stage {}", o.mapping == "thread" ? "own thread" : "inline (deterministic)",
               o.speed > 0 ? std::to_string(o.speed) + "x the dataset rate" : std::string("as fast as possible"), o.opencv_threads);
  spdlog::info("  output: {} ({}){}", o.out, agvslam::io::to_string(format), o.json.empty() ? "" : ", stats " + o.json);
  spdlog::info("  slam settings{}", o.params_slam.empty() ? " (built-in defaults)" : " from " + o.params_slam);
  spdlog::info("  place recognition from {}: {}", o.params_place, place_config.describe());
  spdlog::info("  loop closing {}; map: {}{}{}", o.loop, o.load_map.empty() ? "new" : "load " + o.load_map,
               o.load_map.empty() ? "" : std::string(" (mode ") + slam::to_string(map_mode) + ")",
               o.save_map.empty() ? "" : ", save to " + o.save_map);
  if (blank) spdlog::info("  blank (covered camera) frames {}..{}", blank->first, blank->second);
  if (o.repeat > 1) spdlog::info("  {} laps of frames {}..{}", o.repeat, first, last);
  if (T_w1_w2) {
    spdlog::info("  map frame: the ground truth is expressed in {}'s world frame (t = {:.3f} {:.3f} {:.3f} m)", o.map_dataset,
                 T_w1_w2->translation().x(), T_w1_w2->translation().y(), T_w1_w2->translation().z());
  }
  spdlog::info("  feature settings{}", o.params_features.empty() ? " (built-in defaults)" : " from " + o.params_features);
  if (mode == DynamicMode::kDetector) {
    spdlog::info("  detector settings{}", o.params_dynamic.empty() ? " (built-in defaults)" : " from " + o.params_dynamic);
    for (const auto& line : dynamic_config.describe()) spdlog::info("    {}", line);
    spdlog::info("  stereo settings{}", o.params_stereo.empty() ? " (built-in defaults)" : " from " + o.params_stereo);
    for (const auto& line : stereo_config.describe()) spdlog::info("    {}", line);
  }

  slam::System system(dataset->calibration(), config);
  for (const auto& line : system.describe()) spdlog::info("    {}", line);
  nlohmann::json load_json;
  if (!o.load_map.empty()) {
    const slam::MapLoadStats ls = system.load_map(o.load_map, map_mode);
    spdlog::info("  loaded {}: {} keyframes, {} map points, {:.1f} MB (read {:.0f} ms, decode {:.0f} ms, bag of words {:.0f} ms)",
                 o.load_map, ls.keyframes, ls.map_points, static_cast<double>(ls.bytes) / 1e6, ls.read_ms, ls.decode_ms, ls.bow_ms);
    load_json = {{"file", o.load_map}, {"mode", slam::to_string(map_mode)}, {"keyframes", ls.keyframes},
                 {"map_points", ls.map_points}, {"bytes", ls.bytes}, {"read_ms", ls.read_ms}, {"decode_ms", ls.decode_ms},
                 {"bow_ms", ls.bow_ms}};
  }

  // Reader (+ detector) thread, one frame ahead.
  JobQueue queue(2);
  std::thread worker([&] {
    std::optional<dyn::DynamicDetector> detector;
    dyn::DetectorResult result;
    try {
      if (mode == DynamicMode::kDetector) detector.emplace(dataset->calibration(), dynamic_config, stereo_config);
      const std::size_t per_lap = last - first + 1;
      const int64_t lap_ns = per_lap > 1 ? (dataset->frame(last).t_ns - dataset->frame(first).t_ns) +
                                               static_cast<int64_t>(1e9 / dataset->rate_hz())
                                         : static_cast<int64_t>(1e9 / dataset->rate_hz());
      for (std::size_t step = 0; step < per_lap * static_cast<std::size_t>(o.repeat) && !queue.cancelled(); ++step) {
        const std::size_t i = first + step % per_lap;
        const int64_t lap = static_cast<int64_t>(step / per_lap);
        Job job;
        job.index = i;
        job.lap = static_cast<int>(lap);
        const auto t0 = Clock::now();
        job.frame = dataset->frame(i);
        job.frame.t_ns += lap * lap_ns;
        if (blank && i >= blank->first && i <= blank->second) {
          job.frame.left = cv::Mat::zeros(job.frame.left.size(), job.frame.left.type());
          job.frame.right = cv::Mat::zeros(job.frame.right.size(), job.frame.right.type());
          job.blank = true;
        }
        job.read_ms = ms_since(t0);
        if (mode == DynamicMode::kDetector) {
          const auto t1 = Clock::now();
          const double cpu1 = slam::thread_cpu_ms();
          detector->detect(job.frame, result);
          job.detector_ms = ms_since(t1);
          job.detector_cpu_ms = slam::thread_cpu_ms() - cpu1;
          job.mask = result.mask.image.clone();
        }
        if (has_gt_masks) job.gt_mask = dataset->ground_truth_mask(i);
        if (mode == DynamicMode::kGroundTruth) job.mask = job.gt_mask;
        queue.push(std::move(job));
      }
    } catch (const std::exception& e) {
      Job job;
      job.error = e.what();
      queue.push(std::move(job));
      return;
    }
    Job end;
    end.end = true;
    queue.push(std::move(end));
  });
  struct WorkerGuard {
    JobQueue& q;
    std::thread& t;
    ~WorkerGuard() {
      q.cancel();
      if (t.joinable()) t.join();
    }
  } guard{queue, worker};

  std::map<std::string, Series> series;
  const std::vector<std::string> stage_order = {"extract", "stereo", "map_wait", "frame", "local_map", "keyframe",
                                                "inline_mapping", "tracking", "tracking_cpu", "detector", "detector_cpu", "frontend_sum",
                                                "frontend_cpu", "frame_interval", "read"};
  nlohmann::json per_frame = nlohmann::json::array();
  std::size_t frames = 0, tracked = 0, lost = 0, resets = 0, recovered = 0, max_queue = 0;
  std::size_t keyframes = 0;
  ProgressBar progress((last - first + 1) * static_cast<std::size_t>(o.repeat));
  long first_tracked = -1;          // frames processed before the first pose
  long blank_end_step = -1;         // step of the last blanked frame (first lap)
  long blank_recovered_after = -1;  // frames after the blank until a pose
  std::vector<std::size_t> laps_keyframes, laps_points;
  // Inliers of the pose on ground-truth moving objects (what the dynamic masks are there to prevent).
  std::vector<double> moving_inlier_fraction;
  std::size_t moving_inliers_total = 0, inliers_total = 0;
  const auto t_run = Clock::now();
  auto t_prev_output = Clock::now();
  const double period_s = o.speed > 0 ? 1.0 / (dataset->rate_hz() * o.speed) : 0;

  for (;;) {
    Job job = queue.pop();
    if (!job.error.empty()) throw std::runtime_error("reading or detecting frames: " + job.error);
    if (job.end) break;
    if (period_s > 0) {  // real-time pacing: frame k is due at k * period
      const auto due = t_run + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s * static_cast<double>(frames)));
      std::this_thread::sleep_until(due);
    }
    const slam::TrackResult r = system.track_stereo(job.frame.t_ns, job.frame.left, job.frame.right, job.mask);
    const long step = static_cast<long>(frames);
    ++frames;
    if (r.state == slam::TrackingState::kOk && first_tracked < 0) first_tracked = step;
    if (job.blank && job.lap == 0) blank_end_step = step;
    if (blank_end_step >= 0 && blank_recovered_after < 0 && !job.blank && r.state == slam::TrackingState::kOk) {
      blank_recovered_after = step - blank_end_step - 1;
    }
    if (job.index == last) {
      laps_keyframes.push_back(r.keyframes);
      laps_points.push_back(r.map_points);
    }
    if (r.state == slam::TrackingState::kOk) ++tracked;
    if (r.state == slam::TrackingState::kLost) ++lost;
    if (r.counts.reset) ++resets;
    if (r.counts.recovered) ++recovered;
    keyframes = r.keyframes;
    max_queue = std::max(max_queue, r.mapping_queue);
    const double interval = ms_since(t_prev_output);
    t_prev_output = Clock::now();
    series["extract"].add(r.timings.extract_ms);
    series["stereo"].add(r.timings.stereo_ms);
    series["map_wait"].add(r.timings.map_wait_ms);
    series["frame"].add(r.timings.frame_ms);
    series["local_map"].add(r.timings.local_map_ms);
    series["keyframe"].add(r.timings.keyframe_ms);
    if (o.mapping == "inline") series["inline_mapping"].add(r.timings.inline_mapping_ms);
    series["tracking"].add(r.timings.total_ms);
    series["tracking_cpu"].add(r.timings.total_cpu_ms);
    series["read"].add(job.read_ms);
    if (job.detector_ms >= 0) {
      series["detector"].add(job.detector_ms);
      series["frontend_sum"].add(job.detector_ms + r.timings.total_ms);
      series["detector_cpu"].add(job.detector_cpu_ms);
      series["frontend_cpu"].add(job.detector_cpu_ms + r.timings.total_cpu_ms);
    }
    if (frames > 1) series["frame_interval"].add(interval);
    int moving_inliers = -1;
    if (!job.gt_mask.empty() && r.pose_valid && !r.inlier_keypoints_px.empty()) {
      moving_inliers = 0;
      for (const cv::Point2f& pt : r.inlier_keypoints_px) {
        const int x = std::clamp(static_cast<int>(std::lround(pt.x)), 0, job.gt_mask.cols - 1);
        const int y = std::clamp(static_cast<int>(std::lround(pt.y)), 0, job.gt_mask.rows - 1);
        if (job.gt_mask.at<uint8_t>(y, x) != 0) ++moving_inliers;
      }
      moving_inliers_total += static_cast<std::size_t>(moving_inliers);
      inliers_total += r.inlier_keypoints_px.size();
      moving_inlier_fraction.push_back(static_cast<double>(moving_inliers) / static_cast<double>(r.inlier_keypoints_px.size()));
    }
    per_frame.push_back({{"frame", job.index},
                         {"lap", job.lap},
                         {"blank", job.blank},
                         {"loops", r.loops_closed},
                         {"t_ns", job.frame.t_ns},
                         {"state", slam::to_string(r.state)},
                         {"features", r.counts.features},
                         {"stereo_features", r.counts.stereo_features},
                         {"method", r.counts.method},
                         {"frame_matches", r.counts.frame_matches},
                         {"inliers", r.counts.inliers},
                         {"keyframe", r.counts.new_keyframe},
                         {"keyframes", r.keyframes},
                         {"map_points", r.map_points},
                         {"mapping_queue", r.mapping_queue},
                         {"mask_pixels", job.mask.empty() ? 0 : cv::countNonZero(job.mask)},
                         {"moving_inliers", moving_inliers},
                         {"p_w_c", r.pose_valid ? nlohmann::json::array({r.T_w_c.translation().x(), r.T_w_c.translation().y(),
                                                                         r.T_w_c.translation().z()})
                                                : nlohmann::json()},
                         {"tracking_ms", r.timings.total_ms},
                         {"detector_ms", job.detector_ms}});
    progress.update(frames, slam::to_string(r.state), r.keyframes);
  }
  progress.update(frames, "done", keyframes, true);
  progress.finish();
  const double run_s = ms_since(t_run) / 1000.0;
  system.wait_for_mapping();
  const agvslam::Trajectory trajectory = system.trajectory();
  const slam::LocalMappingStats mstats = system.mapping_stats();
  const slam::LoopClosingStats lstats = system.loop_stats();
  nlohmann::json save_json;
  if (!o.save_map.empty()) {
    const slam::MapSaveStats ss = system.save_map(o.save_map);
    spdlog::info("saved {}: {} keyframes, {} map points, {:.1f} MB (encode {:.0f} ms, write {:.0f} ms)", o.save_map,
                 ss.keyframes, ss.map_points, static_cast<double>(ss.bytes) / 1e6, ss.encode_ms, ss.write_ms);
    save_json = {{"file", o.save_map}, {"keyframes", ss.keyframes}, {"map_points", ss.map_points}, {"bytes", ss.bytes},
                 {"encode_ms", ss.encode_ms}, {"write_ms", ss.write_ms}};
  }
  const auto mapping_history = system.local_mapping().timing_history();
  agvslam::slam::MapCounts map_counts;
  {
    std::lock_guard<std::mutex> lock(system.map().mutex());
    map_counts = system.map().counts();
  }
  system.shutdown();

  // Trajectory.
  agvslam::io::write_trajectory(o.out, trajectory, format);
  if (format == agvslam::io::TrajectoryFormat::kKitti && trajectory.size() != frames) {
    std::vector<int64_t> times;
    for (const auto& p : trajectory) times.push_back(p.t_ns);
    agvslam::io::write_kitti_times(o.out + ".times", times);
    spdlog::warn("{} of {} frames tracked: {} lists the stamps of the written poses (agvslam-eval --times)",
                 trajectory.size(), frames, o.out + ".times");
  }

  std::printf("FRAMES %zu TRACKED %zu KEYFRAMES %zu LOST %zu\n", frames, tracked, keyframes, lost);
  // Drift: the largest distance of a tracked position from the first one (for sequences where the camera stands
  // still, e.g. simulator scene1 and the EuRoC excerpt).
  double drift_m = 0;
  for (const auto& p : trajectory) drift_m = std::max(drift_m, (p.T_w_c.translation() - trajectory.front().T_w_c.translation()).norm());
  nlohmann::json j;
  std::optional<agvslam::Trajectory> gt = dataset->ground_truth();
  if (gt && (o.repeat > 1 || first > 0 || last + 1 < dataset->size())) {
    // The ground truth of the frames played, lap after lap, with the same continuing stamps.
    agvslam::Trajectory g;
    const std::size_t per_lap = last - first + 1;
    const int64_t lap_ns = per_lap > 1 ? (dataset->frame(last).t_ns - dataset->frame(first).t_ns) +
                                             static_cast<int64_t>(1e9 / dataset->rate_hz())
                                       : static_cast<int64_t>(1e9 / dataset->rate_hz());
    const int64_t t_first = dataset->frame(first).t_ns, t_last = dataset->frame(last).t_ns;
    for (int lap = 0; lap < o.repeat; ++lap) {
      for (const auto& p : *gt) {
        if (p.t_ns < t_first || p.t_ns > t_last) continue;
        g.push_back({p.t_ns + lap * lap_ns, p.T_w_c});
      }
    }
    gt = g;
  }
  if (gt && !trajectory.empty()) {
    const auto pairs = agvslam::eval::associate_by_timestamp(*gt, trajectory, 5'000'000);
    if (pairs.size() >= 3) {
      const auto ate = agvslam::eval::compute_ate(pairs, agvslam::eval::AlignMode::kSE3);
      const std::vector<agvslam::SE3d>& gt_poses = pairs.T_w_c_gt;
      double gt_motion_m = 0;
      for (const auto& T : gt_poses) gt_motion_m = std::max(gt_motion_m, (T.translation() - gt_poses.front().translation()).norm());
      std::printf("ATE_RMSE_M %.5f (SE3-aligned, %zu poses, ground-truth path %.2f m)\n", ate.translation_m.rmse,
                  ate.translation_m.count, agvslam::eval::path_length_m(gt_poses));
      j["ate"] = {{"rmse_m", ate.translation_m.rmse}, {"mean_m", ate.translation_m.mean}, {"max_m", ate.translation_m.max},
                  {"poses", ate.translation_m.count}, {"gt_path_m", agvslam::eval::path_length_m(gt_poses)},
                  {"gt_max_displacement_m", gt_motion_m}};
    }
  }
  std::printf("DRIFT_M %.5f (largest distance from the first tracked position)\n", drift_m);
  if (!moving_inlier_fraction.empty()) {
    Series f;
    f.v = moving_inlier_fraction;
    const double mean = inliers_total ? static_cast<double>(moving_inliers_total) / static_cast<double>(inliers_total) : 0;
    const std::size_t over10 = static_cast<std::size_t>(
        std::count_if(f.v.begin(), f.v.end(), [](double x) { return x > 0.10; }));
    std::printf("MOVING_INLIERS %.4f (of the pose inliers on ground-truth moving objects; p95 %.4f, max %.4f, %zu of %zu "
                "frames over 10%%)\n",
                mean, f.quantile(0.95), f.max(), over10, f.v.size());
    j["moving_inliers"] = {{"fraction", mean}, {"p95_fraction", f.quantile(0.95)}, {"max_fraction", f.max()},
                           {"frames_over_10pct", over10}, {"frames_scored", f.v.size()}, {"total", moving_inliers_total}};
  }
  if (gt && T_w1_w2 && !trajectory.empty()) {
    // Positions in the saved map's frame, without alignment.
    agvslam::Trajectory gt_map;
    for (const auto& p : *gt) gt_map.push_back({p.t_ns, *T_w1_w2 * p.T_w_c});
    const auto pairs = agvslam::eval::associate_by_timestamp(gt_map, trajectory, 5'000'000);
    if (pairs.size() >= 1) {
      const auto ate = agvslam::eval::compute_ate(pairs, agvslam::eval::AlignMode::kNone);
      std::printf("MAP_FRAME_ATE_M %.5f (no alignment, %zu poses, max %.4f m)\n", ate.translation_m.rmse,
                  ate.translation_m.count, ate.translation_m.max);
      j["map_frame_ate"] = {{"rmse_m", ate.translation_m.rmse}, {"max_m", ate.translation_m.max},
                            {"poses", ate.translation_m.count}};
    }
  }
  std::printf("LOOPS %llu", static_cast<unsigned long long>(lstats.loops_closed));
  nlohmann::json loops_json = nlohmann::json::array();
  for (const slam::LoopEvent& e : lstats.loops) {
    std::printf("  [kf %llu -> %llu, frame %llu -> %llu, %d matches, moved %.3f m %.2f deg]",
                static_cast<unsigned long long>(e.keyframe_id), static_cast<unsigned long long>(e.loop_keyframe_id),
                static_cast<unsigned long long>(e.frame_id), static_cast<unsigned long long>(e.loop_frame_id),
                e.total_matches, e.correction_m, e.correction_deg);
    loops_json.push_back({{"keyframe", e.keyframe_id}, {"loop_keyframe", e.loop_keyframe_id}, {"frame", e.frame_id},
                          {"loop_frame", e.loop_frame_id}, {"t_ns", e.t_ns}, {"bow_matches", e.bow_matches},
                          {"ransac_inliers", e.ransac_inliers}, {"refined_inliers", e.refined_inliers},
                          {"total_matches", e.total_matches}, {"correction_m", e.correction_m},
                          {"correction_deg", e.correction_deg}, {"fused_points", e.fused_points},
                          {"graph_keyframes", e.graph_keyframes}, {"graph_edges", e.graph_edges},
                          {"detect_ms", e.detect_ms}, {"correct_ms", e.correct_ms}, {"pose_graph_ms", e.pose_graph_ms},
                          {"global_ba_ms", e.global_ba_ms}, {"global_ba_merge_ms", e.global_ba_merge_ms}});
  }
  std::printf("\n");
  std::printf("RELOCALISATION first_tracked %ld", first_tracked);
  if (blank) std::printf(" blank_recovered_after %ld", blank_recovered_after);
  std::printf("\n");
  if (o.repeat > 1) {
    std::printf("laps:");
    for (std::size_t k = 0; k < laps_keyframes.size(); ++k) {
      std::printf(" [%zu: %zu keyframes, %zu map points]", k + 1, laps_keyframes[k], laps_points[k]);
    }
    std::printf("\n");
  }
  std::printf("counts: %zu frames, %zu tracked, %zu lost, %zu recovered, %zu resets; %zu keyframes, %zu map points "
              "(%.1f MB); mapping: %llu keyframes processed, %llu skipped (queue full), max queue %zu, %llu culled "
              "keyframes, %llu created / %llu culled points\n",
              frames, tracked, lost, recovered, resets, map_counts.keyframes, map_counts.map_points,
              static_cast<double>(map_counts.memory_bytes) / 1e6, static_cast<unsigned long long>(mstats.keyframes_processed),
              static_cast<unsigned long long>(mstats.keyframes_skipped), max_queue,
              static_cast<unsigned long long>(mstats.keyframes_culled), static_cast<unsigned long long>(mstats.points_created),
              static_cast<unsigned long long>(mstats.points_culled));
  std::printf("time per frame [ms]   median      p95      max\n");
  for (const auto& name : stage_order) {
    const auto it = series.find(name);
    if (it == series.end() || it->second.v.empty()) continue;
    std::printf("  %-16s %9.2f %8.2f %8.2f\n", name.c_str(), it->second.quantile(0.5), it->second.quantile(0.95),
                it->second.max());
  }
  std::map<std::string, Series> mapping_series;
  for (const auto& h : mapping_history) {
    mapping_series["insert"].add(h.insert_ms);
    mapping_series["point_culling"].add(h.culling_ms);
    mapping_series["triangulation"].add(h.triangulation_ms);
    mapping_series["fusion"].add(h.fusion_ms);
    mapping_series["local_ba"].add(h.ba_ms);
    mapping_series["keyframe_culling"].add(h.kf_culling_ms);
    mapping_series["total"].add(h.total_ms);
  }
  std::printf("time per keyframe (local mapping) [ms]   median      p95      max\n");
  for (const char* name : {"triangulation", "fusion", "local_ba", "total"}) {
    const Series& s = mapping_series[name];
    std::printf("  %-16s %9.2f %8.2f %8.2f\n", name, s.quantile(0.5), s.quantile(0.95), s.max());
  }
  std::printf("wall time %.1f s, %.1f frames/s\n", run_s, run_s > 0 ? static_cast<double>(frames) / run_s : 0.0);

  if (!o.json.empty()) {
    j["dataset"] = dataset->root();
    j["dynamic"] = o.dynamic;
    j["mapping"] = o.mapping;
    j["speed"] = o.speed;
    j["frames"] = {{"first", first}, {"last", last}, {"processed", frames}, {"tracked", tracked}, {"lost", lost},
                   {"recovered", recovered}, {"resets", resets}};
    j["drift_m"] = drift_m;
    j["loops"] = loops_json;
    j["loop_closing"] = {{"enabled", o.loop == "on"}, {"keyframes_processed", lstats.keyframes_processed},
                         {"keyframes_dropped", lstats.keyframes_dropped}, {"consistent_detections", lstats.consistent_detections},
                         {"rejected_geometry", lstats.rejected_geometry}, {"rejected_correction", lstats.rejected_correction},
                         {"loops_closed", lstats.loops_closed}, {"global_ba_runs", lstats.global_ba_runs},
                         {"global_ba_aborted", lstats.global_ba_aborted}};
    j["relocalisation"] = {{"first_tracked", first_tracked}, {"blank_recovered_after", blank_recovered_after}};
    if (!load_json.is_null()) j["load_map"] = load_json;
    if (!save_json.is_null()) j["save_map"] = save_json;
    if (o.repeat > 1) j["laps"] = {{"keyframes", laps_keyframes}, {"map_points", laps_points}};
    j["map"] = {{"keyframes", map_counts.keyframes}, {"map_points", map_counts.map_points},
                {"observations", map_counts.observations}, {"memory_bytes", map_counts.memory_bytes}};
    j["local_mapping"] = {{"keyframes_processed", mstats.keyframes_processed}, {"keyframes_skipped", mstats.keyframes_skipped},
                          {"keyframes_culled", mstats.keyframes_culled}, {"points_created", mstats.points_created},
                          {"points_fused", mstats.points_fused}, {"points_culled", mstats.points_culled},
                          {"ba_runs", mstats.ba_runs}, {"ba_aborted", mstats.ba_aborted}, {"ba_outliers", mstats.ba_outliers},
                          {"max_queue", max_queue}};
    nlohmann::json jt, jm;
    for (const auto& [name, s] : series) jt[name] = s.json();
    for (const auto& [name, s] : mapping_series) jm[name] = s.json();
    j["timings"] = jt;
    j["mapping_timings"] = jm;
    j["wall_s"] = run_s;
    j["per_frame"] = per_frame;
    agvslam::io::write_file_atomically(o.json, j.dump(1) + "\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the FRAMES line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-run"));
  CLI::App app{"agvslam-run: stereo SLAM with dynamic-region removal (paper 004) over a dataset folder"};
  Options o;
  app.add_option("--dataset", o.dataset, "sequence folder: KITTI layout (also agvslam-sim output) or EuRoC ASL")->required();
  app.add_option("--out", o.out, "trajectory file to write (every tracked frame)")->required();
  app.add_option("--calib", o.calib, "calibration file instead of the dataset's own (KITTI calib.txt, ORB-SLAM YAML, Kalibr)");
  app.add_option("--format", o.format, "trajectory format: tum (default) or kitti");
  app.add_option("--dynamic", o.dynamic, "dynamic regions: detector (default), gt (dataset masks) or off");
  app.add_option("--json", o.json, "statistics file (timings, counts, per-frame records)");
  app.add_option("--frames", o.frames, "inclusive frame range A:B (either side may be empty)");
  app.add_option("--params-slam", o.params_slam, "params/slam.yaml");
  app.add_option("--params-features", o.params_features, "params/features.yaml");
  app.add_option("--params-dynamic", o.params_dynamic, "params/dynamic.yaml (with --dynamic detector)");
  app.add_option("--params-stereo", o.params_stereo, "params/stereo.yaml (with --dynamic detector)");
  app.add_option("--mapping", o.mapping, "local mapping: thread (default, as on the vehicle) or inline (deterministic)");
  app.add_option("--speed", o.speed, "feed frames at this multiple of the dataset rate (0, default: as fast as possible)");
  app.add_option("--opencv-threads", o.opencv_threads, "OpenCV's threads inside a stage (default 1: one core per thread)");
  app.add_option("--params-place", o.params_place, "params/place.yaml (the vocabulary; default: the source tree's)");
  app.add_option("--loop", o.loop, "loop closing: on (default) or off");
  app.add_option("--save-map", o.save_map, "write the final map to this file (atomically)");
  app.add_option("--load-map", o.load_map, "start in this saved map (needs --mode)");
  app.add_option("--mode", o.mode, "with --load-map: localise (track without changing the map) or map (extend it)");
  app.add_option("--blank", o.blank, "black out frames A:B (inclusive): a covered camera, forced loss");
  app.add_option("--repeat", o.repeat, "play the frame range this many times in a row (laps of a loop)");
  app.add_option("--map-dataset", o.map_dataset, "with --load-map on simulator folders: the folder the map was made from (MAP_FRAME_ATE_M)");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
