#include "can_log_checker.h"

#include <cmath>
#include <map>
#include <sstream>

#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::test {
namespace {

using drivers::can::CandumpRecord;
using drivers::can::Dbc;
using drivers::can::DbcMessage;

struct Cycle {
  int counter = -1;
  bool fd = false;
  std::map<std::string, std::map<std::string, double>> messages;  // message name -> signal -> value
};

constexpr double kRadToDeg = 180.0 / M_PI;

// Expected physical values, straight from the sample's SI fields (independent of the encoder's arithmetic).
struct Expected {
  double x, y, z, roll, pitch, yaw, vx, vy, yaw_rate, sd_x, sd_y, sd_yaw, latency_ms, fps, dyn_pct;
  int64_t dropped, state, frame_index, t_ms, map_id;
};

Expected expected_from(const nlohmann::json& s) {
  Expected e{};
  const auto& t = s.at("t");
  const auto& R = s.at("R");
  auto r = [&](int i, int j) { return R.at(static_cast<std::size_t>(i * 3 + j)).get<double>(); };
  e.x = t.at(0).get<double>();
  e.y = t.at(1).get<double>();
  e.z = t.at(2).get<double>();
  e.yaw = std::atan2(r(1, 0), r(0, 0)) * kRadToDeg;
  e.pitch = std::asin(std::max(-1.0, std::min(1.0, -r(2, 0)))) * kRadToDeg;
  e.roll = std::atan2(r(2, 1), r(2, 2)) * kRadToDeg;
  e.vx = s.at("v_base_mps").at(0).get<double>();
  e.vy = s.at("v_base_mps").at(1).get<double>();
  e.yaw_rate = s.at("w_base_radps").at(2).get<double>() * kRadToDeg;
  const auto& cov = s.at("cov_pose");
  e.sd_x = std::sqrt(cov.at(0).get<double>());
  e.sd_y = std::sqrt(cov.at(7).get<double>());
  e.sd_yaw = std::sqrt(cov.at(35).get<double>()) * kRadToDeg;
  e.latency_ms = static_cast<double>(s.at("latency_ns").get<int64_t>()) * 1e-6;
  e.fps = s.at("fps").get<double>();
  e.dyn_pct = s.at("dynamic_pixel_fraction").get<double>() * 100.0;
  e.dropped = static_cast<int64_t>(s.at("frames_dropped").get<uint64_t>() % 65536);
  e.state = s.at("tracking_state").get<int64_t>();
  e.frame_index = static_cast<int64_t>(s.at("frame_index").get<uint64_t>() % 4294967296ULL);
  e.map_id = static_cast<int64_t>(s.value("map_id", uint64_t{0}));
  const int64_t t_ns = s.at("t_ns").get<int64_t>();
  e.t_ms = (t_ns >= 0 ? t_ns / 1000000 : -((-t_ns + 999999) / 1000000)) % 4294967296LL;
  return e;
}

}  // namespace

CanCheckResult check_can_log(const Dbc& dbc, const std::vector<nlohmann::json>& sent,
                             const std::vector<CandumpRecord>& log, uint32_t base_id) {
  CanCheckResult res;
  auto fail = [&](const std::string& what) {
    if (res.failures.size() < 20) res.failures.push_back(what);
  };
  const int64_t shift = static_cast<int64_t>(base_id) - 0x300;

  // 1. The log, grouped into cycles: a cycle starts at POSE_XYAW / POSE_FD or where the Counter changes.
  std::vector<Cycle> cycles;
  for (const auto& rec : log) {
    if (rec.error_frame || rec.remote) continue;
    const int64_t id = static_cast<int64_t>(rec.frame.id) - shift;
    const DbcMessage* msg = id >= 0 ? dbc.find(static_cast<uint32_t>(id), rec.frame.extended) : nullptr;
    if (msg == nullptr) continue;
    ++res.frames;
    if (rec.frame.len != msg->length) {
      fail(msg->name + ": " + std::to_string(rec.frame.len) + " bytes, the DBC says " + std::to_string(msg->length));
      continue;
    }
    if (msg->fd != rec.frame.fd) fail(msg->name + ": CAN FD flag differs from the DBC's VFrameFormat");
    const auto values = drivers::can::decode_signals(*msg, rec.frame);
    if (drivers::can::frame_crc(rec.frame) != rec.frame.data[rec.frame.len - 1U]) {
      fail(msg->name + ": Crc mismatch in frame at t " + std::to_string(rec.t_ns));
    }
    const int counter = static_cast<int>(values.at("Counter"));
    const bool starts = msg->name == "AGVSLAM_POSE_XYAW" || msg->name == "AGVSLAM_POSE_FD";
    if (cycles.empty() || starts || cycles.back().counter != counter || cycles.back().messages.count(msg->name) != 0) {
      cycles.push_back(Cycle{counter, msg->fd, {}});
    }
    cycles.back().messages[msg->name] = values;
  }
  res.log_cycles = static_cast<int>(cycles.size());

  // 2. What the driver says it sent. A cycle handed to the socket just before the interface went down (the next
  // due cycle could not be sent) may never reach the bus: the kernel drops what is queued on a device going down,
  // after send() succeeded. Such a cycle may be missing from the log; any other may not.
  struct Sent {
    const nlohmann::json* line;
    bool may_be_lost;
  };
  std::vector<Sent> expected;
  bool seen_unsent = false;
  for (const auto& line : sent) {
    if (!line.contains("i") || !line.contains("can")) continue;
    ++res.samples;
    const auto& c = line.at("can");
    if (!c.at("due").get<bool>()) continue;
    const bool whole = c.at("sent").get<bool>();
    if (whole) {
      ++res.whole_cycles;
      if (seen_unsent) ++res.sent_after_unsent;
    } else {
      ++res.unsent_samples;
      seen_unsent = true;
      if (!expected.empty()) expected.back().may_be_lost = true;
    }
    if (c.at("frames_sent").get<int>() > 0) expected.push_back(Sent{&line, !whole});
  }
  res.expected_cycles = static_cast<int>(expected.size());

  // 3. Values, in order: the log's cycles must be the sent cycles, in order, none extra, none missing but those
  // allowed above.
  std::size_t j = 0;
  for (const Sent& sent_cycle : expected) {
    const nlohmann::json& line = *sent_cycle.line;
    const int sent_counter = line.at("can").at("counter").get<int>();
    if (j >= cycles.size() || cycles[j].counter != sent_counter) {
      if (sent_cycle.may_be_lost) {
        ++res.lost_at_outage;
      } else {
        fail("sample " + std::to_string(line.at("i").get<int>()) + " (Counter " + std::to_string(sent_counter) +
             ") was sent but is not in the log" +
             (j < cycles.size() ? " (next in the log: Counter " + std::to_string(cycles[j].counter) + ")" : ""));
      }
      continue;
    }
    const Cycle& cy = cycles[j++];
    const Expected e = expected_from(line.at("sample"));
    const std::string where = "sample " + std::to_string(line.at("i").get<int>());
    auto check = [&](const std::string& message, const std::string& signal, double want) {
      auto m = cy.messages.find(message);
      if (m == cy.messages.end()) return;  // partial cycle (interface went down mid-cycle) or frame not sent
      const DbcMessage* msg = dbc.find(message);
      const auto* sig = msg->signal(signal);
      auto v = m->second.find(signal);
      if (sig == nullptr || v == m->second.end()) {
        fail(message + "." + signal + " missing from the DBC or the frame");
        return;
      }
      // Values outside the signal's range saturate; otherwise the step is |factor|, rounding error <= step/2.
      const double clamped = std::max(sig->minimum, std::min(sig->maximum, want));
      double diff = std::abs(v->second - clamped);
      if (signal == "PoseYaw" || signal == "PoseRoll") diff = std::min(diff, std::abs(360.0 - diff));
      ++res.values_checked;
      if (diff > 0.5 * std::abs(sig->factor) + 1e-9 * std::max(1.0, std::abs(want))) {
        std::ostringstream s;
        s.precision(10);
        s << where << ": " << message << "." << signal << " = " << v->second << ", expected " << clamped << " +- "
          << 0.5 * std::abs(sig->factor);
        fail(s.str());
      }
    };
    for (const char* msg : {"AGVSLAM_POSE_XYAW", "AGVSLAM_POSE_FD"}) {
      check(msg, "PoseX", e.x);
      check(msg, "PoseYaw", e.yaw);
      check(msg, "TrackingState", static_cast<double>(e.state));
    }
    check("AGVSLAM_POSE_YZ", "PoseY", e.y);
    check("AGVSLAM_POSE_YZ", "PoseZ", e.z);
    check("AGVSLAM_POSE_YZ", "MapId", static_cast<double>(e.map_id % 16));
    check("AGVSLAM_POSE_FD", "MapId", static_cast<double>(e.map_id % 65536));
    for (const char* msg : {"AGVSLAM_VELOCITY", "AGVSLAM_POSE_FD"}) {
      check(msg, "VelX", e.vx);
      check(msg, "VelY", e.vy);
      check(msg, "YawRate", e.yaw_rate);
    }
    for (const char* msg : {"AGVSLAM_POSE_STDDEV", "AGVSLAM_POSE_FD"}) {
      check(msg, "StdDevX", e.sd_x);
      check(msg, "StdDevY", e.sd_y);
      check(msg, "StdDevYaw", e.sd_yaw);
    }
    for (const char* msg : {"AGVSLAM_STATUS", "AGVSLAM_POSE_FD"}) {
      check(msg, "LatencyMs", e.latency_ms);
      check(msg, "Fps", e.fps);
      check(msg, "DynamicPct", e.dyn_pct);
      check(msg, "DroppedFrames", static_cast<double>(e.dropped));
    }
    check("AGVSLAM_STATUS", "TrackingState", static_cast<double>(e.state));
    check("AGVSLAM_POSE_FD", "PoseY", e.y);
    check("AGVSLAM_POSE_FD", "PoseZ", e.z);
    check("AGVSLAM_POSE_FD", "PoseRoll", e.roll);
    check("AGVSLAM_POSE_FD", "PosePitch", e.pitch);
    check("AGVSLAM_POSE_FD", "CaptureTimeMs", static_cast<double>(e.t_ms));
    check("AGVSLAM_POSE_FD", "FrameIndex", static_cast<double>(e.frame_index));
    const bool whole = line.at("can").at("sent").get<bool>();
    if (whole && cy.messages.count("AGVSLAM_POSE_XYAW") == 0 && cy.messages.count("AGVSLAM_POSE_FD") == 0) {
      fail(where + ": sent whole, but its first frame is not in the log");
    }
  }
  if (j < cycles.size()) {
    fail("the log has " + std::to_string(cycles.size() - j) + " pose cycle(s) more than the driver sent");
  }
  res.ok = res.failures.empty() && res.expected_cycles > 0;
  if (res.expected_cycles == 0) fail("the driver sent nothing");
  return res;
}

}  // namespace agvslam::test
