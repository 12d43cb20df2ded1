// The CAN frame encoder against deploy/agvslam.dbc: golden bytes worked out by hand from the documented layout,
// and a round trip of many samples through the DBC's signal definitions (every value within half a step).

#include <gtest/gtest.h>

#include <fstream>

#include "agvslam/drivers/can/candump_log.h"
#include "agvslam/drivers/can/dbc.h"
#include "agvslam/drivers/can/pose_frames.h"
#include "agvslam/drivers/pose_sample_json.h"
#include "can_log_checker.h"

namespace {

using namespace agvslam::drivers;
using namespace agvslam::drivers::can;

const std::string kDbcPath = std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc";

// Bitwise CRC-8/SAE-J1850, written from the definition (not the driver's table).
uint8_t reference_crc(const std::vector<uint8_t>& bytes) {
  uint8_t crc = 0xFF;
  for (uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i)
      crc = (crc & 0x80) ? static_cast<uint8_t>((crc << 1) ^ 0x1D) : static_cast<uint8_t>(crc << 1);
  }
  return static_cast<uint8_t>(crc ^ 0xFF);
}

nlohmann::json sample_line(std::size_t i, const PoseSample& s, uint8_t counter) {
  return {{"i", i},
          {"sample", pose_sample_to_json(s)},
          {"can", {{"due", true}, {"sent", true}, {"counter", counter}, {"frames_sent", 1}}}};
}

TEST(PoseFrames, CrcIsSaeJ1850) {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc8_sae_j1850(check, 9) ^ 0xFF, 0x4B);
  EXPECT_EQ(static_cast<uint8_t>(crc8_sae_j1850(check, 9) ^ 0xFF), reference_crc({check, check + 9}));
}

TEST(PoseFrames, GoldenPoseXYawFrame) {
  PoseSample s;
  s.T_map_base = agvslam::make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::UnitZ())),
                                   Eigen::Vector3d(-12.345, 7.0, 0.25));
  s.tracking_state = TrackingState::kTracking;
  std::array<CanFrameBytes, kMaxClassicFrames> f;
  ASSERT_EQ(encode_classic_frames(s, 5, FrameLayout{}, false, false, false, f), 2U);
  // x = -12345 mm = 0xFFFFCFC7 (LE: C7 CF FF FF); yaw = 9000 = 0x2328 (LE: 28 23); byte 6 = state 1 | counter 5 << 4.
  EXPECT_EQ(f[0].id, 0x300U);
  EXPECT_FALSE(f[0].extended);
  ASSERT_EQ(f[0].len, 8);
  const std::vector<uint8_t> head = {0xC7, 0xCF, 0xFF, 0xFF, 0x28, 0x23, 0x51};
  for (std::size_t i = 0; i < head.size(); ++i) EXPECT_EQ(f[0].data[i], head[i]) << "byte " << i;
  std::vector<uint8_t> crc_in = {0x00, 0x03, 0x00, 0x00};  // id 0x300, 4 bytes little-endian
  crc_in.insert(crc_in.end(), head.begin(), head.end());
  EXPECT_EQ(f[0].data[7], reference_crc(crc_in));
  // y = 7000 mm = 0x1B58; z = 250 mm = 0x00FA; counter 5 in the high nibble of byte 6.
  EXPECT_EQ(f[1].id, 0x301U);
  const std::vector<uint8_t> head_yz = {0x58, 0x1B, 0x00, 0x00, 0xFA, 0x00, 0x50};
  for (std::size_t i = 0; i < head_yz.size(); ++i) EXPECT_EQ(f[1].data[i], head_yz[i]) << "byte " << i;
}

TEST(PoseFrames, SaturatesAndWrapsYaw) {
  PoseSample s;
  s.T_map_base = agvslam::make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(-EIGEN_PI, Eigen::Vector3d::UnitZ())),
                                   Eigen::Vector3d(1e7, -1e7, 40.0));
  s.v_base_mps = Eigen::Vector3d(100.0, -100.0, 0.0);
  std::array<CanFrameBytes, kMaxClassicFrames> f;
  encode_classic_frames(s, 0, FrameLayout{}, true, false, false, f);
  EXPECT_EQ(static_cast<int32_t>(get_bits_le(f[0].data.data(), 0, 32)), INT32_MAX);
  EXPECT_EQ(static_cast<int16_t>(get_bits_le(f[0].data.data(), 32, 16)), 18000);  // -180 deg is sent as +180
  EXPECT_EQ(static_cast<int32_t>(get_bits_le(f[1].data.data(), 0, 32)), INT32_MIN);
  EXPECT_EQ(static_cast<int16_t>(get_bits_le(f[1].data.data(), 32, 16)), 32767);  // z saturates at 32.767 m
  EXPECT_EQ(static_cast<int16_t>(get_bits_le(f[2].data.data(), 0, 16)), 32767);
  EXPECT_EQ(static_cast<int16_t>(get_bits_le(f[2].data.data(), 16, 16)), -32768);
}

TEST(PoseFrames, ExtendedIdsAndBase) {
  PoseSample s;
  std::array<CanFrameBytes, kMaxClassicFrames> f;
  const std::size_t n = encode_classic_frames(s, 3, FrameLayout{0x18FF1000, true}, true, true, true, f);
  ASSERT_EQ(n, 5U);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_TRUE(f[i].extended);
    EXPECT_EQ(f[i].data[7], frame_crc(f[i]));
  }
  EXPECT_EQ(f[4].id, 0x18FF1004U);
  const CanFrameBytes fd = encode_fd_frame(s, 3, FrameLayout{0x18FF1000, true});
  EXPECT_EQ(fd.id, 0x18FF1008U);
  EXPECT_TRUE(fd.fd);
  EXPECT_EQ(fd.len, 48);
}

// AGVSLAM_ODOM_CHECK: golden bytes, and every signal decoded with the DBC within half a step.
TEST(PoseFrames, OdometryCheckFrameAgainstTheDbc) {
  OdometryCheck check;
  check.state = OdometryCheckState::kDisagrees;
  check.distance_ratio = 1.2504;           // 1250 = 0x04E2
  check.speed_rmse_mps = 0.0456;           // 46 = 0x002E
  check.heading_difference_deg = -12.344;  // -1234 = 0xFB2E
  const CanFrameBytes f = encode_odometry_check_frame(check, 7, FrameLayout{});
  EXPECT_EQ(f.id, 0x305U);
  ASSERT_EQ(f.len, 8);
  const std::vector<uint8_t> head = {0xE2, 0x04, 0x2E, 0x00, 0x2E, 0xFB, 0x75};  // byte 6: state 5 | counter 7 << 4
  for (std::size_t i = 0; i < head.size(); ++i) EXPECT_EQ(f.data[i], head[i]) << "byte " << i;
  std::vector<uint8_t> crc_in = {0x05, 0x03, 0x00, 0x00};
  crc_in.insert(crc_in.end(), head.begin(), head.end());
  EXPECT_EQ(f.data[7], reference_crc(crc_in));

  const Dbc dbc = Dbc::load(kDbcPath);
  const DbcMessage* m = dbc.find(0x305, false);
  ASSERT_NE(m, nullptr);
  const auto v = decode_signals(*m, f);
  EXPECT_NEAR(v.at("DistanceRatio"), check.distance_ratio, 0.0005);
  EXPECT_NEAR(v.at("SpeedRmse"), check.speed_rmse_mps, 0.0005);
  EXPECT_NEAR(v.at("HeadingDiff"), check.heading_difference_deg, 0.005);
  EXPECT_EQ(v.at("OdomCheckState"), 5.0);
  EXPECT_EQ(m->signal("OdomCheckState")->value_names.at(4), "Agrees");
  EXPECT_EQ(v.at("Counter"), 7.0);

  // No ratio (the odometry did not move): the reserved 65.535; a huge one saturates below it.
  check.distance_ratio = std::nan("");
  EXPECT_EQ(get_bits_le(encode_odometry_check_frame(check, 0, FrameLayout{}).data.data(), 0, 16), 0xFFFFU);
  check.distance_ratio = 1e6;
  EXPECT_EQ(get_bits_le(encode_odometry_check_frame(check, 0, FrameLayout{}).data.data(), 0, 16), 0xFFFEU);
  EXPECT_EQ(encode_odometry_check_frame(check, 0, FrameLayout{0x18FF1000, true}).id, 0x18FF1005U);
}

// The map the pose is in: a vehicle controller must see a new map (its own origin) in the pose frames themselves.
TEST(PoseFrames, MapIdInThePoseFramesAgainstTheDbc) {
  PoseSample s = synthetic_pose_sample(3, 1700000000000000000LL);
  s.map_id = 0x12345;  // 4 bits on classic CAN (5), 16 on CAN FD (0x2345)
  std::array<CanFrameBytes, kMaxClassicFrames> frames;
  ASSERT_GE(encode_classic_frames(s, 9, FrameLayout{}, false, false, false, frames), 2U);
  const CanFrameBytes& yz = frames[1];
  EXPECT_EQ(yz.id, 0x301U);
  EXPECT_EQ(yz.data[6], 0x95);  // MapId 5 | Counter 9 << 4
  EXPECT_EQ(yz.data[7], frame_crc(yz));
  const CanFrameBytes fd = encode_fd_frame(s, 9, FrameLayout{});
  EXPECT_EQ(fd.data[45], 0x45);
  EXPECT_EQ(fd.data[46], 0x23);

  const Dbc dbc = Dbc::load(kDbcPath);
  EXPECT_EQ(decode_signals(*dbc.find(0x301, false), yz).at("MapId"), 5.0);
  EXPECT_EQ(decode_signals(*dbc.find(0x308, false), fd).at("MapId"), 0x2345);
  // The first map is 0 in both.
  s.map_id = 0;
  encode_classic_frames(s, 9, FrameLayout{}, false, false, false, frames);
  EXPECT_EQ(frames[1].data[6], 0x90);
  EXPECT_EQ(get_bits_le(encode_fd_frame(s, 9, FrameLayout{}).data.data(), 360, 16), 0U);
}

// Every frame the encoder makes for 200 synthetic samples, written as candump -L lines, read back and decoded
// with the DBC's signal definitions: every value within half a step of the sample, Crc and Counter right.
void round_trip(bool fd) {
  const Dbc dbc = Dbc::load(kDbcPath);
  std::vector<nlohmann::json> sent;
  std::vector<CandumpRecord> log;
  int line_no = 0;
  for (std::size_t i = 0; i < 200; ++i) {
    const PoseSample s = synthetic_pose_sample(i, 1700000000000000000LL + static_cast<int64_t>(i) * 50000000);
    const auto counter = static_cast<uint8_t>(i & 0xF);
    sent.push_back(sample_line(i, s, counter));
    std::vector<CanFrameBytes> frames;
    if (fd) {
      frames.push_back(encode_fd_frame(s, counter, FrameLayout{}));
    } else {
      std::array<CanFrameBytes, kMaxClassicFrames> f;
      frames.assign(f.begin(), f.begin() + static_cast<long>(
                                               encode_classic_frames(s, counter, FrameLayout{}, true, true, true, f)));
    }
    for (const auto& frame : frames) {
      const std::string text = format_candump_line(frame, "vcan0", s.t_ns);
      auto rec = parse_candump_line(text, "generated", ++line_no);
      ASSERT_TRUE(rec.has_value());
      log.push_back(*rec);
    }
  }
  const auto res = agvslam::test::check_can_log(dbc, sent, log);
  for (const auto& f : res.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(res.ok);
  EXPECT_EQ(res.log_cycles, 200);
  EXPECT_EQ(res.values_checked, fd ? 200 * 20 : 200 * 17);  // every signal but Counter and Crc
}

TEST(PoseFrames, ClassicFramesRoundTripThroughTheDbc) { round_trip(false); }
TEST(PoseFrames, FdFrameRoundTripsThroughTheDbc) { round_trip(true); }

TEST(PoseFrames, CheckerCatchesACorruptedFrame) {
  const Dbc dbc = Dbc::load(kDbcPath);
  const PoseSample s = synthetic_pose_sample(3, 1700000000000000000LL);
  std::array<CanFrameBytes, kMaxClassicFrames> f;
  const std::size_t n = encode_classic_frames(s, 9, FrameLayout{}, true, true, true, f);
  std::vector<CandumpRecord> log;
  for (std::size_t i = 0; i < n; ++i) {
    CandumpRecord r;
    r.frame = f[i];
    log.push_back(r);
  }
  const std::vector<nlohmann::json> sent = {sample_line(3, s, 9)};
  EXPECT_TRUE(agvslam::test::check_can_log(dbc, sent, log).ok);
  log[0].frame.data[0] ^= 0x01;  // x off by 1 mm: Crc and value both wrong
  const auto res = agvslam::test::check_can_log(dbc, sent, log);
  EXPECT_FALSE(res.ok);
  ASSERT_FALSE(res.failures.empty());
  EXPECT_NE(res.failures[0].find("Crc"), std::string::npos) << res.failures[0];
}

// Cycles 0..9; cycle 5 could not be sent (interface down). Cycle 4 (sent just before) may be missing from the log,
// no other may be, and the log may hold nothing the driver did not send.
TEST(PoseFrames, CheckerAllowsOnlyTheCycleBeforeAnOutageToBeMissing) {
  const Dbc dbc = Dbc::load(kDbcPath);
  std::vector<nlohmann::json> sent;
  std::vector<std::vector<CandumpRecord>> cycles;
  for (std::size_t i = 0; i < 10; ++i) {
    const PoseSample s = synthetic_pose_sample(i, static_cast<int64_t>(i) * 50000000);
    const auto counter = static_cast<uint8_t>(i & 0xF);
    nlohmann::json line = sample_line(i, s, counter);
    std::array<CanFrameBytes, kMaxClassicFrames> f;
    const std::size_t n = encode_classic_frames(s, counter, FrameLayout{}, true, true, true, f);
    cycles.emplace_back();
    if (i == 5) {
      line["can"]["sent"] = false;
      line["can"]["frames_sent"] = 0;
    } else {
      for (std::size_t k = 0; k < n; ++k) {
        CandumpRecord r;
        r.frame = f[k];
        cycles.back().push_back(r);
      }
    }
    sent.push_back(line);
  }
  auto log_without = [&](std::size_t missing) {
    std::vector<CandumpRecord> log;
    for (std::size_t i = 0; i < cycles.size(); ++i) {
      if (i != missing) log.insert(log.end(), cycles[i].begin(), cycles[i].end());
    }
    return log;
  };
  auto all = agvslam::test::check_can_log(dbc, sent, log_without(99));
  EXPECT_TRUE(all.ok);
  EXPECT_EQ(all.unsent_samples, 1);
  EXPECT_EQ(all.sent_after_unsent, 4);
  auto before_outage = agvslam::test::check_can_log(dbc, sent, log_without(4));
  EXPECT_TRUE(before_outage.ok);
  EXPECT_EQ(before_outage.lost_at_outage, 1);
  EXPECT_FALSE(agvslam::test::check_can_log(dbc, sent, log_without(3)).ok);
  EXPECT_FALSE(agvslam::test::check_can_log(dbc, sent, log_without(6)).ok);
  std::vector<nlohmann::json> fewer(sent.begin(), sent.end() - 1);  // the log has a cycle nobody sent
  EXPECT_FALSE(agvslam::test::check_can_log(dbc, fewer, log_without(99)).ok);
}

}  // namespace
