// The CAN publisher without a bus (this host's kernel has no CAN; the real-bus test runs in the VM:
// tests/drivers/can_vcan_test.sh): it must never throw or block when the interface cannot be opened, count what it
// could not send, keep retrying with back-off, decimate to its rate and roll its counter.

#include <gtest/gtest.h>

#include <thread>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/can_publisher.h"

namespace {

using namespace agvslam::drivers;
using namespace agvslam::drivers::can;

CanConfig missing_interface() {
  CanConfig c;
  c.interface = "agvnone0";  // no such interface (or no PF_CAN at all)
  c.rate_hz = 0.0;
  return c;
}

TEST(CanPublisher, MissingInterfaceIsCountedNotThrown) {
  CanConfig c = missing_interface();
  c.reopen_min_ms = 60000;  // no second attempt within this test
  c.reopen_max_ms = 60000;
  CanPosePublisher pub(c);
  EXPECT_FALSE(pub.is_open());
  EXPECT_NE(pub.last_error().find("agvnone0"), std::string::npos) << pub.last_error();
  for (std::size_t i = 0; i < 100; ++i) {
    const CanPublishResult r = pub.publish(synthetic_pose_sample(i, static_cast<int64_t>(i) * 50000000));
    EXPECT_TRUE(r.due);
    EXPECT_FALSE(r.sent);
    EXPECT_EQ(r.frames_sent, 0);
  }
  const CanPublisherStats st = pub.stats();
  EXPECT_EQ(st.poses_submitted, 100U);
  EXPECT_EQ(st.cycles, 100U);
  EXPECT_EQ(st.frames_dropped_down, 500U);  // 5 classic frames per cycle
  EXPECT_EQ(st.frames_sent, 0U);
  EXPECT_EQ(st.reopen_attempts, 1U);
  EXPECT_EQ(st.reopens, 0U);
  EXPECT_FALSE(st.open);
}

TEST(CanPublisher, KeepsRetryingWithBackoff) {
  CanConfig c = missing_interface();
  c.reopen_min_ms = 1;
  c.reopen_max_ms = 2;
  CanPosePublisher pub(c);
  for (std::size_t i = 0; i < 5; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // longer than the back-off
    pub.publish(synthetic_pose_sample(i, static_cast<int64_t>(i) * 50000000));
  }
  EXPECT_EQ(pub.stats().reopen_attempts, 6U);  // the constructor's and one per publish
}

TEST(CanPublisher, DecimatesToItsRateByCaptureTimeAndRollsTheCounter) {
  CanConfig c = missing_interface();
  c.rate_hz = 20.0;
  c.reopen_min_ms = 60000;
  c.reopen_max_ms = 60000;
  CanPosePublisher pub(c);
  std::vector<int64_t> due_t_ns;
  std::vector<int> counters;
  for (int i = 0; i < 90; ++i) {  // 3 s at 30 Hz
    const int64_t t_ns = 1700000000000000000LL + static_cast<int64_t>(i) * 1000000000 / 30;
    const CanPublishResult r = pub.publish(synthetic_pose_sample(static_cast<uint64_t>(i), t_ns));
    if (r.due) {
      due_t_ns.push_back(t_ns);
      counters.push_back(r.counter);
    }
  }
  EXPECT_GE(due_t_ns.size(), 59U);
  EXPECT_LE(due_t_ns.size(), 61U);
  for (std::size_t k = 1; k < due_t_ns.size(); ++k) {
    EXPECT_GE(due_t_ns[k] - due_t_ns[k - 1], 30000000);  // never two poses within one 30 Hz frame
    EXPECT_EQ(counters[k], (counters[k - 1] + 1) % 16);
  }
}

TEST(CanPublisher, FdNeedsAnFdInterface) {
  CanConfig c = missing_interface();
  c.fd = true;
  c.reopen_min_ms = 60000;
  c.reopen_max_ms = 60000;
  CanPosePublisher pub(c);
  const CanPublishResult r = pub.publish(synthetic_pose_sample(0, 0));
  EXPECT_TRUE(r.due);
  EXPECT_EQ(pub.stats().frames_dropped_down, 1U);  // one FD frame per cycle
}

TEST(CanConfig, ValidatesAndDescribes) {
  CanConfig c;
  EXPECT_NO_THROW(c.validate("agvslamd.yaml"));
  EXPECT_NE(c.describe().find("base_id=0x300, extended_ids=false"), std::string::npos) << c.describe();
  c.base_id = 0x7FC;  // + 8 exceeds 11 bits
  try {
    c.validate("agvslamd.yaml");
    FAIL();
  } catch (const agvslam::InputError& e) {
    EXPECT_EQ(e.where(), "can.base_id");
  }
  c.extended_ids = true;
  EXPECT_NO_THROW(c.validate("agvslamd.yaml"));
  c = CanConfig{};
  c.interface = "";
  EXPECT_THROW(c.validate("x"), agvslam::InputError);
  c = CanConfig{};
  c.reopen_max_ms = 10;
  EXPECT_THROW(c.validate("x"), agvslam::InputError);
  c = CanConfig{};
  c.rate_hz = -1;
  EXPECT_THROW(c.validate("x"), agvslam::InputError);
}

}  // namespace
