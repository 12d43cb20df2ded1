// agvslamd: the onboard daemon. A V4L2 stereo camera (or a dataset played like one) in; the base_link pose in
// the map frame out over Cyclone DDS (ROS 2 types and topics), SocketCAN (deploy/agvslam.dbc) and a trajectory
// file; systemd notification (Type=notify) and watchdog.
//
//   agvslamd --config params/agvslamd.yaml [--check] [--json STATS]
//
// Every setting is echoed at start-up; a bad setting stops it before anything is opened (exit 2, the message
// names the file, the field and what was expected). --check validates the configuration and the files it names
// (stage params, calibration, dataset) and exits 0.
//
// Threads and queues: see include/agvslam/daemon/pipeline.h. The main thread only supervises: it waits for
// signals, sends READY=1 (after the first frame went through, or systemd.ready_timeout_s without one: a vehicle
// booting with its camera unplugged still gets a running daemon that reports state lost) and STATUS= once a
// second; the processing (tracking) loop sends WATCHDOG=1 while every pipeline loop turns.
// SIGTERM / SIGINT: STOPPING=1, stop capturing, process and publish what was captured, close the devices, flush
// the trajectory, save the map atomically (map.file in mapping mode), exit 0. SIGHUP: reopen the log file
// (logrotate). A dataset played once ends the daemon (exit 0, the map saved) after its last frame is published.
// --json writes the run's statistics (counts, latency and stage times: median, p99, max) at exit.
// Exit status: 0 stopped cleanly, 2 bad configuration, 1 any other failure (a device or output that failed).

#include <pthread.h>
#include <signal.h>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <ctime>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "agvslam/core/error.h"
#include "agvslam/daemon/daemon_config.h"
#include "agvslam/daemon/frame_source.h"
#include "agvslam/daemon/log_setup.h"
#include "agvslam/daemon/pipeline.h"
#include "agvslam/daemon/systemd_notifier.h"
#include "agvslam/drivers/v4l2/device.h"
#include "agvslam/io/trajectory_io.h"
#include "tool_main.h"

namespace {

namespace daemon = agvslam::daemon;
using agvslam::InputError;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string config;
  bool check = false;
  std::string json;
};

nlohmann::json stats_json(const daemon::PipelineStats& s, double run_s) {
  return {{"run_s", run_s},
          {"captured", s.captured},
          {"processed", s.processed},
          {"tracked", s.tracked},
          {"lost", s.lost},
          {"dropped_queue", s.dropped_queue},
          {"dropped_source", s.dropped_source},
          {"dropped_outputs", s.dropped_outputs},
          {"published", s.published},
          {"heartbeats", s.heartbeats},
          {"keyframes", s.keyframes},
          {"map_points", s.map_points},
          {"latency_ms", {{"median", s.latency_p50_ms}, {"p99", s.latency_p99_ms}, {"max", s.latency_max_ms}}},
          {"tracking_ms", {{"median", s.tracking_p50_ms}, {"p99", s.tracking_p99_ms}}},
          {"detector_ms", {{"median", s.detector_p50_ms}}},
          {"source",
           {{"frames", s.source.frames},
            {"losses", s.source.losses},
            {"reopens", s.source.reopens},
            {"connected", s.source.connected},
            {"line", s.source.line}}},
          {"dds",
           {{"pose_published", s.outputs.dds_pose.published},
            {"pose_dropped", s.outputs.dds_pose.dropped_queue_full},
            {"status_published", s.outputs.dds_status.published},
            {"write_errors", s.outputs.dds_pose.write_errors + s.outputs.dds_status.write_errors}}},
          {"can",
           {{"enabled", s.outputs.can_enabled},
            {"cycles", s.outputs.can.cycles},
            {"cycles_sent", s.outputs.can.cycles_sent},
            {"frames_sent", s.outputs.can.frames_sent},
            {"dropped_down", s.outputs.can.frames_dropped_down},
            {"dropped_no_buffer", s.outputs.can.frames_dropped_no_buffer},
            {"reopens", s.outputs.can.reopens},
            {"last_error", s.outputs.can_last_error}}},
          {"odometry",
           {{"enabled", s.outputs.odometry_enabled},
            {"samples", s.outputs.odometry_samples},
            {"can_frames", s.outputs.can_odometry.frames},
            {"crc_bad", s.outputs.can_odometry.crc_bad},
            {"counter_repeated", s.outputs.can_odometry.counter_repeated},
            {"counter_gaps", s.outputs.can_odometry.counter_gaps},
            {"disagreements", s.outputs.odometry_disagreements},
            {"check", daemon::odometry_check_json(s.outputs.odometry_check)}}}};
}

// Signals: blocked in every thread (the pipeline's, Cyclone's) and taken by the main thread with sigtimedwait.
sigset_t block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

std::unique_ptr<daemon::FrameSource> open_source(const daemon::SourceSetup& setup, const daemon::DaemonConfig& config) {
  try {
    return daemon::make_frame_source(setup, config);
  } catch (const agvslam::drivers::v4l2::V4l2Error& e) {
    if (e.configuration()) throw InputError(config.path, "camera", e.what());
    throw;
  }
}

// Why the daemon stops, and with which exit status.
struct StopReason {
  std::string text = "end of the dataset";
  int exit_code = 0;
};

// The main thread while the pipeline runs: signals (SIGTERM / SIGINT stop, SIGHUP reopens the log), READY=1,
// STATUS= once a second and the periodic statistics line, until a stop signal, a failure or the dataset's end.
StopReason supervise(const daemon::DaemonConfig& config, const sigset_t& signals, daemon::Pipeline& pipeline,
                     daemon::SystemdNotifier& notifier, const std::shared_ptr<daemon::ReopenableFileSink>& log_file,
                     Clock::time_point t_start) {
  bool ready = false;
  if (config.systemd.ready == daemon::ReadyWhen::kStartup) {
    notifier.ready("started, waiting for frames");
    ready = true;
  }
  auto last_status = Clock::now();
  auto last_stats_log = Clock::now();
  for (;;) {
    timespec wait{0, 200 * 1000 * 1000};
    const int sig = sigtimedwait(&signals, nullptr, &wait);
    if (sig == SIGTERM || sig == SIGINT) return {sig == SIGTERM ? "SIGTERM" : "SIGINT", 0};
    if (sig == SIGHUP) {
      if (log_file) {
        const bool ok = log_file->reopen();
        spdlog::info("agvslamd: SIGHUP: log file {} {}", log_file->path(), ok ? "reopened" : "could not be reopened");
      } else {
        spdlog::info("agvslamd: SIGHUP: no log file to reopen (log.file not set)");
      }
    }
    if (pipeline.failed()) return {"failure: " + pipeline.error(), 1};
    if (pipeline.finished()) return {};
    const auto now = Clock::now();
    if (!ready) {
      const bool waited = now - t_start >= std::chrono::duration<double>(config.systemd.ready_timeout_s);
      if (pipeline.frames_published() > 0 || waited) {
        const std::string why =
            pipeline.frames_published() > 0
                ? "first frame processed"
                : "no frame yet after " + std::to_string(config.systemd.ready_timeout_s) + " s, reporting state lost";
        notifier.ready(why + "; " + pipeline.stats().one_line());
        spdlog::info("agvslamd: ready ({})", why);
        ready = true;
      }
    }
    if (ready && now - last_status >= std::chrono::seconds(1)) {
      notifier.status(pipeline.stats().one_line());
      last_status = now;
    }
    if (config.log.stats_every_s > 0 &&
        now - last_stats_log >= std::chrono::duration<double>(config.log.stats_every_s)) {
      spdlog::info("status: {}", pipeline.stats().one_line());
      last_stats_log = now;
    }
  }
}

// Saves the map (mapping mode); false when it could not be written.
bool save_map(const daemon::DaemonConfig& config, daemon::Pipeline& pipeline) {
  try {
    const auto saved = pipeline.save_map();
    if (saved) {
      spdlog::info("agvslamd: map saved to {} ({} keyframes, {} map points, {} bytes; {:.0f} ms)", config.map.file,
                   saved->keyframes, saved->map_points, saved->bytes,
                   saved->wait_ms + saved->encode_ms + saved->write_ms);
      std::printf("MAP_SAVED %s KEYFRAMES %zu MAP_POINTS %zu BYTES %zu\n", config.map.file.c_str(), saved->keyframes,
                  saved->map_points, saved->bytes);
    }
    return true;
  } catch (const std::exception& e) {
    // The previous map file is intact (written to a temporary file, renamed only when complete).
    spdlog::error("agvslamd: the map could not be saved ({}); the previous file {} is unchanged", e.what(),
                  config.map.file);
    return false;
  }
}

// The FRAMES line and --json.
void report(const Options& o, const daemon::PipelineStats& st, double run_s, const std::string& stop_reason) {
  spdlog::info("agvslamd: stopped after {:.1f} s: {}", run_s, st.one_line());
  std::printf(
      "FRAMES %llu TRACKED %llu LOST %llu DROPPED %llu PUBLISHED %llu LATENCY_P50_MS %.2f LATENCY_P99_MS %.2f\n",
      static_cast<unsigned long long>(st.processed), static_cast<unsigned long long>(st.tracked),
      static_cast<unsigned long long>(st.lost), static_cast<unsigned long long>(st.dropped_queue + st.dropped_source),
      static_cast<unsigned long long>(st.published), st.latency_p50_ms, st.latency_p99_ms);
  std::fflush(stdout);
  if (!o.json.empty()) {
    nlohmann::json j = stats_json(st, run_s);
    j["stop_reason"] = stop_reason;
    agvslam::io::write_file_atomically(o.json, j.dump(1) + "\n");
  }
}

int run(const Options& o) {
  const sigset_t signals = block_stop_signals();
  const daemon::DaemonConfig config = daemon::load_daemon_config(o.config);
  const daemon::SourceSetup setup = daemon::prepare_source(config);
  const auto log_file = daemon::setup_logging(config.log.file, config.log.level, config.path);
  spdlog::info("agvslamd: configuration {}", config.path);
  for (const auto& line : config.describe()) spdlog::info("  {}", line);
  spdlog::info("  source: {}", setup.summary);
  spdlog::info("  SLAM frame rate {:.2f} Hz", setup.slam_rate_hz);
  if (o.check) {
    spdlog::info("agvslamd: configuration OK (--check)");
    std::printf("CONFIG OK %s\n", config.path.c_str());
    return 0;
  }

  cv::setNumThreads(config.pipeline.opencv_threads);
  daemon::SystemdNotifier notifier;
  spdlog::info("  systemd: notify socket {}, watchdog {}", notifier.enabled() ? "set" : "not set (run by hand)",
               notifier.watchdog_interval().count() > 0
                   ? std::to_string(notifier.watchdog_interval().count() / 1000) + " ms"
                   : std::string("off"));
  daemon::Pipeline pipeline(config, setup, open_source(setup, config));
  // Watchdog from the processing loop, only while every loop of the pipeline turns.
  const auto max_age =
      std::max(std::chrono::milliseconds(1000),
               std::chrono::duration_cast<std::chrono::milliseconds>(notifier.watchdog_interval() / 2));
  pipeline.set_processing_hook([&pipeline, &notifier, max_age] {
    if (pipeline.alive(max_age)) notifier.watchdog();
  });
  const auto t_start = Clock::now();
  pipeline.start();
  spdlog::info("agvslamd: running");
  StopReason stop = supervise(config, signals, pipeline, notifier, log_file, t_start);

  spdlog::info("agvslamd: stopping ({})", stop.text);
  notifier.stopping("stopping: " + stop.text);
  pipeline.request_stop();
  pipeline.wait();
  if (!save_map(config, pipeline)) stop.exit_code = 1;
  report(o, pipeline.stats(), std::chrono::duration<double>(Clock::now() - t_start).count(), stop.text);
  if (pipeline.failed() && stop.exit_code == 0) stop.exit_code = 1;
  return stop.exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  daemon::setup_logging("", "info", "agvslamd");
  CLI::App app{"agvslamd: stereo visual SLAM daemon for AGVs (V4L2 in, DDS / CAN out, systemd)"};
  Options o;
  app.add_option("--config", o.config, "the daemon's YAML file (params/agvslamd.yaml)")->required();
  app.add_flag("--check", o.check, "validate the configuration and the files it names, then exit");
  app.add_option("--json", o.json, "write the run's statistics to this JSON file at exit");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
