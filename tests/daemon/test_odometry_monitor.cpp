// The live odometry monitor on synthetic drives: wheel odometry at 50 Hz and SLAM poses at 20 Hz of one vehicle
// driving an S-curve at 1 m/s, the poses with a scale error or a heading drift where a test wants one.

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "agvslam/daemon/odometry_monitor.h"

namespace {

using agvslam::OdometryRate;
using agvslam::SE3d;
using agvslam::daemon::OdometryMonitor;
using agvslam::daemon::OdometryMonitorConfig;
using agvslam::drivers::OdometryCheck;
using agvslam::drivers::OdometryCheckState;

constexpr int64_t kT0 = 1700000000000000000LL;  // CLOCK_REALTIME-like stamps
constexpr int64_t kMs = 1000000;

struct Drive {
  double speed_mps = 1.0;
  double slam_scale = 1.0;  // SLAM path length / true path length
  double slam_heading_drift_degps = 0;
  bool odometry = true;
  int64_t odometry_stops_at_ms = -1;  // -1: never
  bool slam_moves_while_standing = false;
};

// Yaw rate of the S-curve: +-10 deg/s, changing sign every 4 s.
double yaw_rate_radps(double t_s) { return (std::fmod(t_s, 8.0) < 4.0 ? 10.0 : -10.0) * M_PI / 180.0; }

// Runs `duration_ms` of the drive through a monitor (1 ms integration steps); returns the check of the last pose.
// The odometry reaches the monitor `odometry_lead_ms` ahead of the pose of the same time (the pipeline's latency).
OdometryCheck run(OdometryMonitor& m, const Drive& d, int64_t duration_ms, int64_t odometry_lead_ms = 100) {
  std::vector<OdometryRate> odometry;
  std::vector<std::pair<int64_t, SE3d>> poses;
  double x = 0, y = 0, yaw = 0;
  for (int64_t ms = 0; ms <= duration_ms; ++ms) {
    const double t_s = static_cast<double>(ms) * 1e-3;
    const int64_t t_ns = kT0 + ms * kMs;
    const double w = d.speed_mps > 0 ? yaw_rate_radps(t_s) : 0.0;
    if (ms % 20 == 0 && d.odometry && (d.odometry_stops_at_ms < 0 || ms < d.odometry_stops_at_ms)) {
      odometry.push_back(OdometryRate{t_ns, d.speed_mps, w});
    }
    if (ms % 50 == 0) {
      const double slam_yaw = yaw + d.slam_heading_drift_degps * t_s * M_PI / 180.0;
      const double drift_x = d.slam_moves_while_standing ? 0.5 * t_s : 0.0;
      poses.emplace_back(t_ns,
                         agvslam::make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(slam_yaw, Eigen::Vector3d::UnitZ())),
                                           Eigen::Vector3d(d.slam_scale * x + drift_x, d.slam_scale * y, 0.0)));
    }
    x += d.speed_mps * std::cos(yaw) * 1e-3;
    y += d.speed_mps * std::sin(yaw) * 1e-3;
    yaw += w * 1e-3;
  }
  OdometryCheck last;
  std::size_t next = 0;
  for (const auto& [t_ns, T] : poses) {
    while (next < odometry.size() && odometry[next].t_ns <= t_ns + odometry_lead_ms * kMs)
      m.add_odometry(odometry[next++]);
    last = m.add_pose(t_ns, T, true);
  }
  return last;
}

TEST(OdometryMonitor, AgreeingDriveAgrees) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  const OdometryCheck c = run(m, Drive{}, 12000);
  EXPECT_EQ(c.state, OdometryCheckState::kAgrees);
  EXPECT_NEAR(c.distance_ratio, 1.0, 0.01);
  EXPECT_LT(c.speed_rmse_mps, 0.02);
  EXPECT_LT(std::abs(c.heading_difference_deg), 0.5);
  EXPECT_NEAR(c.window_s, 5.0, 0.06);
}

// A slow pipeline (poses 8 s behind the odometry, as in the emulated VM) still compares full windows.
TEST(OdometryMonitor, PosesLaggingTheOdometryCompareFullWindows) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  const OdometryCheck c = run(m, Drive{}, 20000, 8000);
  EXPECT_EQ(c.state, OdometryCheckState::kAgrees);
  EXPECT_NEAR(c.window_s, 5.0, 0.06);
  EXPECT_NEAR(c.distance_ratio, 1.0, 0.01);
}

TEST(OdometryMonitor, FivePercentScaleErrorIsReportedButAgrees) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.slam_scale = 1.05;
  const OdometryCheck c = run(m, d, 12000);
  EXPECT_EQ(c.state, OdometryCheckState::kAgrees);  // inside the 20 % tolerance
  EXPECT_NEAR(c.distance_ratio, 1.05, 0.01);
  EXPECT_NEAR(c.speed_rmse_mps, 0.05, 0.01);
}

TEST(OdometryMonitor, TwentyFivePercentScaleErrorDisagrees) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.slam_scale = 1.25;
  const OdometryCheck c = run(m, d, 12000);
  EXPECT_EQ(c.state, OdometryCheckState::kDisagrees);
  EXPECT_NEAR(c.distance_ratio, 1.25, 0.01);
  // The same error the other way (SLAM too short).
  OdometryMonitor m2{OdometryMonitorConfig{}};
  d.slam_scale = 0.75;
  EXPECT_EQ(run(m2, d, 12000).state, OdometryCheckState::kDisagrees);
}

TEST(OdometryMonitor, HeadingDriftDisagrees) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.slam_heading_drift_degps = 3.0;  // 15 deg over the 5 s window, against a tolerance of 0.2 * 25 deg
  const OdometryCheck c = run(m, d, 12000);
  EXPECT_EQ(c.state, OdometryCheckState::kDisagrees);
  EXPECT_NEAR(c.heading_difference_deg, 15.0, 0.5);
  EXPECT_NEAR(c.distance_ratio, 1.0, 0.01);  // the distance itself agrees
  // 0.5 deg/s (2.5 deg per window) stays inside.
  OdometryMonitor m2{OdometryMonitorConfig{}};
  d.slam_heading_drift_degps = 0.5;
  EXPECT_EQ(run(m2, d, 12000).state, OdometryCheckState::kAgrees);
}

TEST(OdometryMonitor, StaleOdometryIsItsOwnState) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.odometry_stops_at_ms = 8000;
  EXPECT_EQ(run(m, d, 8400).state, OdometryCheckState::kAgrees);  // 400 ms without: not stale yet (500 ms)
  OdometryMonitor m2{OdometryMonitorConfig{}};
  const OdometryCheck c = run(m2, d, 9000);
  EXPECT_EQ(c.state, OdometryCheckState::kStale);
  // Heartbeats (no pose) judge staleness at their own time.
  EXPECT_EQ(m.status_at(kT0 + 8400 * kMs).state, OdometryCheckState::kAgrees);
  EXPECT_EQ(m.status_at(kT0 + 8600 * kMs).state, OdometryCheckState::kStale);
}

TEST(OdometryMonitor, NoOdometryYet) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.odometry = false;
  EXPECT_EQ(run(m, d, 6000).state, OdometryCheckState::kNoOdometry);
  EXPECT_EQ(m.status_at(kT0).state, OdometryCheckState::kNoOdometry);
}

TEST(OdometryMonitor, StandingStillIsTooLittleMotionUnlessTheSlamMoves) {
  OdometryMonitor m{OdometryMonitorConfig{}};
  Drive d;
  d.speed_mps = 0.0;
  const OdometryCheck c = run(m, d, 8000);
  EXPECT_EQ(c.state, OdometryCheckState::kTooLittleMotion);
  EXPECT_TRUE(std::isnan(c.distance_ratio));  // the odometry did not move
  // The vehicle stands, the pose drifts away at 0.5 m/s: that is what the check is for.
  OdometryMonitor m2{OdometryMonitorConfig{}};
  d.slam_moves_while_standing = true;
  EXPECT_EQ(run(m2, d, 8000).state, OdometryCheckState::kDisagrees);
}

TEST(OdometryMonitor, TrackingLossRestartsTheWindow) {
  OdometryMonitor young{OdometryMonitorConfig{}};
  EXPECT_EQ(run(young, Drive{}, 3000).state, OdometryCheckState::kTooLittleMotion);  // window not full yet
  OdometryMonitor m{OdometryMonitorConfig{}};
  EXPECT_EQ(run(m, Drive{}, 6000).state, OdometryCheckState::kAgrees);
  const OdometryCheck lost = m.add_pose(kT0 + 6100 * kMs, SE3d::Identity(), false);
  EXPECT_EQ(lost.state, OdometryCheckState::kTooLittleMotion);
  // Out-of-order odometry is dropped and counted.
  const uint64_t before = m.odometry_samples();
  m.add_odometry(OdometryRate{kT0, 1.0, 0.0});
  EXPECT_EQ(m.odometry_samples(), before);
  EXPECT_EQ(m.odometry_out_of_order(), 1U);
}

}  // namespace
