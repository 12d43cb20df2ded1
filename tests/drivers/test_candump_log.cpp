#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/candump_log.h"

namespace {

using namespace agvslam::drivers::can;

TEST(CandumpLog, ParsesClassicExtendedFdErrorAndRemoteFrames) {
  auto r = parse_candump_line("(1436509052.249713) vcan0 044#2A366C2BBA", "log", 1);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->t_ns, 1436509052249713000LL);
  EXPECT_EQ(r->interface, "vcan0");
  EXPECT_EQ(r->frame.id, 0x44U);
  EXPECT_FALSE(r->frame.extended);
  ASSERT_EQ(r->frame.len, 5);
  EXPECT_EQ(r->frame.data[0], 0x2A);
  EXPECT_EQ(r->frame.data[4], 0xBA);

  r = parse_candump_line("(0.000001) can1 18FF1008##1" + std::string(96, 'A'), "log", 2);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->frame.extended);
  EXPECT_TRUE(r->frame.fd);
  EXPECT_EQ(r->fd_flags, 1);
  EXPECT_EQ(r->frame.id, 0x18FF1008U);
  EXPECT_EQ(r->frame.len, 48);

  r = parse_candump_line("(1.5) can0 20000040#0000000000000000", "log", 3);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->error_frame);
  EXPECT_EQ(r->frame.id & 0x40U, 0x40U);  // CAN_ERR_BUSOFF

  r = parse_candump_line("(1.5) can0 123#R", "log", 4);
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->remote);
  EXPECT_FALSE(parse_candump_line("", "log", 5));
  EXPECT_FALSE(parse_candump_line("# comment", "log", 6));
}

TEST(CandumpLog, FormatAndParseAgree) {
  CanFrameBytes f;
  f.id = 0x301;
  f.len = 8;
  for (int i = 0; i < 8; ++i) f.data[static_cast<std::size_t>(i)] = static_cast<uint8_t>(0x10 * i + 1);
  const std::string line = format_candump_line(f, "vcan0", 1700000000123456000LL);
  EXPECT_EQ(line, "(1700000000.123456) vcan0 301#0111213141516171");
  auto r = parse_candump_line(line, "log", 1);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame.data, f.data);
  EXPECT_EQ(r->frame.len, 8);
}

TEST(CandumpLog, RejectsMalformedLines) {
  for (const char* bad : {"vcan0 123#00", "(1.0) vcan0 12#00", "(1.0) vcan0 123#0",
                          "(1.0) vcan0 123#00112233445566778899", "(x.0) vcan0 123#00"}) {
    try {
      parse_candump_line(bad, "dump.log", 7);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const agvslam::InputError& e) {
      EXPECT_EQ(e.where(), "line 7");
    }
  }
}

// Found by tests/fuzz (candump): seconds whose nanoseconds overflow int64, and a line that ends after the
// interface, were undefined behaviour and an uncaught std::out_of_range.
TEST(CandumpLog, RejectsTimeStampsBeyondInt64AndLinesWithoutAFrame) {
  EXPECT_EQ(parse_candump_line("(9223372035.999999) vcan0 123#00", "dump.log", 1)->t_ns, 9223372035999999000);
  for (const char* bad : {"(9223372036.0) vcan0 123#00", "(11699999999.123456) vcan0 300#00", "(1.0) vcan0   "}) {
    try {
      parse_candump_line(bad, "dump.log", 3);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const agvslam::InputError& e) {
      EXPECT_EQ(e.where(), "line 3") << bad;
    }
  }
}

}  // namespace
