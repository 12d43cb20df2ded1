// agvslam-echo: subscribes to the daemon's DDS topics and prints what arrives (a field engineer's check that a
// vehicle publishes, and the receiving end of the DDS tests).
//
//   agvslam-echo [--topic pose|odom|status|all] [--domain N] [--interface NAME] [--namespace NS]
//                [--count N] [--timeout S] [--json] [--summary FILE]
//
// Text mode prints one line per sample (time, position, heading, state). --json prints one JSON object per line:
// {"topic": "pose", "recv_t_ns": <receive time>, "msg": <the ROS message, field names as in ROS 2>}, and after
// the last sample {"summary": {...}} with counts and the latency stamp -> receive (median, p95, p99, max), which
// is the publish -> receive latency when the publisher stamps at publish time and runs on the same host.
// --count N: stop after N samples (all chosen topics together); --timeout S: give up after S seconds (exit 1 when
// --count was not reached). Without either it runs until SIGINT/SIGTERM.
// Exit status: 0 done, 1 timeout or DDS failure, 2 bad option.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "agvslam/core/error.h"
#include "agvslam/core/stats.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "tool_main.h"

namespace {

namespace dds = agvslam::drivers::dds;

std::atomic<bool> g_stop{false};  // set by the signal handler only
extern "C" void on_signal(int /*sig*/) { g_stop = true; }

struct Options {
  std::string topic = "all";
  int domain = 0;
  std::string interface;
  std::string ns = "agvslam";
  std::string keystore;
  std::string enclave;
  long count = 0;
  double timeout_s = 0.0;
  bool json = false;
  std::string summary_path;
};

double yaw_deg(const geometry_msgs_msg_dds__Quaternion_& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z)) * 180.0 / M_PI;
}

int run(const Options& o) {
  dds::DdsConfig cfg;
  cfg.domain_id = o.domain;
  cfg.network_interface = o.interface;
  cfg.topic_namespace = o.ns;
  cfg.security.enabled = !o.keystore.empty();
  cfg.security.keystore = o.keystore;
  if (!o.enclave.empty()) cfg.security.enclave = o.enclave;
  cfg.validate("agvslam-echo options");
  if (cfg.security.enabled) spdlog::info("agvslam-echo: {}", cfg.security.describe());
  const bool all = o.topic == "all";
  spdlog::info("agvslam-echo: topic {}, {}, count {}, timeout {} s, output {}", o.topic, cfg.describe(), o.count,
               o.timeout_s, o.json ? "json" : "text");

  long received = 0;
  agvslam::Series latency_ms;
  std::map<std::string, long> per_topic;
  auto emit = [&](const char* topic, nlohmann::json msg, int64_t stamp_ns, int64_t recv_t_ns, const std::string& text) {
    ++received;
    ++per_topic[topic];
    latency_ms.add(static_cast<double>(recv_t_ns - stamp_ns) * 1e-6);
    if (o.json) {
      nlohmann::json line = {{"topic", topic}, {"recv_t_ns", recv_t_ns}, {"msg", std::move(msg)}};
      std::printf("%s\n", line.dump().c_str());
    } else {
      std::printf("%s %.6f %s\n", topic, static_cast<double>(stamp_ns) * 1e-9, text.c_str());
    }
  };
  dds::SubscriberHandlers h;
  char buf[256];
  if (all || o.topic == "pose") {
    h.on_pose = [&](const dds::PoseMsg& m, int64_t recv) {
      const auto& p = m.pose.pose.position;
      std::snprintf(buf, sizeof buf, "[%s] x %.3f y %.3f z %.3f m yaw %.2f deg sd_x %.3f m", m.header.frame_id, p.x,
                    p.y, p.z, yaw_deg(m.pose.pose.orientation), std::sqrt(std::max(0.0, m.pose.covariance[0])));
      emit("pose", dds::to_json(m), dds::from_ros_time(m.header.stamp), recv, buf);
    };
  }
  if (all || o.topic == "odom") {
    h.on_odom = [&](const dds::OdomMsg& m, int64_t recv) {
      const auto& p = m.pose.pose.position;
      const auto& v = m.twist.twist;
      std::snprintf(buf, sizeof buf, "[%s -> %s] x %.3f y %.3f yaw %.2f deg v %.3f m/s w %.3f rad/s", m.header.frame_id,
                    m.child_frame_id, p.x, p.y, yaw_deg(m.pose.pose.orientation), v.linear.x, v.angular.z);
      emit("odom", dds::to_json(m), dds::from_ros_time(m.header.stamp), recv, buf);
    };
  }
  if (all || o.topic == "status") {
    h.on_status = [&](const dds::StatusMsg& m, int64_t recv) {
      std::snprintf(buf, sizeof buf, "state %s fps %.1f dynamic %.1f %% dropped %llu latency %.1f ms",
                    agvslam::drivers::to_string(static_cast<agvslam::drivers::TrackingState>(m.tracking_state)),
                    static_cast<double>(m.fps), 100.0 * static_cast<double>(m.dynamic_pixel_fraction),
                    static_cast<unsigned long long>(m.frames_dropped), static_cast<double>(m.latency_ms));
      emit("status", dds::to_json(m), dds::from_ros_time(m.header.stamp), recv, buf);
    };
  }
  // tf only when named (all: the daemon's own topics): rt/tf and rt/tf_static are every node's.
  for (const char* tf_topic : {"tf", "tf_static"}) {
    if (o.topic != tf_topic) continue;
    auto print = [&, tf_topic](const dds::TfMsg& m, int64_t recv) {
      std::string text;
      int64_t stamp_ns = recv;
      for (uint32_t i = 0; i < m.transforms._length; ++i) {
        const dds::TransformMsg& t = m.transforms._buffer[i];
        const auto& p = t.transform.translation;
        std::snprintf(buf, sizeof buf, "%s[%s -> %s] x %.3f y %.3f z %.3f m yaw %.2f deg", i > 0 ? "; " : "",
                      t.header.frame_id, t.child_frame_id, p.x, p.y, p.z, yaw_deg(t.transform.rotation));
        text += buf;
        stamp_ns = dds::from_ros_time(t.header.stamp);
      }
      emit(tf_topic, dds::to_json(m), stamp_ns, recv, text);
    };
    (o.topic == "tf" ? h.on_tf : h.on_tf_static) = print;
  }
  dds::DdsPoseSubscriber sub(cfg, std::move(h));

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
  while (!g_stop && (o.count <= 0 || received < o.count)) {
    if (o.timeout_s > 0.0 && std::chrono::steady_clock::now() - start > std::chrono::duration<double>(o.timeout_s)) {
      timed_out = true;
      break;
    }
    sub.poll(std::chrono::milliseconds(100));
    std::fflush(stdout);
  }

  nlohmann::json summary = {{"received", received},
                            {"per_topic", per_topic},
                            {"latency_ms",
                             {{"median", latency_ms.median()},
                              {"p95", latency_ms.quantile(0.95)},
                              {"p99", latency_ms.quantile(0.99)},
                              {"max", latency_ms.max()}}},
                            {"timed_out", timed_out}};
  if (o.json) std::printf("%s\n", nlohmann::json{{"summary", summary}}.dump().c_str());
  std::fflush(stdout);
  if (!o.summary_path.empty()) {
    std::ofstream out(o.summary_path);
    if (!out) throw agvslam::InputError(o.summary_path, "--summary", "expected a writable file");
    out << summary.dump(2) << "\n";
  }
  spdlog::info("agvslam-echo: received {} samples; latency stamp->receive median {:.3f} ms, p99 {:.3f} ms{}", received,
               latency_ms.median(), latency_ms.quantile(0.99), timed_out ? " (timed out)" : "");
  return timed_out && o.count > 0 && received < o.count ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-echo"));
  CLI::App app{"agvslam-echo: print the pose, odometry and status samples agvslamd publishes over DDS"};
  Options o;
  app.add_option("--topic", o.topic, "pose|odom|status|all (those three)|tf|tf_static")
      ->check(CLI::IsMember({"pose", "odom", "status", "all", "tf", "tf_static"}))
      ->capture_default_str();
  app.add_option("--domain", o.domain, "DDS domain id (ROS_DOMAIN_ID)")->capture_default_str();
  app.add_option("--interface", o.interface,
                 "network interface for DDS (default: Cyclone's choice, or CYCLONEDDS_URI)");
  app.add_option("--namespace", o.ns, "topic namespace: rt/<ns>/pose ...")->capture_default_str();
  app.add_option("--keystore", o.keystore,
                 "DDS Security: an SROS2 keystore (deploy/make-keystore.sh); none: plain DDS");
  app.add_option("--enclave", o.enclave, "DDS Security: the enclave whose credentials to use")
      ->default_str(agvslam::drivers::dds::DdsSecurityConfig{}.enclave);
  app.add_option("--count", o.count, "stop after N samples (0: run until interrupted)")->capture_default_str();
  app.add_option("--timeout", o.timeout_s, "give up after S seconds (0: never)")->capture_default_str();
  app.add_flag("--json", o.json, "one JSON object per sample, then a summary line");
  app.add_option("--summary", o.summary_path, "also write the summary (counts, latency) to this JSON file");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
