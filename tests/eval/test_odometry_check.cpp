#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "agvslam/core/error.h"
#include "agvslam/eval/odometry_check.h"
#include "agvslam/io/odometry_io.h"
#include "agvslam/sim/simulator.h"
#include "agvslam/sim/wheel_odometry.h"
#include "common/test_data.h"

namespace agvslam::eval {
namespace {

constexpr int64_t kFrameNs = 50'000'000;  // 20 Hz

// A vehicle driving at speed(t) m/s and turning at yaw_rate(t) rad/s (counter-clockwise seen from above), as camera
// poses (x right, y down, z forward) and as the rates its controller reports.
struct Drive {
  Trajectory camera;
  std::vector<OdometryRate> rates;
};
template <class Speed, class YawRate>
Drive drive(int frames, Speed speed, YawRate yaw_rate) {
  Drive d;
  double yaw = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < frames; ++i) {
    const double t = i * 0.05;
    const Eigen::Matrix3d R(Eigen::AngleAxisd(yaw, -Eigen::Vector3d::UnitY()));  // up = -y
    d.camera.push_back({i * kFrameNs, make_se3(R, p)});
    d.rates.push_back({i * kFrameNs, speed(t), yaw_rate(t)});
    // Midpoint integration of the next step, so that the poses follow the rates closely.
    const double mid_yaw = yaw + 0.5 * 0.05 * yaw_rate(t + 0.025);
    const Eigen::Matrix3d R_mid(Eigen::AngleAxisd(mid_yaw, -Eigen::Vector3d::UnitY()));
    p += 0.05 * speed(t + 0.025) * (R_mid * Eigen::Vector3d::UnitZ());
    yaw += 0.05 * yaw_rate(t + 0.025);
  }
  return d;
}

Drive s_curve() {
  return drive(
      400, [](double t) { return t < 1 ? t : 1.0; }, [](double t) { return 0.4 * std::sin(0.5 * t); });
}

TEST(OdometryCheck, AgreesWithTheOdometryItWasDrivenBy) {
  const Drive d = s_curve();
  const OdometryCheckResult r = check_against_odometry(d.camera, BodyAxes::kCamera, planar_track(d.rates));
  EXPECT_EQ(r.frames_compared, 400u);
  EXPECT_NEAR(r.distance_ratio, 1.0, 0.002);
  EXPECT_TRUE(r.distance_within_tolerance);
  EXPECT_LT(r.speed_rmse_mps, 0.01);
  EXPECT_GT(std::abs(r.odometry_heading_change_deg), 30.0);  // it did turn
  EXPECT_NEAR(r.heading_difference_deg, 0.0, 0.2);
  EXPECT_LT(r.max_heading_difference_deg, 0.3);
  EXPECT_EQ(r.disagreeing_windows, 0u);
  EXPECT_TRUE(r.disagreements.empty());
  EXPECT_NEAR(r.duration_s, 19.95, 1e-9);
}

TEST(OdometryCheck, ReportsATrajectoryFivePercentTooLong) {
  Drive d = s_curve();
  for (auto& pose : d.camera) pose.T_w_c.translation() *= 1.05;
  const OdometryCheckResult r = check_against_odometry(d.camera, BodyAxes::kCamera, planar_track(d.rates));
  EXPECT_NEAR(r.distance_ratio, 1.05, 0.003);
  EXPECT_FALSE(r.distance_within_tolerance);  // 3 % tolerance
  EXPECT_NEAR(r.speed_rmse_mps, 0.05, 0.01);  // 5 % of 1 m/s
  EXPECT_EQ(r.disagreeing_windows, 0u);       // 5 % is no 20 % disagreement
}

TEST(OdometryCheck, FlagsTheFramesOfAJumpAndOfAPoseStuckWhileTheWheelsTurn) {
  Drive d = s_curve();
  // Frames 200-219: the pose stands still while the vehicle drives on (tracking frozen), then jumps back on track.
  const SE3d frozen = d.camera[200].T_w_c;
  for (int i = 201; i < 220; ++i) d.camera[static_cast<std::size_t>(i)].T_w_c = frozen;
  const OdometryCheckResult r = check_against_odometry(d.camera, BodyAxes::kCamera, planar_track(d.rates));
  ASSERT_FALSE(r.disagreements.empty());
  bool covers_freeze = false;
  for (const auto& g : r.disagreements) {
    if (g.first_frame <= 205 && g.last_frame >= 215) covers_freeze = true;
    EXPECT_GE(g.last_frame, 195u);   // nothing flagged before it
    EXPECT_LE(g.first_frame, 225u);  // nor long after it
  }
  EXPECT_TRUE(covers_freeze);
}

TEST(OdometryCheck, AStandingVehicleWithJitterDisagreesNowhere) {
  Drive d = drive(
      200, [](double) { return 0.0; }, [](double) { return 0.0; });
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter_m(0, 0.001);
  for (auto& pose : d.camera) pose.T_w_c.translation() += Eigen::Vector3d(jitter_m(rng), jitter_m(rng), jitter_m(rng));
  const OdometryCheckResult r = check_against_odometry(d.camera, BodyAxes::kCamera, planar_track(d.rates));
  EXPECT_TRUE(std::isnan(r.distance_ratio));
  EXPECT_EQ(r.disagreeing_windows, 0u);
}

TEST(OdometryCheck, BaseAxesReadTheSameMotion) {
  // The same drive in REP-103 base_link axes (x forward, z up): camera = base * R_base_cam.
  const Drive d = s_curve();
  Eigen::Matrix3d R_base_cam;
  R_base_cam << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Trajectory base;
  for (const auto& pose : d.camera)
    base.push_back({pose.t_ns, pose.T_w_c * make_se3(R_base_cam.transpose(), Eigen::Vector3d::Zero())});
  const OdometryCheckResult a = check_against_odometry(d.camera, BodyAxes::kCamera, planar_track(d.rates));
  const OdometryCheckResult b = check_against_odometry(base, BodyAxes::kBase, planar_track(d.rates));
  EXPECT_NEAR(a.distance_ratio, b.distance_ratio, 1e-9);
  EXPECT_NEAR(a.heading_difference_deg, b.heading_difference_deg, 1e-6);
  EXPECT_THROW(parse_body_axes("ros", "--trajectory-axes"), InputError);
}

TEST(OdometryCheck, SimulatorGroundTruthAgainstItsWheelOdometryShowsTheOdometryBias) {
  // The simulator's wheel odometry reads distances 1 % long: the ground truth's distance ratio is 1 / 1.01.
  sim::ScenarioOptions scenario;
  scenario.name = "scene4";
  scenario.seed = 7;
  const sim::Simulator simulator(sim::SimConfig{}, scenario);
  const Trajectory gt = simulator.ground_truth();
  const sim::WheelOdometryConfig odometry_config;
  const Trajectory odometry = sim::simulate_wheel_odometry(gt, odometry_config, scenario.seed);
  const OdometryCheckResult r =
      check_against_odometry(gt, BodyAxes::kCamera, planar_track(odometry, BodyAxes::kCamera));
  RecordProperty("gt_distance_ratio", std::to_string(r.distance_ratio));
  RecordProperty("gt_speed_rmse_mps", std::to_string(r.speed_rmse_mps));
  RecordProperty("gt_heading_difference_deg", std::to_string(r.heading_difference_deg));
  EXPECT_GT(r.trajectory_distance_m, 20.0);
  EXPECT_NEAR(r.distance_ratio, 1.0 / (1.0 + odometry_config.distance_scale_error), 0.004);
  EXPECT_TRUE(r.distance_within_tolerance);
  EXPECT_EQ(r.disagreeing_windows, 0u);
  // A SLAM result 5 % too large is reported.
  Trajectory scaled = gt;
  for (auto& pose : scaled) pose.T_w_c.translation() *= 1.05;
  const OdometryCheckResult s =
      check_against_odometry(scaled, BodyAxes::kCamera, planar_track(odometry, BodyAxes::kCamera));
  RecordProperty("scaled_distance_ratio", std::to_string(s.distance_ratio));
  EXPECT_NEAR(s.distance_ratio, 1.05 / 1.01, 0.005);
  EXPECT_FALSE(s.distance_within_tolerance);
}

TEST(OdometryCheck, NoCommonTimeIsAnError) {
  const Drive d = s_curve();
  PlanarTrack later = planar_track(d.rates);
  for (auto& t : later.t_ns) t += 100'000'000'000;
  EXPECT_THROW(check_against_odometry(d.camera, BodyAxes::kCamera, later, {}, "odo.csv"), InputError);
}

class OdometryCsv : public ::testing::Test {
 protected:
  // Each test in its own folder: ctest runs the tests of this file in parallel processes.
  void SetUp() override { dir_ = test::make_temp_dir("agvslam-odometry-csv"); }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }
  std::string write(const std::string& text) {
    const std::string path = dir_ + "/odometry_" + std::to_string(counter_++) + ".csv";
    std::ofstream(path) << text;
    return path;
  }
  std::string dir_;
  int counter_ = 0;
};

TEST_F(OdometryCsv, ReadsSamplesWithAHeader) {
  const std::string path = write("t_s,speed_mps,yaw_rate_radps\n# comment\n0.0,0.5,0.1\n0.05, 0.6 ,-0.2\n");
  EXPECT_TRUE(io::looks_like_odometry_csv(path));
  const auto s = io::read_odometry_csv(path);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].t_ns, 50'000'000);
  EXPECT_DOUBLE_EQ(s[1].speed_mps, 0.6);
  EXPECT_DOUBLE_EQ(s[1].yaw_rate_radps, -0.2);
}

TEST_F(OdometryCsv, BadLinesNameTheFileAndLine) {
  const auto message = [&](const std::string& text) {
    try {
      io::read_odometry_csv(write(text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("0,1,0\n0.05,1\n").find("line 2: expected 3 comma-separated fields"), std::string::npos);
  EXPECT_NE(message("0,1,0\n0.05,x,0\n").find("line 2"), std::string::npos);
  EXPECT_NE(message("0,1,0\n0.05,nan,0\n").find("NaN"), std::string::npos);
  EXPECT_NE(message("0.1,1,0\n0.05,1,0\n").find("increase"), std::string::npos);
  EXPECT_NE(message("0,1,0\n").find("at least 2"), std::string::npos);
  EXPECT_FALSE(io::looks_like_odometry_csv(write("0 0 0 0 0 0 0 1\n")));
}

}  // namespace
}  // namespace agvslam::eval
