// agvslam-run: the stereo SLAM (paper 004: dynamic regions removed, then ORB-SLAM2-style tracking and mapping)
// over a dataset folder.
//
//   agvslam-run --dataset DIR --out TRAJ [--calib FILE] [--format tum|kitti] [--dynamic detector|gt|off]
//               [--json STATS] [--frames A:B] [--params-slam params/slam.yaml] [--params-features ...]
//               [--params-dynamic ...] [--params-stereo ...] [--mapping thread|inline] [--speed X]
//               [--opencv-threads N] [--params-place params/place.yaml] [--loop on|off]
//               [--save-map FILE] [--load-map FILE --mode localise|map] [--blank A:B] [--repeat N]
//               [--map-dataset DIR] [--semantic MODEL|off] [--params-semantic params/semantic.yaml]
//               [--save-earlier-maps DIR] [--test-slow-mapping-ms MS]
//
// Reads KITTI-layout folders (also what agvslam-sim writes), EuRoC ASL folders and rosbag2 recordings (sqlite3
// storage) through agvslam::io, and runs
// them through agvslamd's pipeline (agvslam/daemon/pipeline.h) with its outputs off and lossless queues (every
// frame processed): a reader thread, with --dynamic detector a detector thread (detection of frame k+1 overlaps
// tracking of frame k), and the tracking thread. --dynamic gt takes the dataset's ground-truth masks (simulator
// mask_0/), --dynamic off is the plain ORB-SLAM2-like baseline. --semantic MODEL (with --dynamic detector) adds the
// semantic stage in the detector thread (agvslam/semantic/semantic_masker.h): the network in a worker of its own,
// moving segmented objects fused into the detector's mask; a model that cannot be loaded leaves the detector alone,
// with a warning.
//
// --mapping thread runs local mapping in its own thread, as on the vehicle; --mapping inline maps each keyframe
// before the next frame (deterministic: the same input gives the same trajectory; the tracking times then include
// that mapping work, shown separately as inline_mapping: take speed figures with --mapping thread). --speed 1 feeds
// frames at the dataset's rate (the real-time case; none is dropped when the pipeline falls behind), 0 as fast as
// tracking goes. --test-slow-mapping-ms MS (tests only) makes local mapping sleep MS after each of its steps, as
// on a computer too slow for the frame rate.
//
// Writes TRAJ with the pose of every tracked frame (each relative to its reference keyframe, composed with the
// keyframe's final pose, as ORB-SLAM2 saves trajectories); with --format kitti and frames missing, TRAJ.times
// gives the stamps of the written poses (agvslam-eval --times). stdout: first line
//   FRAMES <n> TRACKED <m> KEYFRAMES <k> LOST <l>
// then, with ground truth, `ATE_RMSE_M <x>` (SE(3)-aligned, by time stamp) and the drift, then per-stage timing
// (median / p95 / max ms; wall clock, and *_cpu: the thread's own CPU time, which other load on the machine does
// not inflate), and
//   MAPS <n> (new maps after a long loss: <n-1>) LAST_STATE <state> KEYFRAME_WAITS <k>
// (tracking lost for slam.tracking.new_map_after_lost_s starts a new map: the trajectory file then holds the poses
// of each map in that map's frame, and ATE aligns each map on its own; KEYFRAME_WAITS: frames that waited for room
// in local mapping's queue; --save-earlier-maps DIR saves each map left behind as DIR/map_<map_id>.agvmap). --json
// adds per-frame records (state, map_id, counts, times, mapping queue length).
// A progress bar with the frame rate goes to stderr. Exit status: 0 on success, 2 on bad input (the message names
// the option, file or field), 1 on any other failure.
//
// Place recognition and maps: --params-place names the vocabulary (default: the source tree's
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

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/error.h"
#include "agvslam/core/stats.h"
#include "agvslam/daemon/frame_source.h"
#include "agvslam/daemon/pipeline.h"
#include "agvslam/eval/association.h"
#include "agvslam/eval/metrics.h"
#include "agvslam/features/features_config.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/place/place_config.h"
#include "agvslam/sim/simulator.h"
#include "agvslam/slam/system.h"
#include "agvslam/stereo/stereo_config.h"
#include "run_frame_log.h"
#include "tool_main.h"

namespace {

using agvslam::InputError;
using agvslam::Series;
namespace slam = agvslam::slam;
namespace dyn = agvslam::dynamic;
namespace daemon = agvslam::daemon;
using agvslam::apps::run_tool::FrameLog;

enum class DynamicMode { kDetector, kGroundTruth, kOff };

#ifndef AGVSLAM_PARAMS_DIR
#define AGVSLAM_PARAMS_DIR "params"
#endif

struct Options {
  std::string dataset, calib, out, format = "tum", dynamic = "detector", json, frames, mapping = "thread";
  std::string params_slam, params_features, params_dynamic, params_stereo;
  std::string semantic = "off", params_semantic = AGVSLAM_PARAMS_DIR "/semantic.yaml";
  std::string params_place = AGVSLAM_PARAMS_DIR "/place.yaml";
  std::string loop = "on", save_map, load_map, mode, blank, map_dataset, save_earlier_maps;
  int repeat = 1;
  double speed = 0;
  int opencv_threads = 1;
  double test_slow_mapping_ms = 0;
};

// The options checked and parsed.
struct Settings {
  DynamicMode dynamic = DynamicMode::kDetector;
  agvslam::io::TrajectoryFormat format = agvslam::io::TrajectoryFormat::kTum;
  slam::MapMode map_mode = slam::MapMode::kMapping;
  std::optional<std::pair<std::size_t, std::size_t>> blank;  // --blank A:B, inclusive
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

DynamicMode parse_dynamic_mode(const std::string& text) {
  if (text == "detector") return DynamicMode::kDetector;
  if (text == "gt") return DynamicMode::kGroundTruth;
  if (text == "off") return DynamicMode::kOff;
  throw InputError("--dynamic", text, "expected detector, gt or off");
}

// Every option that can be checked before a file is read; InputError naming the option otherwise.
Settings check_options(const Options& o) {
  Settings s;
  s.dynamic = parse_dynamic_mode(o.dynamic);
  s.format = agvslam::io::parse_trajectory_format(o.format, "--format");
  if (s.format == agvslam::io::TrajectoryFormat::kEuroc)
    throw InputError("--format", o.format, "expected tum or kitti");
  if (o.mapping != "thread" && o.mapping != "inline")
    throw InputError("--mapping", o.mapping, "expected thread or inline");
  if (!(o.speed >= 0))
    throw InputError("--speed", std::to_string(o.speed), "expected a factor >= 0 (0: as fast as possible)");
  if (o.opencv_threads < 1 || o.opencv_threads > 64) {
    throw InputError("--opencv-threads", std::to_string(o.opencv_threads), "expected an integer in [1, 64]");
  }
  if (o.loop != "on" && o.loop != "off") throw InputError("--loop", o.loop, "expected on or off");
  if (!(o.test_slow_mapping_ms >= 0 && o.test_slow_mapping_ms <= 10000)) {
    throw InputError("--test-slow-mapping-ms", std::to_string(o.test_slow_mapping_ms), "expected 0 to 10000 ms");
  }
  if (o.repeat < 1 || o.repeat > 100)
    throw InputError("--repeat", std::to_string(o.repeat), "expected an integer in [1, 100]");
  if (!o.mode.empty()) {
    if (o.load_map.empty()) throw InputError("--mode", o.mode, "expected only with --load-map");
    s.map_mode = slam::parse_map_mode(o.mode, "--mode");
  } else if (!o.load_map.empty()) {
    throw InputError("--load-map", o.load_map, "expected --mode localise or --mode map with it");
  }
  if (!o.map_dataset.empty() && o.load_map.empty())
    throw InputError("--map-dataset", o.map_dataset, "expected only with --load-map");
  if (!o.blank.empty()) s.blank = parse_blank(o.blank);
  if (!o.save_map.empty()) {
    // Checked now rather than after the whole run.
    std::filesystem::path folder = std::filesystem::path(o.save_map).parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec)) {
      throw InputError("--save-map", o.save_map,
                       "expected a file in an existing folder (" + folder.string() + " is not one)");
    }
  }
  return s;
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
      throw InputError(path, "scenario, frames, seed, layout_seed, start_offset_m",
                       std::string("expected them (") + e.what() + ")");
    }
    const agvslam::sim::Simulator sim(agvslam::sim::SimConfig{}, so);
    return std::make_pair(agvslam::SE3d(sim.T_map_cam(0)), so.effective_layout_seed());
  };
  const auto [T_map_c1, layout1] = first_camera(map_dir);
  const auto [T_map_c2, layout2] = first_camera(run_dir);
  if (layout1 != layout2) {
    throw InputError("--map-dataset", map_dir,
                     "expected a run through the same warehouse (layout seed " + std::to_string(layout2) +
                         ", that folder has " + std::to_string(layout1) + ")");
  }
  return T_map_c1.inverse() * T_map_c2;
}

// The dataset, the frames played, whether it has ground-truth masks, and (--map-dataset) the map's world frame.
struct Input {
  daemon::SourceSetup setup;             // the dataset and frames first..last
  bool has_gt_masks = false;             // mask_0/ (simulator): every mode scores the pose's inliers against them
  std::optional<agvslam::SE3d> T_w1_w2;  // --map-dataset: this run's world frame in the map's
};

Input open_input(const Options& o, const Settings& s) {
  std::shared_ptr<const agvslam::io::StereoDataset> dataset = agvslam::io::open_dataset(o.dataset, o.calib);
  std::size_t first = 0, last = 0;
  agvslam::io::parse_frame_range(o.frames, dataset->size(), "--frames", o.frames, first, last);
  Input in;
  in.has_gt_masks = !dataset->ground_truth_mask(first).empty();
  if (s.dynamic == DynamicMode::kGroundTruth && !in.has_gt_masks) {
    throw InputError("--dynamic", "gt",
                     "expected a dataset with ground-truth masks (mask_0/, as agvslam-sim writes); " + dataset->root() +
                         " has none");
  }
  in.setup = daemon::dataset_setup(std::move(dataset), first, last);
  if (!o.map_dataset.empty()) in.T_w1_w2 = simulator_world_offset(o.map_dataset, o.dataset);
  return in;
}

// agvslamd's configuration for playing the dataset: the stage settings from the command line, no outputs.
daemon::DaemonConfig pipeline_config(const Options& o, const Settings& s) {
  daemon::DaemonConfig c;
  c.path = "agvslam-run";
  c.source.type = daemon::SourceType::kDataset;
  c.source.dataset = o.dataset;
  c.source.rate = o.speed;
  c.pipeline.dynamic = s.dynamic == DynamicMode::kDetector ? daemon::DynamicMode::kDetector : daemon::DynamicMode::kOff;
  c.pipeline.mapping = o.mapping == "thread" ? daemon::MappingMode::kThread : daemon::MappingMode::kInline;
  c.pipeline.opencv_threads = o.opencv_threads;
  c.outputs.dds_enabled = false;
  c.outputs.can_enabled = false;

  slam::SystemConfig& system = c.system;
  if (!o.params_slam.empty()) system.slam = slam::load_slam_config(o.params_slam);
  if (!o.params_features.empty()) {
    const agvslam::features::FeaturesConfig f = agvslam::features::load_features_config(o.params_features);
    system.orb = f.orb;
    system.stereo = f.stereo_matching;
  }
  system.threaded_mapping = o.mapping == "thread";
  system.test_mapping_step_delay_ms = o.test_slow_mapping_ms;
  system.earlier_maps_folder = o.save_earlier_maps;
  c.place = agvslam::place::load_place_config(o.params_place);  // the pipeline loads the vocabulary
  system.direct_index_level = c.place->direct_index_level;
  if (o.loop == "off") system.slam.loop_closing.enabled = false;
  if (s.dynamic == DynamicMode::kDetector) {
    if (!o.params_dynamic.empty()) c.detector = dyn::load_dynamic_config(o.params_dynamic);
    if (!o.params_stereo.empty()) c.stereo = agvslam::stereo::load_stereo_config(o.params_stereo);
    if (o.semantic != "off") {
      c.semantic = agvslam::semantic::load_semantic_config(o.params_semantic);
      c.semantic->model.path = o.semantic;
    }
  }
  return c;
}

void log_settings(const Options& o, const Settings& s, const Input& in, const daemon::DaemonConfig& c) {
  const agvslam::io::StereoDataset& dataset = *in.setup.dataset;
  spdlog::info("agvslam-run: {} dataset {} ({} frames at {:.1f} Hz, using {}..{})", dataset.kind(), dataset.root(),
               dataset.size(), dataset.rate_hz(), in.setup.first, in.setup.last);
  spdlog::info("  calibration: {}", dataset.calibration().summary());
  spdlog::info("  dynamic regions: {}", o.dynamic == "detector"
                                            ? "detector (paper 004 III.A-B), one frame ahead in its own thread"
                                        : o.dynamic == "gt" ? "ground-truth masks (mask_0/)"
                                                            : "off (ORB-SLAM2-like baseline)");
  spdlog::info("  mapping: {}, speed {}, OpenCV threads per stage {}",
               o.mapping == "thread" ? "own thread" : "inline (deterministic)",
               o.speed > 0 ? std::to_string(o.speed) + "x the dataset rate" : std::string("as fast as possible"),
               o.opencv_threads);
  spdlog::info("  output: {} ({}){}", o.out, agvslam::io::to_string(s.format),
               o.json.empty() ? "" : ", stats " + o.json);
  spdlog::info("  slam settings{}", o.params_slam.empty() ? " (built-in defaults)" : " from " + o.params_slam);
  spdlog::info("  place recognition from {}: {}", o.params_place, c.place->describe());
  spdlog::info("  loop closing {}; map: {}{}{}", o.loop, o.load_map.empty() ? "new" : "load " + o.load_map,
               o.load_map.empty() ? "" : std::string(" (mode ") + slam::to_string(s.map_mode) + ")",
               o.save_map.empty() ? "" : ", save to " + o.save_map);
  if (s.blank) spdlog::info("  blank (covered camera) frames {}..{}", s.blank->first, s.blank->second);
  if (o.test_slow_mapping_ms > 0)
    spdlog::warn("  TEST ONLY: local mapping sleeps {} ms after each step (a slower computer)", o.test_slow_mapping_ms);
  if (o.repeat > 1) spdlog::info("  {} laps of frames {}..{}", o.repeat, in.setup.first, in.setup.last);
  if (in.T_w1_w2) {
    spdlog::info("  map frame: the ground truth is expressed in {}'s world frame (t = {:.3f} {:.3f} {:.3f} m)",
                 o.map_dataset, in.T_w1_w2->translation().x(), in.T_w1_w2->translation().y(),
                 in.T_w1_w2->translation().z());
  }
  spdlog::info("  feature settings{}",
               o.params_features.empty() ? " (built-in defaults)" : " from " + o.params_features);
  if (s.dynamic == DynamicMode::kDetector) {
    spdlog::info("  detector settings{}",
                 o.params_dynamic.empty() ? " (built-in defaults)" : " from " + o.params_dynamic);
    for (const auto& line : c.detector.describe()) spdlog::info("    {}", line);
    spdlog::info("  stereo settings{}", o.params_stereo.empty() ? " (built-in defaults)" : " from " + o.params_stereo);
    for (const auto& line : c.stereo.describe()) spdlog::info("    {}", line);
    if (c.semantic) {
      spdlog::info("  semantic settings from {}", o.params_semantic);
      for (const auto& line : c.semantic->describe()) spdlog::info("    {}", line);
    }
  }
}

nlohmann::json timing_json(const Series& s) {
  return {{"median_ms", s.median()},
          {"p95_ms", s.quantile(0.95)},
          {"p99_ms", s.quantile(0.99)},
          {"max_ms", s.max()},
          {"count", s.count()}};
}

// What the SLAM holds at the end of the run.
struct SlamResults {
  agvslam::Trajectory trajectory;
  std::vector<uint32_t> trajectory_map_ids;    // the map of each pose (System::trajectory)
  std::vector<std::string> earlier_map_files;  // --save-earlier-maps
  slam::LocalMappingStats mapping;
  slam::RetirementCounts retired;  // map points on objects that moved
  slam::LoopClosingStats loops;
  std::vector<slam::KeyframeMappingTimes> mapping_history;
  slam::MapCounts map_counts;
  nlohmann::json load_map, save_map;  // null when not asked for
  uint64_t skipped_frames = 0;        // unreadable images the source skipped
};

nlohmann::json load_map(slam::System& system, const Options& o, const Settings& s) {
  const slam::MapLoadStats ls = system.load_map(o.load_map, s.map_mode);
  spdlog::info(
      "  loaded {}: {} keyframes, {} map points, {:.1f} MB (read {:.0f} ms, decode {:.0f} ms, bag of words {:.0f} ms)",
      o.load_map, ls.keyframes, ls.map_points, static_cast<double>(ls.bytes) / 1e6, ls.read_ms, ls.decode_ms,
      ls.bow_ms);
  return {{"file", o.load_map},        {"mode", slam::to_string(s.map_mode)},
          {"keyframes", ls.keyframes}, {"map_points", ls.map_points},
          {"bytes", ls.bytes},         {"read_ms", ls.read_ms},
          {"decode_ms", ls.decode_ms}, {"bow_ms", ls.bow_ms}};
}

nlohmann::json save_map(slam::System& system, const std::string& file) {
  const slam::MapSaveStats ss = system.save_map(file);
  spdlog::info("saved {}: {} keyframes, {} map points, {:.1f} MB (encode {:.0f} ms, write {:.0f} ms)", file,
               ss.keyframes, ss.map_points, static_cast<double>(ss.bytes) / 1e6, ss.encode_ms, ss.write_ms);
  return {{"file", file},      {"keyframes", ss.keyframes}, {"map_points", ss.map_points},
          {"bytes", ss.bytes}, {"encode_ms", ss.encode_ms}, {"write_ms", ss.write_ms}};
}

// Plays the dataset through the pipeline; the frames' figures go to `log`. False when a pipeline thread failed
// (its error is logged).
bool play(const Options& o, const Settings& s, const Input& in, FrameLog& log, SlamResults& results) {
  const daemon::DaemonConfig config = pipeline_config(o, s);
  log_settings(o, s, in, config);
  daemon::DatasetPlayback playback;
  playback.laps = o.repeat;
  playback.blank = s.blank;
  playback.ground_truth_masks = in.has_gt_masks;
  playback.lossless = true;
  daemon::PipelineOptions options;
  options.ground_truth_masks = s.dynamic == DynamicMode::kGroundTruth;
  options.on_tracked = [&log](const daemon::TrackedFrame& f) { log.add(f); };
  options.settle_mapping = true;
  daemon::Pipeline pipeline(
      config, in.setup, std::make_unique<daemon::DatasetSource>(in.setup, config.source, playback), std::move(options));
  slam::System& system = pipeline.system();
  for (const auto& line : system.describe()) spdlog::info("    {}", line);
  if (!o.load_map.empty()) results.load_map = load_map(system, o, s);

  log.start();
  pipeline.start();
  pipeline.wait();
  if (pipeline.failed()) return false;
  results.skipped_frames = pipeline.stats().dropped_source;
  if (results.skipped_frames > 0) spdlog::warn("{} unreadable frames skipped", results.skipped_frames);
  results.trajectory = system.trajectory(&results.trajectory_map_ids);
  results.mapping = system.mapping_stats();
  results.earlier_map_files = system.earlier_map_files();
  for (const std::string& e : system.earlier_map_errors()) spdlog::error("earlier map not saved: {}", e);
  results.retired = system.retirement_counts();
  results.loops = system.loop_stats();
  if (!o.save_map.empty()) results.save_map = save_map(system, o.save_map);
  results.mapping_history = system.local_mapping().timing_history();
  std::lock_guard<std::mutex> lock(system.map().mutex());
  results.map_counts = system.map().counts();
  return true;
}

void write_trajectory(const Options& o, const Settings& s, const agvslam::Trajectory& trajectory, std::size_t frames) {
  agvslam::io::write_trajectory(o.out, trajectory, s.format);
  if (s.format == agvslam::io::TrajectoryFormat::kKitti && trajectory.size() != frames) {
    std::vector<int64_t> times;
    for (const auto& p : trajectory) times.push_back(p.t_ns);
    agvslam::io::write_kitti_times(o.out + ".times", times);
    spdlog::warn("{} of {} frames tracked: {} lists the stamps of the written poses (agvslam-eval --times)",
                 trajectory.size(), frames, o.out + ".times");
  }
}

// The dataset's ground truth of the frames played, lap after lap with the same continuing stamps as the frames.
std::optional<agvslam::Trajectory> played_ground_truth(const Options& o, const daemon::SourceSetup& setup) {
  const agvslam::io::StereoDataset& dataset = *setup.dataset;
  std::optional<agvslam::Trajectory> gt = dataset.ground_truth();
  if (!gt || (o.repeat == 1 && setup.first == 0 && setup.last + 1 >= dataset.size())) return gt;
  const int64_t lap_ns = daemon::lap_duration_ns(dataset, setup.first, setup.last);
  const int64_t t_first = dataset.timestamp_ns(setup.first), t_last = dataset.timestamp_ns(setup.last);
  agvslam::Trajectory played;
  for (int lap = 0; lap < o.repeat; ++lap) {
    for (const auto& p : *gt) {
      if (p.t_ns < t_first || p.t_ns > t_last) continue;
      played.push_back({p.t_ns + lap * lap_ns, p.T_w_c});
    }
  }
  return played;
}

// ATE_RMSE_M (SE(3)-aligned) and DRIFT_M lines; j["ate"]. Poses of several maps (a new map after a long loss)
// are in different frames: each map is aligned on its own and the RMSE is over all their poses.
void report_accuracy(const agvslam::Trajectory& trajectory, const std::vector<uint32_t>& map_ids,
                     const std::optional<agvslam::Trajectory>& gt, nlohmann::json& j) {
  const bool several_maps =
      !map_ids.empty() && std::any_of(map_ids.begin(), map_ids.end(), [&](uint32_t m) { return m != map_ids[0]; });
  if (several_maps && map_ids.size() == trajectory.size()) {
    std::map<uint32_t, agvslam::Trajectory> by_map;
    for (std::size_t k = 0; k < trajectory.size(); ++k) by_map[map_ids[k]].push_back(trajectory[k]);
    double drift_m = 0, sum_sq = 0;
    std::size_t poses = 0;
    nlohmann::json per_map = nlohmann::json::array();
    for (const auto& [id, part] : by_map) {
      for (const auto& p : part)
        drift_m = std::max(drift_m, (p.T_w_c.translation() - part.front().T_w_c.translation()).norm());
      if (!gt) continue;
      const auto pairs = agvslam::eval::associate_by_timestamp(*gt, part, 5'000'000);
      if (pairs.size() < 3) continue;
      const auto ate = agvslam::eval::compute_ate(pairs, agvslam::eval::AlignMode::kSE3);
      sum_sq += ate.translation_m.rmse * ate.translation_m.rmse * static_cast<double>(ate.translation_m.count);
      poses += ate.translation_m.count;
      per_map.push_back({{"map_id", id}, {"rmse_m", ate.translation_m.rmse}, {"poses", ate.translation_m.count}});
    }
    if (poses > 0) {
      const double rmse = std::sqrt(sum_sq / static_cast<double>(poses));
      std::printf("ATE_RMSE_M %.5f (SE3-aligned per map, %zu maps, %zu poses)\n", rmse, by_map.size(), poses);
      j["ate"] = {{"rmse_m", rmse}, {"poses", poses}, {"per_map", per_map}};
    }
    std::printf("DRIFT_M %.5f (largest distance from the first tracked position of its map)\n", drift_m);
    j["drift_m"] = drift_m;
    return;
  }
  // Drift: the largest distance of a tracked position from the first one (for sequences where the camera stands
  // still, e.g. simulator scene1 and the EuRoC excerpt).
  double drift_m = 0;
  for (const auto& p : trajectory)
    drift_m = std::max(drift_m, (p.T_w_c.translation() - trajectory.front().T_w_c.translation()).norm());
  if (gt && !trajectory.empty()) {
    const auto pairs = agvslam::eval::associate_by_timestamp(*gt, trajectory, 5'000'000);
    if (pairs.size() >= 3) {
      const auto ate = agvslam::eval::compute_ate(pairs, agvslam::eval::AlignMode::kSE3);
      const std::vector<agvslam::SE3d>& gt_poses = pairs.T_w_c_gt;
      double gt_motion_m = 0;
      for (const auto& T : gt_poses)
        gt_motion_m = std::max(gt_motion_m, (T.translation() - gt_poses.front().translation()).norm());
      std::printf("ATE_RMSE_M %.5f (SE3-aligned, %zu poses, ground-truth path %.2f m)\n", ate.translation_m.rmse,
                  ate.translation_m.count, agvslam::eval::path_length_m(gt_poses));
      j["ate"] = {{"rmse_m", ate.translation_m.rmse},
                  {"mean_m", ate.translation_m.mean},
                  {"max_m", ate.translation_m.max},
                  {"poses", ate.translation_m.count},
                  {"gt_path_m", agvslam::eval::path_length_m(gt_poses)},
                  {"gt_max_displacement_m", gt_motion_m}};
    }
  }
  std::printf("DRIFT_M %.5f (largest distance from the first tracked position)\n", drift_m);
  j["drift_m"] = drift_m;
}

// MOVING_INLIERS line; j["moving_inliers"].
void report_moving_inliers(const FrameLog& log, nlohmann::json& j) {
  if (log.moving_inlier_fraction.empty()) return;
  Series f;
  for (double x : log.moving_inlier_fraction) f.add(x);
  const double mean =
      log.inliers_total ? static_cast<double>(log.moving_inliers_total) / static_cast<double>(log.inliers_total) : 0;
  const auto over10 =
      static_cast<std::size_t>(std::count_if(f.values().begin(), f.values().end(), [](double x) { return x > 0.10; }));
  std::printf(
      "MOVING_INLIERS %.4f (of the pose inliers on ground-truth moving objects; p95 %.4f, max %.4f, %zu of %zu "
      "frames over 10%%)\n",
      mean, f.quantile(0.95), f.max(), over10, f.count());
  j["moving_inliers"] = {{"fraction", mean},           {"p95_fraction", f.quantile(0.95)},
                         {"max_fraction", f.max()},    {"frames_over_10pct", over10},
                         {"frames_scored", f.count()}, {"total", log.moving_inliers_total}};
}

// MAP_FRAME_ATE_M line (positions in the saved map's frame, without alignment); j["map_frame_ate"].
void report_map_frame_accuracy(const agvslam::Trajectory& trajectory, const std::optional<agvslam::Trajectory>& gt,
                               const agvslam::SE3d& T_w1_w2, nlohmann::json& j) {
  if (!gt || trajectory.empty()) return;
  agvslam::Trajectory gt_map;
  for (const auto& p : *gt) gt_map.push_back({p.t_ns, T_w1_w2 * p.T_w_c});
  const auto pairs = agvslam::eval::associate_by_timestamp(gt_map, trajectory, 5'000'000);
  if (pairs.size() < 1) return;
  const auto ate = agvslam::eval::compute_ate(pairs, agvslam::eval::AlignMode::kNone);
  std::printf("MAP_FRAME_ATE_M %.5f (no alignment, %zu poses, max %.4f m)\n", ate.translation_m.rmse,
              ate.translation_m.count, ate.translation_m.max);
  j["map_frame_ate"] = {
      {"rmse_m", ate.translation_m.rmse}, {"max_m", ate.translation_m.max}, {"poses", ate.translation_m.count}};
}

// LOOPS line; returns the loops as JSON.
nlohmann::json report_loops(const slam::LoopClosingStats& lstats) {
  std::printf("LOOPS %llu", static_cast<unsigned long long>(lstats.loops_closed));
  nlohmann::json loops_json = nlohmann::json::array();
  for (const slam::LoopEvent& e : lstats.loops) {
    std::printf("  [kf %llu -> %llu, frame %llu -> %llu, %d matches, moved %.3f m %.2f deg]",
                static_cast<unsigned long long>(e.keyframe_id), static_cast<unsigned long long>(e.loop_keyframe_id),
                static_cast<unsigned long long>(e.frame_id), static_cast<unsigned long long>(e.loop_frame_id),
                e.total_matches, e.correction_m, e.correction_deg);
    loops_json.push_back({{"keyframe", e.keyframe_id},
                          {"loop_keyframe", e.loop_keyframe_id},
                          {"frame", e.frame_id},
                          {"loop_frame", e.loop_frame_id},
                          {"t_ns", e.t_ns},
                          {"bow_matches", e.bow_matches},
                          {"ransac_inliers", e.ransac_inliers},
                          {"refined_inliers", e.refined_inliers},
                          {"total_matches", e.total_matches},
                          {"correction_m", e.correction_m},
                          {"correction_deg", e.correction_deg},
                          {"fused_points", e.fused_points},
                          {"graph_keyframes", e.graph_keyframes},
                          {"graph_edges", e.graph_edges},
                          {"detect_ms", e.detect_ms},
                          {"correct_ms", e.correct_ms},
                          {"pose_graph_ms", e.pose_graph_ms},
                          {"global_ba_ms", e.global_ba_ms},
                          {"global_ba_merge_ms", e.global_ba_merge_ms}});
  }
  std::printf("\n");
  return loops_json;
}

// RELOCALISATION, laps and counts lines.
void report_counts(const Options& o, const Settings& s, const FrameLog& log, const SlamResults& results) {
  std::printf("RELOCALISATION first_tracked %ld", log.first_tracked);
  if (s.blank) std::printf(" blank_recovered_after %ld", log.blank_recovered_after);
  std::printf("\n");
  if (o.repeat > 1) {
    std::printf("laps:");
    for (std::size_t k = 0; k < log.laps_keyframes.size(); ++k) {
      std::printf(" [%zu: %zu keyframes, %zu map points]", k + 1, log.laps_keyframes[k], log.laps_points[k]);
    }
    std::printf("\n");
  }
  const slam::LocalMappingStats& m = results.mapping;
  const slam::MapCounts& map = results.map_counts;
  std::printf(
      "counts: %zu frames, %zu tracked, %zu lost, %zu recovered, %zu resets; %zu keyframes, %zu map points "
      "(%.1f MB); mapping: %llu keyframes processed, %llu skipped (queue full), max queue %zu, %llu culled "
      "keyframes, %llu created / %llu culled points; retired points (moved objects): %llu mask, %llu absent\n",
      log.frames, log.tracked, log.lost, log.recovered, log.resets, map.keyframes, map.map_points,
      static_cast<double>(map.memory_bytes) / 1e6, static_cast<unsigned long long>(m.keyframes_processed),
      static_cast<unsigned long long>(m.keyframes_skipped), log.max_queue,
      static_cast<unsigned long long>(m.keyframes_culled), static_cast<unsigned long long>(m.points_created),
      static_cast<unsigned long long>(m.points_culled), static_cast<unsigned long long>(results.retired.mask),
      static_cast<unsigned long long>(results.retired.absent));
}

// Local mapping's per-keyframe times (ms) by step.
std::map<std::string, Series> mapping_series(const std::vector<slam::KeyframeMappingTimes>& history) {
  std::map<std::string, Series> series;
  for (const auto& h : history) {
    series["insert"].add(h.insert_ms);
    series["point_culling"].add(h.culling_ms);
    series["triangulation"].add(h.triangulation_ms);
    series["fusion"].add(h.fusion_ms);
    series["local_ba"].add(h.ba_ms);
    series["keyframe_culling"].add(h.kf_culling_ms);
    series["total"].add(h.total_ms);
  }
  return series;
}

// The timing tables; the mapping table's rows are added to `mapping` (as zeros when no keyframe was mapped).
void report_timings(const FrameLog& log, std::map<std::string, Series>& mapping, double run_s) {
  std::printf("time per frame [ms]   median      p95      max\n");
  for (const char* name : FrameLog::kStageOrder) {
    const auto it = log.series.find(name);
    if (it == log.series.end() || it->second.empty()) continue;
    std::printf("  %-16s %9.2f %8.2f %8.2f\n", name, it->second.median(), it->second.quantile(0.95), it->second.max());
  }
  std::printf("time per keyframe (local mapping) [ms]   median      p95      max\n");
  for (const char* name : {"triangulation", "fusion", "local_ba", "total"}) {
    const Series& s = mapping[name];
    std::printf("  %-16s %9.2f %8.2f %8.2f\n", name, s.median(), s.quantile(0.95), s.max());
  }
  std::printf("wall time %.1f s, %.1f frames/s\n", run_s, run_s > 0 ? static_cast<double>(log.frames) / run_s : 0.0);
}

// The --json statistics, added to what the reports put into j.
void write_json(const Options& o, const Input& in, const FrameLog& log, const SlamResults& results,
                const std::map<std::string, Series>& mapping, const nlohmann::json& loops_json, double run_s,
                nlohmann::json& j) {
  const slam::LocalMappingStats& m = results.mapping;
  const slam::LoopClosingStats& l = results.loops;
  const slam::MapCounts& map = results.map_counts;
  j["dataset"] = in.setup.dataset->root();
  j["dynamic"] = o.dynamic;
  j["semantic"] = o.semantic;
  j["mapping"] = o.mapping;
  j["speed"] = o.speed;
  j["frames"] = {{"first", in.setup.first},
                 {"last", in.setup.last},
                 {"processed", log.frames},
                 {"tracked", log.tracked},
                 {"lost", log.lost},
                 {"recovered", log.recovered},
                 {"resets", log.resets},
                 {"skipped_unreadable", results.skipped_frames},
                 {"new_maps", log.new_maps},
                 {"last_state", log.last_state},
                 {"keyframe_waits", log.keyframe_waits}};
  j["earlier_map_files"] = results.earlier_map_files;
  j["loops"] = loops_json;
  j["loop_closing"] = {{"enabled", o.loop == "on"},
                       {"keyframes_processed", l.keyframes_processed},
                       {"keyframes_dropped", l.keyframes_dropped},
                       {"consistent_detections", l.consistent_detections},
                       {"rejected_geometry", l.rejected_geometry},
                       {"rejected_correction", l.rejected_correction},
                       {"loops_closed", l.loops_closed},
                       {"global_ba_runs", l.global_ba_runs},
                       {"global_ba_aborted", l.global_ba_aborted}};
  j["relocalisation"] = {{"first_tracked", log.first_tracked}, {"blank_recovered_after", log.blank_recovered_after}};
  if (!results.load_map.is_null()) j["load_map"] = results.load_map;
  if (!results.save_map.is_null()) j["save_map"] = results.save_map;
  if (o.repeat > 1) j["laps"] = {{"keyframes", log.laps_keyframes}, {"map_points", log.laps_points}};
  j["map"] = {{"keyframes", map.keyframes},
              {"map_points", map.map_points},
              {"observations", map.observations},
              {"memory_bytes", map.memory_bytes}};
  j["retired_points"] = {{"mask", results.retired.mask}, {"absent", results.retired.absent}};
  j["local_mapping"] = {{"keyframes_processed", m.keyframes_processed},
                        {"keyframes_skipped", m.keyframes_skipped},
                        {"keyframes_culled", m.keyframes_culled},
                        {"points_created", m.points_created},
                        {"points_fused", m.points_fused},
                        {"points_culled", m.points_culled},
                        {"ba_runs", m.ba_runs},
                        {"ba_aborted", m.ba_aborted},
                        {"ba_outliers", m.ba_outliers},
                        {"max_queue", log.max_queue}};
  nlohmann::json jt, jm;
  for (const auto& [name, s] : log.series) jt[name] = timing_json(s);
  for (const auto& [name, s] : mapping) jm[name] = timing_json(s);
  j["timings"] = jt;
  j["mapping_timings"] = jm;
  j["wall_s"] = run_s;
  j["per_frame"] = log.per_frame;
  agvslam::io::write_file_atomically(o.json, j.dump(1) + "\n");
}

int run(const Options& o) {
  const Settings s = check_options(o);
  cv::setNumThreads(o.opencv_threads);
  const Input in = open_input(o, s);

  FrameLog log(o.mapping == "inline", in.setup.last,
               (in.setup.last - in.setup.first + 1) * static_cast<std::size_t>(o.repeat));
  SlamResults results;
  if (!play(o, s, in, log, results)) return 1;
  const double run_s = log.finish();

  write_trajectory(o, s, results.trajectory, log.frames);
  std::printf("FRAMES %zu TRACKED %zu KEYFRAMES %zu LOST %zu\n", log.frames, log.tracked, log.keyframes, log.lost);
  nlohmann::json j;
  const std::optional<agvslam::Trajectory> gt = played_ground_truth(o, in.setup);
  report_accuracy(results.trajectory, results.trajectory_map_ids, gt, j);
  std::printf("MAPS %zu (new maps after a long loss: %zu) LAST_STATE %s KEYFRAME_WAITS %zu\n", log.new_maps + 1,
              log.new_maps, log.last_state.c_str(), log.keyframe_waits);
  report_moving_inliers(log, j);
  if (in.T_w1_w2) report_map_frame_accuracy(results.trajectory, gt, *in.T_w1_w2, j);
  const nlohmann::json loops_json = report_loops(results.loops);
  report_counts(o, s, log, results);
  std::map<std::string, Series> mapping = mapping_series(results.mapping_history);
  report_timings(log, mapping, run_s);
  if (!o.json.empty()) write_json(o, in, log, results, mapping, loops_json, run_s, j);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the FRAMES line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-run"));
  CLI::App app{"agvslam-run: stereo SLAM with dynamic-region removal (paper 004) over a dataset folder"};
  Options o;
  app.add_option("--dataset", o.dataset,
                 "sequence folder: KITTI layout (also agvslam-sim output), EuRoC ASL, or a rosbag2 recording "
                 "(BAG or 'BAG?left=TOPIC&right=TOPIC&odom=TOPIC', agvslam/io/rosbag_dataset.h)")
      ->required();
  app.add_option("--out", o.out, "trajectory file to write (every tracked frame)")->required();
  app.add_option("--calib", o.calib,
                 "calibration file instead of the dataset's own (KITTI calib.txt, ORB-SLAM YAML, Kalibr)");
  app.add_option("--format", o.format, "trajectory format: tum (default) or kitti");
  app.add_option("--dynamic", o.dynamic, "dynamic regions: detector (default), gt (dataset masks) or off");
  app.add_option("--json", o.json, "statistics file (timings, counts, per-frame records)");
  app.add_option("--frames", o.frames, "inclusive frame range A:B (either side may be empty)");
  app.add_option("--params-slam", o.params_slam, "params/slam.yaml");
  app.add_option("--params-features", o.params_features, "params/features.yaml");
  app.add_option("--params-dynamic", o.params_dynamic, "params/dynamic.yaml (with --dynamic detector)");
  app.add_option("--params-stereo", o.params_stereo, "params/stereo.yaml (with --dynamic detector)");
  app.add_option("--semantic", o.semantic,
                 "segmentation model (ONNX) whose moving objects join the detector's mask, or off (default)");
  app.add_option("--params-semantic", o.params_semantic, "params/semantic.yaml (with --semantic MODEL)");
  app.add_option("--mapping", o.mapping,
                 "local mapping: thread (default, as on the vehicle) or inline (deterministic)");
  app.add_option("--speed", o.speed,
                 "feed frames at this multiple of the dataset rate (0, default: as fast as possible)");
  app.add_option("--opencv-threads", o.opencv_threads,
                 "OpenCV's threads inside a stage (default 1: one core per thread)");
  app.add_option("--params-place", o.params_place, "params/place.yaml (the vocabulary; default: the source tree's)");
  app.add_option("--loop", o.loop, "loop closing: on (default) or off");
  app.add_option("--save-map", o.save_map, "write the final map to this file (atomically)");
  app.add_option("--load-map", o.load_map, "start in this saved map (needs --mode)");
  app.add_option("--mode", o.mode, "with --load-map: localise (track without changing the map) or map (extend it)");
  app.add_option("--blank", o.blank, "black out frames A:B (inclusive): a covered camera, forced loss");
  app.add_option("--repeat", o.repeat, "play the frame range this many times in a row (laps of a loop)");
  app.add_option("--save-earlier-maps", o.save_earlier_maps,
                 "folder: a map left behind after a long loss is saved there as map_<map_id>.agvmap");
  app.add_option("--test-slow-mapping-ms", o.test_slow_mapping_ms,
                 "TEST ONLY: local mapping sleeps this long (ms) after each of its steps, as on a slower computer");
  app.add_option("--map-dataset", o.map_dataset,
                 "with --load-map on simulator folders: the folder the map was made from (MAP_FRAME_ATE_M)");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
