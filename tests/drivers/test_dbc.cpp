// The DBC reader on hand-written input, and on deploy/agvslam.dbc (the layout the encoder documents).

#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/dbc.h"

namespace {

using namespace agvslam::drivers::can;

const char* kSmall = R"(VERSION ""
BU_: A B

BO_ 291 MOTOROLA_AND_INTEL: 8 A
 SG_ Be16 : 7|16@0+ (1,0) [0|65535] "" B
 SG_ LeSigned12 : 16|12@1- (0.5,-1) [-1025|1022.5] "m" B
 SG_ Be4 : 39|4@0+ (1,0) [0|15] "" B

BO_ 2566848512 EXTENDED: 2 A
 SG_ Flag : 0|1@1+ (1,0) [0|1] "" B

VAL_ 291 Be4 1 "One" 2 "Two" ;
)";

TEST(Dbc, ParsesMessagesSignalsAndValueNames) {
  const Dbc dbc = Dbc::parse(kSmall, "small.dbc");
  ASSERT_EQ(dbc.messages().size(), 2U);
  const DbcMessage* m = dbc.find(291, false);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->name, "MOTOROLA_AND_INTEL");
  ASSERT_EQ(m->signals.size(), 3U);
  EXPECT_FALSE(m->signals[0].little_endian);
  EXPECT_TRUE(m->signals[1].is_signed);
  EXPECT_EQ(m->signals[1].unit, "m");
  EXPECT_EQ(m->signal("Be4")->value_names.at(2), "Two");
  const DbcMessage* e = dbc.find(0x18FF0000, true);  // 2566848512 = 0x80000000 | 0x18FF0000
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->name, "EXTENDED");
}

TEST(Dbc, DecodesMotorolaAndIntelSignals) {
  const Dbc dbc = Dbc::parse(kSmall, "small.dbc");
  const DbcMessage* m = dbc.find(291, false);
  CanFrameBytes f;
  f.len = 8;
  // Be16: start bit 7 (MSB of byte 0), 16 bits big-endian: bytes 0x12 0x34 -> 0x1234.
  f.data[0] = 0x12;
  f.data[1] = 0x34;
  // LeSigned12 at bits 16..27: raw 0xFFE = -2 -> -2 * 0.5 - 1 = -2.
  f.data[2] = 0xFE;
  f.data[3] = 0x0F;
  // Be4: start bit 39 = bit 7 of byte 4, 4 bits: high nibble of byte 4.
  f.data[4] = 0xA0;
  const auto v = decode_signals(*m, f);
  EXPECT_EQ(v.at("Be16"), 0x1234);
  EXPECT_EQ(v.at("LeSigned12"), -2.0);
  EXPECT_EQ(v.at("Be4"), 10.0);
}

TEST(Dbc, RejectsMalformedLinesWithTheirNumber) {
  try {
    Dbc::parse("BO_ 1 M: 8 A\n SG_ S : 0|8@2+ (1,0) [0|1] \"\" B\n", "bad.dbc");
    FAIL() << "expected InputError";
  } catch (const agvslam::InputError& e) {
    EXPECT_EQ(e.source(), "bad.dbc");
    EXPECT_EQ(e.where(), "line 2");
  }
  EXPECT_THROW(Dbc::parse("BO_ 1 M: 2 A\n SG_ S : 8|16@1+ (1,0) [0|1] \"\" B\n", "x"), agvslam::InputError);
  EXPECT_THROW(Dbc::load("/nonexistent/agvslam.dbc"), agvslam::InputError);
}

// Found by tests/fuzz (dbc): a run of digits beyond unsigned long escaped as std::out_of_range, and ids beyond
// 32 bits were truncated.
TEST(Dbc, RejectsNumbersBeyondTheirField) {
  for (const char* bad :
       {"BO_ 77888888888888888888888 M: 8 A\n", "BO_ 4294967296 M: 8 A\n", "BO_ 1 M: 65 A\n",
        "BO_ 1 M: 8 A\n SG_ S : 99999999999999999999|8@1+ (1,0) [0|1] \"\" B\n",
        "BO_ 1 M: 8 A\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" B\n\nVAL_ 1 S 99999999999999999999 \"x\" ;\n"}) {
    try {
      Dbc::parse(bad, "big.dbc");
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const agvslam::InputError& e) {
      EXPECT_EQ(e.source(), "big.dbc");
    }
  }
}

TEST(Dbc, ShippedDbcDescribesTheEncoderLayout) {
  const Dbc dbc = Dbc::load(std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc");
  struct Want {
    uint32_t id;
    const char* name;
    unsigned len;
    bool fd;
  };
  for (const Want& w : {Want{0x300, "AGVSLAM_POSE_XYAW", 8, false}, Want{0x301, "AGVSLAM_POSE_YZ", 8, false},
                        Want{0x302, "AGVSLAM_VELOCITY", 8, false}, Want{0x303, "AGVSLAM_POSE_STDDEV", 8, false},
                        Want{0x304, "AGVSLAM_STATUS", 8, false}, Want{0x305, "AGVSLAM_ODOM_CHECK", 8, false},
                        Want{0x306, "VEHICLE_ODOMETRY", 8, false}, Want{0x308, "AGVSLAM_POSE_FD", 48, true}}) {
    const DbcMessage* m = dbc.find(w.id, false);
    ASSERT_NE(m, nullptr) << w.name;
    EXPECT_EQ(m->name, w.name);
    EXPECT_EQ(m->length, w.len);
    EXPECT_EQ(m->fd, w.fd);
    // Counter and Crc in every frame; Crc in the last byte.
    const DbcSignal* crc = m->signal("Crc");
    ASSERT_NE(crc, nullptr) << w.name;
    EXPECT_EQ(crc->start_bit, w.len * 8 - 8);
    EXPECT_EQ(crc->length, 8U);
    ASSERT_NE(m->signal("Counter"), nullptr) << w.name;
    for (const auto& s : m->signals) EXPECT_TRUE(s.little_endian) << w.name << "." << s.name;
  }
  EXPECT_EQ(dbc.find(0x300, false)->signal("TrackingState")->value_names.at(3), "Lost");
  // The odometry comes from the vehicle controller, in m/s and deg/s.
  const DbcMessage* odo = dbc.find("VEHICLE_ODOMETRY");
  EXPECT_EQ(odo->transmitter, "VEHICLE_CONTROLLER");
  EXPECT_EQ(odo->signal("Speed")->unit, "m/s");
  EXPECT_EQ(odo->signal("YawRate")->unit, "deg/s");
  EXPECT_EQ(dbc.find("AGVSLAM_ODOM_CHECK")->transmitter, "AGVSLAM");
}

TEST(Dbc, EncodeIsTheInverseOfDecode) {
  const Dbc dbc = Dbc::parse(kSmall, "small.dbc");
  const DbcMessage* m = dbc.find(291, false);
  CanFrameBytes f;
  f.len = 8;
  m->signal("Be16")->encode(0x1234, f.data.data());
  m->signal("LeSigned12")->encode(-2.0, f.data.data());
  m->signal("Be4")->encode(10, f.data.data());
  EXPECT_EQ(f.data[0], 0x12);
  EXPECT_EQ(f.data[1], 0x34);
  EXPECT_EQ(f.data[2], 0xFE);
  EXPECT_EQ(f.data[3], 0x0F);
  EXPECT_EQ(f.data[4], 0xA0);
  // Rounded to the nearest step; clamped to the raw range (12 bits signed: -2048..2047 -> -1025..1022.5).
  m->signal("LeSigned12")->encode(3.26, f.data.data());
  EXPECT_EQ(decode_signals(*m, f).at("LeSigned12"), 3.5);
  m->signal("LeSigned12")->encode(1e9, f.data.data());
  EXPECT_EQ(decode_signals(*m, f).at("LeSigned12"), 1022.5);
  EXPECT_EQ(decode_signals(*m, f).at("Be16"), 0x1234);  // neighbours untouched
}

}  // namespace
