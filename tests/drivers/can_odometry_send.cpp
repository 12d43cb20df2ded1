// can_odometry_send: plays wheel odometry onto a CAN interface as a vehicle controller would (VEHICLE_ODOMETRY of
// deploy/agvslam.dbc, Counter and Crc), in step with agvslamd playing the same simulator sequence, for the VM
// case tests/vm/cases/can_odometry_check.sh.
//
//   can_odometry_send --interface vcan0 --odometry SEQ/odometry.txt --dbc deploy/agvslam.dbc --pose-log poses.jsonl
//                     [--rate R] [--scale S] [--scale-from-s T] [--send-hz 50]
//
// --odometry: the simulator's odometry.txt (TUM poses of the camera, turned into speed and yaw rate) or a CSV of
// t_s, speed_mps, yaw_rate_radps. --pose-log: the daemon's JSON log; the first line with a dataset frame gives the
// wall time of that frame's dataset time, and the odometry follows the dataset clock from there. --rate: the
// daemon's source.rate (dataset seconds per wall second): speeds and yaw rates are multiplied by it so that the
// motion per wall second is the played motion. --scale: speeds multiplied by S from dataset time T on (a wheel
// scale error). Exit 0 once the odometry is played out, 1 on a send error, 2 on bad input.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/can_socket.h"
#include "agvslam/drivers/can/odometry_input.h"
#include "agvslam/eval/odometry_check.h"
#include "agvslam/io/odometry_io.h"
#include "agvslam/io/trajectory_io.h"

namespace {

namespace can = agvslam::drivers::can;
using agvslam::OdometryRate;

int64_t realtime_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Speed and yaw rate between consecutive poses, stamped at the middle of each step.
std::vector<OdometryRate> rates_from_poses(const agvslam::Trajectory& poses, agvslam::eval::BodyAxes axes) {
  const agvslam::eval::PlanarTrack track = agvslam::eval::planar_track(poses, axes);
  std::vector<OdometryRate> rates;
  for (std::size_t i = 1; i < track.t_ns.size(); ++i) {
    const double dt = agvslam::ns_to_s(track.t_ns[i] - track.t_ns[i - 1]);
    if (dt <= 0) continue;
    rates.push_back(OdometryRate{(track.t_ns[i] + track.t_ns[i - 1]) / 2,
                                 (track.distance_m[i] - track.distance_m[i - 1]) / dt,
                                 (track.heading_rad[i] - track.heading_rad[i - 1]) / dt});
  }
  return rates;
}

OdometryRate at(const std::vector<OdometryRate>& rates, int64_t t_ns) {
  auto it =
      std::lower_bound(rates.begin(), rates.end(), t_ns, [](const OdometryRate& r, int64_t t) { return r.t_ns < t; });
  if (it == rates.begin()) return *it;
  if (it == rates.end()) return rates.back();
  const OdometryRate& a = *(it - 1);
  const OdometryRate& b = *it;
  const double f = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  return OdometryRate{t_ns, a.speed_mps + f * (b.speed_mps - a.speed_mps),
                      a.yaw_rate_radps + f * (b.yaw_rate_radps - a.yaw_rate_radps)};
}

// Waits for the first pose-log line of a dataset frame: (wall t_ns, dataset t_ns).
std::pair<int64_t, int64_t> wait_for_first_pose(const std::string& path) {
  for (int i = 0; i < 6000; ++i) {
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
      const auto j = nlohmann::json::parse(line, nullptr, false);
      if (j.is_discarded() || !j.contains("source_index") || j["source_index"].get<int64_t>() < 0) continue;
      return {j["t_ns"].get<int64_t>(), j["source_t_ns"].get<int64_t>()};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  throw agvslam::InputError(path, "file", "expected the daemon's pose log with a frame within 600 s");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"can_odometry_send: wheel odometry onto a CAN bus, in step with agvslamd's dataset playback"};
  std::string interface, odometry_path, dbc_path, pose_log, axes = "camera", base_id_text = "0x300";
  double rate = 1.0, scale = 1.0, scale_from_s = 0.0, send_hz = 50.0;
  app.add_option("--interface", interface)->required();
  app.add_option("--odometry", odometry_path)->required();
  app.add_option("--dbc", dbc_path)->required();
  app.add_option("--pose-log", pose_log)->required();
  app.add_option("--axes", axes, "body axes of TUM odometry poses")->capture_default_str();
  app.add_option("--base-id", base_id_text)->capture_default_str();
  app.add_option("--rate", rate)->capture_default_str();
  app.add_option("--scale", scale)->capture_default_str();
  app.add_option("--scale-from-s", scale_from_s)->capture_default_str();
  app.add_option("--send-hz", send_hz)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    can::CanOdometryConfig config;
    config.dbc = dbc_path;
    const can::CanOdometryDecoder codec(
        config, can::FrameLayout{static_cast<uint32_t>(std::stoul(base_id_text, nullptr, 0)), false},
        "can_odometry_send");
    const std::vector<OdometryRate> rates =
        agvslam::io::looks_like_odometry_csv(odometry_path)
            ? agvslam::io::read_odometry_csv(odometry_path)
            : rates_from_poses(agvslam::io::read_tum(odometry_path), agvslam::eval::parse_body_axes(axes, "--axes"));
    if (rates.size() < 2) throw agvslam::InputError(odometry_path, "file", "expected at least 3 poses");
    can::CanSocket socket;
    std::string error;
    if (!socket.open(interface, false, &error)) {
      std::fprintf(stderr, "can_odometry_send: %s\n", error.c_str());
      return 1;
    }
    const auto [wall0_ns, data0_ns] = wait_for_first_pose(pose_log);
    std::fprintf(stderr, "can_odometry_send: %s: dataset %.3f s = wall %.3f s, rate %.4f, scale %.3f from %.1f s\n",
                 codec.describe().c_str(), data0_ns * 1e-9, wall0_ns * 1e-9, rate, scale, scale_from_s);
    const auto period_ns = static_cast<int64_t>(1e9 / send_hz);
    uint8_t counter = 0;
    uint64_t sent = 0, failed = 0;
    for (int64_t wall = realtime_ns();; wall += period_ns) {
      const auto data_ns = data0_ns + static_cast<int64_t>(static_cast<double>(wall - wall0_ns) * rate);
      if (data_ns > rates.back().t_ns) break;
      const int64_t sleep_ns = wall - realtime_ns();
      if (sleep_ns > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(sleep_ns));
      OdometryRate r = at(rates, data_ns);
      const double k = agvslam::ns_to_s(data_ns) >= scale_from_s ? scale : 1.0;
      r.speed_mps *= k * rate;
      r.yaw_rate_radps *= rate;
      if (socket.send(codec.encode(r, counter), nullptr) == can::SendResult::kSent) {
        ++sent;
      } else {
        ++failed;
      }
      counter = static_cast<uint8_t>((counter + 1) & 0xF);
    }
    std::fprintf(stderr, "can_odometry_send: %llu frames sent, %llu failed\n", static_cast<unsigned long long>(sent),
                 static_cast<unsigned long long>(failed));
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "can_odometry_send: %s\n", e.what());
    return 2;
  }
}
