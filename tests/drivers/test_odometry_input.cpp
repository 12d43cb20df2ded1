// Wheel odometry in over CAN: the decoder on deploy/agvslam.dbc's VEHICLE_ODOMETRY (values, id with the base id,
// Crc and Counter rejection) and on a vehicle's own DBC (Motorola signals, km/h, no Counter or Crc), and the
// configuration errors that stop the daemon at start-up.

#include <gtest/gtest.h>

#include <cmath>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/odometry_input.h"
#include "common/config_test.h"

namespace {

using namespace agvslam::drivers::can;
using agvslam::OdometryRate;

const std::string kDbcPath = std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc";

CanOdometryConfig shipped() {
  CanOdometryConfig c;
  c.dbc = kDbcPath;
  return c;
}

OdometryRate rate(double speed_mps, double yaw_rate_degps) {
  OdometryRate r;
  r.speed_mps = speed_mps;
  r.yaw_rate_radps = yaw_rate_degps * M_PI / 180.0;
  return r;
}

TEST(CanOdometry, DecodesTheShippedMessage) {
  CanOdometryDecoder d(shipped(), FrameLayout{}, "agvslamd.yaml");
  EXPECT_EQ(d.id(), 0x306U);
  EXPECT_FALSE(d.extended());
  // Speed -1.234 m/s = -1234 = 0xFB2E, YawRate 12.5 deg/s = 1250 = 0x04E2, Counter 3 in the high nibble of byte 6.
  CanFrameBytes f = d.encode(rate(-1.234, 12.5), 3);
  EXPECT_EQ(f.id, 0x306U);
  ASSERT_EQ(f.len, 8);
  const std::vector<uint8_t> head = {0x2E, 0xFB, 0xE2, 0x04, 0x00, 0x00, 0x30};
  for (std::size_t i = 0; i < head.size(); ++i) EXPECT_EQ(f.data[i], head[i]) << "byte " << i;
  EXPECT_EQ(f.data[7], frame_crc(f));
  const auto r = d.decode(f, 123456789);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->t_ns, 123456789);
  EXPECT_NEAR(r->speed_mps, -1.234, 1e-9);
  EXPECT_NEAR(r->yaw_rate_radps, 12.5 * M_PI / 180.0, 1e-9);
  EXPECT_EQ(d.stats().accepted, 1U);
}

TEST(CanOdometry, IdMovesWithTheBaseId) {
  EXPECT_EQ(CanOdometryDecoder(shipped(), FrameLayout{0x400, false}, "x").id(), 0x406U);
  const CanOdometryDecoder ext(shipped(), FrameLayout{0x18FF1000, true}, "x");
  EXPECT_EQ(ext.id(), 0x18FF1006U);
  EXPECT_TRUE(ext.extended());
  CanOdometryConfig absolute = shipped();
  absolute.relative_to_base_id = false;
  EXPECT_EQ(CanOdometryDecoder(absolute, FrameLayout{0x400, false}, "x").id(), 0x306U);
}

TEST(CanOdometry, RejectsABadCrcAndACounterThatDidNotAdvance) {
  CanOdometryDecoder d(shipped(), FrameLayout{}, "x");
  ASSERT_TRUE(d.decode(d.encode(rate(1.0, 0.0), 0), 0).has_value());
  CanFrameBytes bad = d.encode(rate(1.0, 0.0), 1);
  bad.data[0] ^= 0x01;  // 1 mm/s off: the Crc no longer matches
  EXPECT_FALSE(d.decode(bad, 1).has_value());
  EXPECT_EQ(d.stats().crc_bad, 1U);
  EXPECT_TRUE(d.decode(d.encode(rate(1.0, 0.0), 1), 2).has_value());
  EXPECT_FALSE(d.decode(d.encode(rate(1.0, 0.0), 1), 3).has_value());  // repeated
  EXPECT_EQ(d.stats().counter_repeated, 1U);
  EXPECT_TRUE(d.decode(d.encode(rate(1.0, 0.0), 4), 4).has_value());  // 2 and 3 lost: accepted, gap counted
  EXPECT_EQ(d.stats().counter_gaps, 1U);
  EXPECT_TRUE(d.decode(d.encode(rate(1.0, 0.0), 5), 5).has_value());
  for (uint8_t c = 6; c < 16; ++c) ASSERT_TRUE(d.decode(d.encode(rate(1.0, 0.0), c), c).has_value());
  EXPECT_TRUE(d.decode(d.encode(rate(1.0, 0.0), 0), 16).has_value());  // the 4-bit counter wraps
  EXPECT_EQ(d.stats().counter_gaps, 1U);
  CanFrameBytes short_frame = d.encode(rate(1.0, 0.0), 1);
  short_frame.len = 3;
  EXPECT_FALSE(d.decode(short_frame, 17).has_value());
  EXPECT_EQ(d.stats().too_short, 1U);
  EXPECT_EQ(d.stats().frames, 18U);
  EXPECT_EQ(d.stats().accepted, 15U);
}

// A vehicle's own message: big-endian (Motorola) speed in km/h, yaw rate in rad/s, no Counter, no Crc.
const char* kVehicleDbc = R"(VERSION ""
BU_: VCU AGV

BO_ 1234 VCU_MOTION: 8 VCU
 SG_ VehSpeed : 7|16@0- (0.01,0) [-327.68|327.67] "km/h" AGV
 SG_ VehYawRate : 23|16@0- (0.0001,0) [-3.2768|3.2767] "rad/s" AGV
 SG_ WheelRpm : 32|16@1+ (1,0) [0|65535] "rpm" AGV
)";

TEST(CanOdometry, ReadsAVehiclesOwnMessage) {
  agvslam::test::TempYaml dbc(kVehicleDbc, "vehicle.dbc");
  CanOdometryConfig c;
  c.dbc = dbc.path();
  c.message = "VCU_MOTION";
  c.relative_to_base_id = false;
  c.speed_signal = "VehSpeed";
  c.yaw_rate_signal = "VehYawRate";
  c.counter_signal = "";
  c.crc_signal = "";
  CanOdometryDecoder d(c, FrameLayout{}, "agvslamd.yaml");
  EXPECT_EQ(d.id(), 1234U);
  CanFrameBytes f;
  f.id = 1234;
  f.len = 8;
  f.data[0] = 0x0E;  // 0x0E10 = 3600 -> 36.00 km/h = 10 m/s
  f.data[1] = 0x10;
  f.data[2] = 0xFC;  // 0xFC18 = -1000 -> -0.1 rad/s
  f.data[3] = 0x18;
  const auto r = d.decode(f, 5);
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->speed_mps, 10.0, 1e-9);
  EXPECT_NEAR(r->yaw_rate_radps, -0.1, 1e-12);
  EXPECT_TRUE(d.decode(f, 6).has_value());  // no counter: a repeated frame is a sample
  const auto back = d.decode(d.encode(*r, 0), 7);
  ASSERT_TRUE(back.has_value());
  EXPECT_NEAR(back->speed_mps, 10.0, 1e-9);

  // A unit this decoder does not know must be named in the config.
  c.speed_signal = "WheelRpm";
  try {
    CanOdometryDecoder bad(c, FrameLayout{}, "agvslamd.yaml");
    FAIL() << "expected InputError";
  } catch (const agvslam::InputError& e) {
    EXPECT_EQ(e.source(), "agvslamd.yaml");
    EXPECT_EQ(e.where(), "can_odometry.speed_unit");
    EXPECT_NE(std::string(e.what()).find("'rpm'"), std::string::npos) << e.what();
  }
  c.speed_unit = "km/h";  // the configured unit wins over the DBC's
  EXPECT_NO_THROW(CanOdometryDecoder(c, FrameLayout{}, "agvslamd.yaml"));
}

// Each bad setting is an InputError naming the daemon's file and the field.
TEST(CanOdometry, ConfigErrorsNameTheFileAndField) {
  auto expect_error = [](const CanOdometryConfig& c, const std::string& field, const std::string& says) {
    try {
      CanOdometryDecoder d(c, FrameLayout{}, "/etc/agvslam/agvslamd.yaml");
      ADD_FAILURE() << "expected InputError for " << field;
    } catch (const agvslam::InputError& e) {
      EXPECT_EQ(e.source(), "/etc/agvslam/agvslamd.yaml") << field;
      EXPECT_EQ(e.where(), field);
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  CanOdometryConfig c = shipped();
  c.dbc = "/nonexistent/vehicle.dbc";
  expect_error(c, "can_odometry.dbc", "/nonexistent/vehicle.dbc does not exist");
  c = shipped();
  c.message = "WHEEL_SPEEDS";
  expect_error(c, "can_odometry.message", "VEHICLE_ODOMETRY");  // lists what the DBC has
  c = shipped();
  c.yaw_rate_signal = "Yaw";
  expect_error(c, "can_odometry.yaw_rate_signal", "YawRate");
  c = shipped();
  c.counter_signal = "Seq";
  expect_error(c, "can_odometry.counter_signal", "Counter");
  c = shipped();
  c.speed_unit = "furlong/fortnight";
  expect_error(c, "can_odometry.speed_unit", "m/s");
  c = shipped();
  c.crc_signal = "Speed";  // not in the last byte
  expect_error(c, "can_odometry.crc_signal", "last byte");
  c = shipped();
  c.message = "AGVSLAM_STATUS";  // an id the pose output sends itself
  c.speed_signal = "LatencyMs";
  c.yaw_rate_signal = "Fps";
  c.yaw_rate_unit = "deg/s";
  c.speed_unit = "m/s";
  expect_error(c, "can_odometry.message", "base_id + 4");
}

}  // namespace
