// agvslam-sim: renders a synthetic stereo warehouse sequence with moving people and vehicles.
//
//   agvslam-sim --scenario NAME --out DIR [--frames N] [--squeeze-to N] [--seed S] [--layout-seed L]
//               [--start-offset M] [--params params/sim.yaml] [--threads N]
//   agvslam-sim --list
//
// Writes the KITTI layout (image_0/ image_1/ calib.txt times.txt poses.txt) plus disp_0/ (16-bit disparity*256),
// mask_0/ (255 = moving object), instance_0/ (the actor id seen at each pixel, 0 = none), class_0/ (the semantic
// class of each pixel, agvslam/sim/semantic_classes.h), objects.txt and scenario.json (what was generated, with
// its seeds, and the class ids).
// --frames N writes the first N frames of the scenario's timeline at its own speed; --squeeze-to N plays the whole
// timeline over N frames (faster or slower; --frames then cuts that).
// The output is identical for any --threads. Exit status: 0 on success, 2 on bad input (the message names the
// option, file or folder), 1 on any other failure.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "agvslam/core/error.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/sim/semantic_classes.h"
#include "agvslam/sim/sim_config.h"
#include "agvslam/sim/simulator.h"
#include "tool_main.h"

namespace {

using agvslam::InputError;
namespace sim = agvslam::sim;

struct Options {
  std::string scenario, out_dir, params_path;
  int frames = 0;
  bool frames_given = false;
  int squeeze_to = 0;
  bool squeeze_given = false;
  uint64_t seed = 1;
  uint64_t layout_seed = 0;
  bool layout_seed_given = false;
  double start_offset_m = 0;
  int threads = 1;
};

nlohmann::json describe(const sim::Simulator& s) {
  const sim::Scenario& sc = s.scenario();
  nlohmann::json j;
  j["scenario"] = sc.name;
  j["description"] = sc.description;
  j["seed"] = sc.seed;
  j["layout_seed"] = sc.layout_seed;
  j["start_offset_m"] = sc.start_offset_m;
  j["frames"] = sc.frames;
  j["timeline_frames"] = sc.timeline_frames;  // the whole timeline is played over these (--squeeze-to)
  j["speed_factor"] = 1.0 / sc.time_scale;    // 1: the scenario's own speed
  j["rate_hz"] = sc.rate_hz;
  j["duration_s"] = sc.frames / sc.rate_hz;
  j["agv"] = {{"stationary", sc.agv.stationary},
              {"path_length_m", sc.agv_path_length_m()},
              {"cruise_speed_mps", sc.agv_speed_mps()}};
  nlohmann::json actors = nlohmann::json::array();
  for (const auto& a : sc.actors) {
    nlohmann::json moving = nlohmann::json::array();  // [first, last] frames (inclusive) while it moves
    for (const auto& [first, last] : s.moving_frames(a)) moving.push_back({first, last});
    actors.push_back({{"id", a.id}, {"class", sim::to_string(a.cls)}, {"role", a.role}, {"moving_frames", moving}});
  }
  j["actors"] = actors;
  j["min_camera_clearance_m"] = sc.actors.empty() ? nlohmann::json(nullptr) : nlohmann::json(sc.min_camera_clearance_m);
  const sim::SimConfig& c = s.config();
  j["camera"] = {{"width", c.width},
                 {"height", c.height},
                 {"fx", c.fx},
                 {"fy", c.fy_px()},
                 {"cx", c.cx_px()},
                 {"cy", c.cy_px()},
                 {"baseline_m", c.baseline_m},
                 {"height_above_floor_m", c.camera_height_m}};
  j["conventions"] =
      "poses.txt: T_w_cam0 (world = left camera at frame 0; camera x right, y down, z forward); "
      "disp_0: uint16 disparity*256 of the left image, 0 = none; mask_0: 255 = moving object; "
      "instance_0: uint8 actor id (objects.txt) of each pixel, 0 = none; class_0: uint8 class id "
      "(classes) of each pixel";
  nlohmann::json classes = nlohmann::json::array();
  for (int id = 0; id < sim::kSemanticClassCount; ++id)
    classes.push_back({{"id", id}, {"name", sim::semantic_class_name(static_cast<sim::SemanticClass>(id))}});
  j["classes"] = classes;
  return j;
}

int run(const Options& o) {
  if (o.frames_given && o.frames <= 0)
    throw InputError("--frames", std::to_string(o.frames), "expected a number of frames > 0");
  if (o.squeeze_given && o.squeeze_to <= 0)
    throw InputError("--squeeze-to", std::to_string(o.squeeze_to), "expected a number of frames > 0");
  if (o.threads < 1 || o.threads > 256)
    throw InputError("--threads", std::to_string(o.threads), "expected a thread count in [1, 256]");
  sim::find_scenario(o.scenario);  // fail early on an unknown name
  sim::prepare_output_dir(o.out_dir, "--out");

  sim::SimConfig config;
  if (!o.params_path.empty()) config = sim::load_sim_config(o.params_path);
  spdlog::info("agvslam-sim: settings{}", o.params_path.empty() ? " (built-in defaults)" : " from " + o.params_path);
  for (const auto& line : config.describe()) spdlog::info("  {}", line);

  sim::ScenarioOptions so;
  so.name = o.scenario;
  so.frames = o.frames_given ? o.frames : 0;
  so.squeeze_to_frames = o.squeeze_given ? o.squeeze_to : 0;
  so.seed = o.seed;
  if (o.layout_seed_given) so.layout_seed = o.layout_seed;
  so.start_offset_m = o.start_offset_m;

  const auto t0 = std::chrono::steady_clock::now();
  const sim::Simulator simulator(config, so);
  const sim::Scenario& sc = simulator.scenario();
  if (sc.frames > sc.timeline_frames)
    throw InputError("--frames", std::to_string(sc.frames),
                     "expected at most " + std::to_string(sc.timeline_frames) + " frames (" + sc.name +
                         "'s whole timeline" + (o.squeeze_given ? " as squeezed" : " at its own speed") +
                         "; --squeeze-to plays it over more frames)");
  spdlog::info("scenario {}: {}", sc.name, sc.description);
  spdlog::info("  seed {}, layout seed {}, start offset {:.2f} m, {} frames at {:.1f} Hz ({:.2f} s){}", sc.seed,
               sc.layout_seed, sc.start_offset_m, sc.frames, sc.rate_hz, sc.frames / sc.rate_hz,
               sc.frames == sc.timeline_frames ? " (the whole timeline)" : " (the start of the timeline)");
  if (sc.agv.stationary) {
    spdlog::info("  AGV speed: 0.00 m/s (stationary)");
  } else {
    spdlog::info("  AGV speed: {:.3f} m/s cruise over a {:.2f} m path (timeline played x{:.3f} its own speed)",
                 sc.agv_speed_mps(), sc.agv_path_length_m(), 1.0 / sc.time_scale);
    if (sc.agv_speed_mps() > 2.5)
      spdlog::warn("  the AGV drives unusually fast ({:.2f} m/s) for so few frames", sc.agv_speed_mps());
  }
  for (const auto& a : sc.actors) spdlog::info("  actor {}: {} ({})", a.id, sim::to_string(a.cls), a.role);
  if (!sc.actors.empty())
    spdlog::info("  closest approach of an actor to the camera: {:.2f} m", sc.min_camera_clearance_m);
  spdlog::info("  warehouse: {} boxes, rendering with {} thread(s) into {}", simulator.warehouse().boxes.size(),
               o.threads, o.out_dir);

  sim::WriteOptions wo;
  wo.threads = o.threads;
  const int step = std::max(1, sc.frames / 10);
  wo.progress = [&](int done, int total) {
    if (done % step != 0 && done != total) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("  frame {}/{} ({:.0f} %), {:.1f} s, {:.1f} frames/s", done, total, 100.0 * done / total, s, done / s);
  };
  sim::write_sequence(simulator, o.out_dir, wo);
  agvslam::io::write_file_atomically((std::filesystem::path(o.out_dir) / "scenario.json").string(),
                                     describe(simulator).dump(2) + "\n");
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  spdlog::info("done: {} frames in {:.2f} s ({:.1f} ms/frame) -> {}", sc.frames, total_s, 1000.0 * total_s / sc.frames,
               o.out_dir);
  return 0;
}

void list_scenarios() {
  for (const auto& s : sim::scenario_catalogue())
    std::printf("%-8s %5.0f frames at 20 Hz  %s\n", s.name.c_str(), s.nominal_duration_s * 20.0, s.description.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries --list.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-sim"));
  CLI::App app{"agvslam-sim: synthetic stereo warehouse sequences (KITTI layout + disparity, motion mask, objects)"};
  Options o;
  bool list = false;
  std::string names;
  for (const auto& s : sim::scenario_catalogue()) names += (names.empty() ? "" : "|") + s.name;
  app.add_option("--scenario", o.scenario, "scenario: " + names);
  app.add_option("--out", o.out_dir, "output folder (created if missing)");
  app.add_option("--frames", o.frames,
                 "write the first N frames of the scenario's timeline, at its own speed (default: all of it)");
  app.add_option("--squeeze-to", o.squeeze_to,
                 "play the whole timeline over N frames, faster or slower than its own speed (--frames cuts that)");
  app.add_option("--seed", o.seed, "seed of the people/vehicles, sensor noise (and of the layout by default)")
      ->capture_default_str();
  app.add_option("--layout-seed", o.layout_seed, "seed of the warehouse layout and textures (default: --seed)");
  app.add_option("--start-offset", o.start_offset_m,
                 "AGV start along its route in metres (loop: any, wraps; aisle: 0..3; scene1: sideways -2..2)")
      ->capture_default_str();
  app.add_option("--params", o.params_path, "camera/rendering settings (params/sim.yaml)");
  app.add_option("--threads", o.threads, "rendering threads (the output does not depend on it)")->capture_default_str();
  app.add_flag("--list", list, "list the scenarios and exit");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] {
    if (list) {
      list_scenarios();
      return 0;
    }
    o.frames_given = app.count("--frames") > 0;
    o.squeeze_given = app.count("--squeeze-to") > 0;
    o.layout_seed_given = app.count("--layout-seed") > 0;
    if (o.scenario.empty()) throw InputError("--scenario", "", "expected a scenario name: " + names);
    if (o.out_dir.empty()) throw InputError("--out", "", "expected an output folder");
    return run(o);
  });
}
