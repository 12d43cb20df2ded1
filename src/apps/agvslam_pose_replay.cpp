// agvslam-pose-replay: feeds pose samples through the daemon's outputs (DDS and/or CAN) without a camera: a
// deterministic synthetic drive or a TUM trajectory file. Used to check a vehicle's wiring (does the controller
// read the CAN frames, does the ROS 2 stack see the topics) and by the driver tests (it prints exactly what it
// handed to each output).
//
//   agvslam-pose-replay [--synthetic N | --trajectory FILE.tum] [--rate HZ] [--stamp now|source]
//                       [--dds] [--domain N] [--interface NAME] [--namespace NS] [--wait-subscribers N]
//                       [--wait-timeout S] [--sync]
//                       [--can IFACE] [--can-base-id ID] [--can-extended] [--can-fd] [--can-rate HZ]
//                       [--json]
//
// --json prints one line per sample: {"i", "t_ns", "sample": {...SI values...}, "dds": {"pose": msg, "odom":
// msg, "status": msg}, "can": {"due", "sent", "counter", "frames_sent"}}, then {"summary": {...}}.
// --stamp now (default) stamps each sample with CLOCK_REALTIME when it is handed over, so a subscriber on the
// same host measures publish -> receive latency from header.stamp. --sync writes DDS on this thread instead of
// the publisher's thread.
// Exit status: 0 done, 1 no subscriber within --wait-timeout or an output failed to start, 2 bad input.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/can_publisher.h"
#include "agvslam/drivers/dds/publisher.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "agvslam/drivers/pose_sample.h"
#include "agvslam/drivers/pose_sample_json.h"
#include "agvslam/io/trajectory_io.h"
#include "tool_main.h"

namespace {

namespace drv = agvslam::drivers;
namespace dds = agvslam::drivers::dds;
namespace can = agvslam::drivers::can;

struct Options {
  long synthetic = 0;
  std::string trajectory;
  double rate_hz = 20.0;
  std::string stamp = "now";
  bool dds = false;
  int domain = 0;
  std::string interface;
  std::string ns = "agvslam";
  std::string keystore;
  std::string enclave;
  int wait_subscribers = 0;
  double wait_timeout_s = 10.0;
  bool sync = false;
  std::string can_interface;
  std::string can_base_id = "0x300";
  bool can_extended = false;
  bool can_fd = false;
  double can_rate_hz = 0.0;
  bool json = false;
};

uint32_t parse_id(const std::string& text) {
  try {
    std::size_t used = 0;
    const unsigned long v = std::stoul(text, &used, 0);
    if (used == text.size() && v <= 0x1FFFFFFFUL) return static_cast<uint32_t>(v);
  } catch (const std::exception&) {
  }
  throw agvslam::InputError("--can-base-id", text, "expected a CAN id such as 0x300");
}

void check_options(const Options& o) {
  if ((o.synthetic > 0) == !o.trajectory.empty()) {
    throw agvslam::InputError("options", "--synthetic/--trajectory", "expected exactly one of them");
  }
  if (!o.dds && o.can_interface.empty() && !o.json) {
    throw agvslam::InputError("options", "--dds/--can/--json", "expected at least one output");
  }
}

// The DDS publisher (null without --dds); false when the subscribers asked for did not come in time.
bool open_dds(const Options& o, std::unique_ptr<dds::DdsPosePublisher>& pub) {
  if (!o.dds) return true;
  dds::DdsConfig cfg;
  cfg.domain_id = o.domain;
  cfg.network_interface = o.interface;
  cfg.topic_namespace = o.ns;
  cfg.security.enabled = !o.keystore.empty();
  cfg.security.keystore = o.keystore;
  if (!o.enclave.empty()) cfg.security.enclave = o.enclave;
  cfg.validate("agvslam-pose-replay options");
  if (cfg.security.enabled) spdlog::info("agvslam-pose-replay: {}", cfg.security.describe());
  spdlog::info("agvslam-pose-replay: {}{}", cfg.describe(), o.sync ? ", writes on the caller's thread" : "");
  // The replayed pose topics only: tf is one tree per robot, and a replay beside a running daemon must not join it.
  cfg.publish_tf = cfg.publish_tf_static = false;
  pub = std::make_unique<dds::DdsPosePublisher>(cfg, !o.sync);
  if (o.wait_subscribers <= 0) return true;
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(o.wait_timeout_s * 1000));
  if (pub->wait_for_subscribers(o.wait_subscribers, timeout)) return true;
  spdlog::error("agvslam-pose-replay: fewer than {} subscriber(s) on every topic after {} s", o.wait_subscribers,
                o.wait_timeout_s);
  return false;
}

// The CAN publisher (null without --can).
std::unique_ptr<can::CanPosePublisher> open_can(const Options& o) {
  if (o.can_interface.empty()) return nullptr;
  can::CanConfig cfg;
  cfg.interface = o.can_interface;
  cfg.base_id = parse_id(o.can_base_id);
  cfg.extended_ids = o.can_extended;
  cfg.fd = o.can_fd;
  cfg.rate_hz = o.can_rate_hz;
  cfg.validate("agvslam-pose-replay options");
  spdlog::info("agvslam-pose-replay: {}", cfg.describe());
  return std::make_unique<can::CanPosePublisher>(cfg);
}

struct Publishers {
  std::unique_ptr<dds::DdsPosePublisher> dds;
  std::unique_ptr<can::CanPosePublisher> can;
};

// Sample i: synthetic, or the trajectory's pose i (tracking), stamped now or with its source time.
drv::PoseSample make_sample(const Options& o, const agvslam::Trajectory& traj, std::size_t i) {
  const int64_t source_t_ns = o.synthetic > 0 ? static_cast<int64_t>(i) * 50000000 : traj[i].t_ns;
  drv::PoseSample s = drv::synthetic_pose_sample(i, source_t_ns);
  if (o.synthetic == 0) {
    s.T_map_base = traj[i].T_w_c;
    s.tracking_state = drv::TrackingState::kTracking;
  }
  if (o.stamp == "now") s.t_ns = dds::realtime_now_ns();
  return s;
}

// Hands one sample to every output; with --json prints what each did.
void send(const Options& o, std::size_t i, const drv::PoseSample& s, Publishers& pub) {
  const dds::FrameIds frames;  // the DdsConfig defaults, as the publisher uses them
  nlohmann::json line;
  if (o.json) line = {{"i", i}, {"t_ns", s.t_ns}, {"sample", drv::pose_sample_to_json(s)}};
  if (pub.dds) {
    if (o.sync) {
      pub.dds->write_now(s);
    } else {
      pub.dds->publish(s);
    }
    if (o.json) {
      dds::PoseMsg pm{};
      dds::OdomMsg om{};
      dds::StatusMsg sm{};
      dds::fill_pose_msg(s, frames, pm);
      dds::fill_odom_msg(s, frames, om);
      dds::fill_status_msg(s, frames, sm);
      line["dds"] = {{"pose", dds::to_json(pm)}, {"odom", dds::to_json(om)}, {"status", dds::to_json(sm)}};
    }
  }
  if (pub.can) {
    const can::CanPublishResult r = pub.can->publish(s);
    if (o.json)
      line["can"] = {{"due", r.due}, {"sent", r.sent}, {"counter", r.counter}, {"frames_sent", r.frames_sent}};
  }
  if (o.json) {
    std::printf("%s\n", line.dump().c_str());
    std::fflush(stdout);  // a test watching the file sees each sample as it goes
  }
}

// What the outputs did (the DDS writes acknowledged first); logged, and printed with --json.
void summarise(const Options& o, std::size_t n, Publishers& pub) {
  nlohmann::json summary = {{"samples", n}};
  if (pub.dds) {
    const bool flushed = pub.dds->flush(std::chrono::seconds(5));
    const auto st = pub.dds->stats();
    summary["dds"] = {{"submitted", st.submitted},
                      {"published", st.published},
                      {"dropped_queue_full", st.dropped_queue_full},
                      {"write_errors", st.write_errors},
                      {"acknowledged", flushed}};
    spdlog::info("agvslam-pose-replay: dds published {} of {}, dropped {}, write errors {}, all acknowledged: {}",
                 st.published, st.submitted, st.dropped_queue_full, st.write_errors, flushed);
  }
  if (pub.can) {
    const auto st = pub.can->stats();
    summary["can"] = {{"cycles", st.cycles},
                      {"cycles_sent", st.cycles_sent},
                      {"frames_sent", st.frames_sent},
                      {"frames_dropped_no_buffer", st.frames_dropped_no_buffer},
                      {"frames_dropped_down", st.frames_dropped_down},
                      {"frames_failed", st.frames_failed},
                      {"reopen_attempts", st.reopen_attempts},
                      {"reopens", st.reopens},
                      {"error_frames", st.error_frames.total},
                      {"bus_off", st.error_frames.bus_off},
                      {"open", st.open},
                      {"last_error", pub.can->last_error()}};
    spdlog::info(
        "agvslam-pose-replay: can {} cycles, {} sent whole, {} frames sent, dropped {} (no buffer) {} (down), "
        "{} opens",
        st.cycles, st.cycles_sent, st.frames_sent, st.frames_dropped_no_buffer, st.frames_dropped_down, st.reopens);
  }
  if (o.json) std::printf("%s\n", nlohmann::json{{"summary", summary}}.dump().c_str());
}

int run(const Options& o) {
  check_options(o);
  agvslam::Trajectory traj;
  if (!o.trajectory.empty()) {
    traj = agvslam::io::read_trajectory(o.trajectory, agvslam::io::TrajectoryFormat::kTum, std::nullopt);
    if (traj.empty()) throw agvslam::InputError(o.trajectory, "", "expected at least one pose");
  }
  const std::size_t n = o.synthetic > 0 ? static_cast<std::size_t>(o.synthetic) : traj.size();

  Publishers pub;
  if (!open_dds(o, pub.dds)) return 1;
  pub.can = open_can(o);
  spdlog::info("agvslam-pose-replay: {} samples ({}), rate {} Hz, stamps {}", n,
               o.synthetic > 0 ? "synthetic" : o.trajectory, o.rate_hz, o.stamp);

  const auto period =
      o.rate_hz > 0 ? std::chrono::nanoseconds(static_cast<int64_t>(1e9 / o.rate_hz)) : std::chrono::nanoseconds(0);
  auto next = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < n; ++i) {
    if (period.count() > 0) {
      std::this_thread::sleep_until(next);
      next += period;
    }
    send(o, i, make_sample(o, traj, i), pub);
  }
  std::fflush(stdout);
  summarise(o, n, pub);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-pose-replay"));
  CLI::App app{"agvslam-pose-replay: send synthetic or recorded poses through the DDS and CAN outputs"};
  Options o;
  app.add_option("--synthetic", o.synthetic, "N deterministic samples (a circle drive through every tracking state)");
  app.add_option("--trajectory", o.trajectory, "TUM trajectory file (poses taken as T_map_base)");
  app.add_option("--rate", o.rate_hz, "samples per second (0: as fast as possible)")->capture_default_str();
  app.add_option("--stamp", o.stamp, "now: stamp with the current time; source: the file's / synthetic time")
      ->check(CLI::IsMember({"now", "source"}))
      ->capture_default_str();
  app.add_flag("--dds", o.dds, "publish on DDS (rt/<ns>/pose, odom, status)");
  app.add_option("--domain", o.domain, "DDS domain id")->capture_default_str();
  app.add_option("--interface", o.interface, "network interface for DDS");
  app.add_option("--namespace", o.ns, "topic namespace")->capture_default_str();
  app.add_option("--keystore", o.keystore,
                 "DDS Security: an SROS2 keystore (deploy/make-keystore.sh); none: plain DDS");
  app.add_option("--enclave", o.enclave, "DDS Security: the enclave whose credentials to use")
      ->default_str(agvslam::drivers::dds::DdsSecurityConfig{}.enclave);
  app.add_option("--wait-subscribers", o.wait_subscribers, "wait for N subscribers on every topic before sending")
      ->capture_default_str();
  app.add_option("--wait-timeout", o.wait_timeout_s, "seconds to wait for them")->capture_default_str();
  app.add_flag("--sync", o.sync, "write DDS on the caller's thread (no publisher thread)");
  app.add_option("--can", o.can_interface, "send CAN frames on this SocketCAN interface");
  app.add_option("--can-base-id", o.can_base_id, "id of the first frame")->capture_default_str();
  app.add_flag("--can-extended", o.can_extended, "29-bit ids");
  app.add_flag("--can-fd", o.can_fd, "one 48-byte CAN FD frame per pose instead of the classic frames");
  app.add_option("--can-rate", o.can_rate_hz, "highest CAN pose rate (0: every sample)")->capture_default_str();
  app.add_flag("--json", o.json, "print every sample and what each output did, one JSON object per line");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
