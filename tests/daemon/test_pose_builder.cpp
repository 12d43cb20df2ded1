// TrackResult -> PoseSample: the REP-105 base_link pose in the map frame, the finite-difference twist in
// base_link axes, the covariance heuristic, and what a sample without a pose carries.
#include "agvslam/daemon/pose_builder.h"

#include <gtest/gtest.h>

namespace agvslam::daemon {
namespace {

constexpr int64_t kT0 = 1700000000000000000LL;
constexpr int64_t kDt = 50000000LL;  // 20 Hz

SE3d camera_pose(const Eigen::Vector3d& p_w_c, double yaw_left_rad = 0) {
  // A forward-looking optical camera turned left by yaw about its own -y (up) axis.
  return make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(-yaw_left_rad, Eigen::Vector3d::UnitY())), p_w_c);
}

slam::TrackResult tracked(const SE3d& T_w_c, int inliers = 200) {
  slam::TrackResult r;
  r.state = slam::TrackingState::kOk;
  r.pose_valid = true;
  r.T_w_c = T_w_c;
  r.counts.inliers = inliers;
  return r;
}

BaseLinkConfig mount() {
  BaseLinkConfig b;
  b.x_m = 0.3;
  b.z_m = 0.5;
  return b;
}

TEST(PoseSampleBuilder, TheMapFrameIsBaseLinkAtTheFirstKeyframe) {
  PoseSampleBuilder builder(mount().T_base_cam(), CovarianceConfig{});
  drivers::PoseSample s;
  builder.build(tracked(SE3d::Identity()), kT0, s);
  EXPECT_TRUE(s.T_map_base.isApprox(SE3d::Identity(), 1e-12));
  EXPECT_EQ(s.t_ns, kT0);
  EXPECT_EQ(s.tracking_state, drivers::TrackingState::kTracking);
  // The camera moved 2 m along its optical axis and turned 30 degrees left: the vehicle drove 2 m forward (map x)
  // and its heading is +30 degrees; the camera's 0.3 m lever arm moves with the turn.
  const double yaw = 30 * M_PI / 180;
  builder.build(tracked(camera_pose(Eigen::Vector3d(0, 0, 2), yaw)), kT0 + kDt, s);
  EXPECT_NEAR(drivers::yaw_rad(s.T_map_base), yaw, 1e-12);
  const Eigen::Vector3d expected =
      Eigen::Vector3d(0.3 + 2.0, 0, 0) - Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0.3, 0, 0);
  EXPECT_TRUE(s.T_map_base.translation().isApprox(expected, 1e-12)) << s.T_map_base.translation().transpose();
  EXPECT_NEAR(s.T_map_base.translation().z(), 0.0, 1e-12);  // stays on the floor
  // Round trip.
  EXPECT_TRUE(builder.to_camera(s.T_map_base).isApprox(camera_pose(Eigen::Vector3d(0, 0, 2), yaw), 1e-12));
}

TEST(PoseSampleBuilder, TwistIsTheFiniteDifferenceInBaseLinkAxes) {
  BaseLinkConfig b;  // camera at base_link's origin
  PoseSampleBuilder builder(b.T_base_cam(), CovarianceConfig{});
  drivers::PoseSample s;
  // Heading 90 degrees (camera turned left), then 5 cm further along map +y and 0.01 rad more to the left.
  builder.build(tracked(camera_pose(Eigen::Vector3d(0, 0, 0), M_PI / 2)), kT0, s);
  EXPECT_EQ(s.cov_twist(0, 0), kUnknownVariance);  // no previous pose: unknown
  const SE3d T_map_base0 = s.T_map_base;
  // Base pose wanted: T_map_base0 * (forward 5 cm, turn 0.01 rad).
  const SE3d step =
      make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(0.05, 0, 0));
  const SE3d T_map_base1 = T_map_base0 * step;
  builder.build(tracked(builder.to_camera(T_map_base1)), kT0 + kDt, s);
  EXPECT_TRUE(s.v_base_mps.isApprox(Eigen::Vector3d(1.0, 0, 0), 1e-9)) << s.v_base_mps.transpose();
  EXPECT_NEAR(s.w_base_radps.z(), 0.2, 1e-9);
  EXPECT_NEAR(s.w_base_radps.head<2>().norm(), 0.0, 1e-9);
  EXPECT_LT(s.cov_twist(0, 0), 1.0);
}

TEST(PoseSampleBuilder, CovarianceHeuristicScalesWithTheInliers) {
  CovarianceConfig c;
  PoseSampleBuilder builder(SE3d::Identity(), c);
  drivers::PoseSample s;
  builder.build(tracked(SE3d::Identity(), c.reference_inliers), kT0, s);
  EXPECT_NEAR(s.cov_pose(0, 0), c.position_sd_m * c.position_sd_m, 1e-15);
  EXPECT_NEAR(s.cov_pose(5, 5), std::pow(c.rotation_sd_deg * M_PI / 180, 2), 1e-15);
  EXPECT_EQ(s.cov_pose(0, 1), 0.0);
  builder.build(tracked(SE3d::Identity(), c.reference_inliers / 4), kT0 + kDt, s);
  EXPECT_NEAR(s.cov_pose(1, 1), 4 * c.position_sd_m * c.position_sd_m, 1e-15);  // a quarter of the inliers: sd x 2
  builder.build(tracked(SE3d::Identity(), 0), kT0 + 2 * kDt, s);                // floored at min_inliers
  EXPECT_NEAR(s.cov_pose(2, 2), c.position_sd_m * c.position_sd_m * c.reference_inliers / c.min_inliers, 1e-12);
}

TEST(PoseSampleBuilder, ASampleWithoutAPoseCarriesTheLastGoodOneFlaggedByItsState) {
  PoseSampleBuilder builder(mount().T_base_cam(), CovarianceConfig{});
  drivers::PoseSample s;
  slam::TrackResult init;
  init.state = slam::TrackingState::kInitialising;
  builder.build(init, kT0, s);
  EXPECT_EQ(s.tracking_state, drivers::TrackingState::kNotInitialized);
  EXPECT_TRUE(s.T_map_base.isApprox(SE3d::Identity()));
  EXPECT_EQ(s.cov_pose(0, 0), kUnknownVariance);

  builder.build(tracked(camera_pose(Eigen::Vector3d(0, 0, 1))), kT0 + kDt, s);
  const SE3d good = s.T_map_base;
  slam::TrackResult lost;
  lost.state = slam::TrackingState::kLost;
  lost.T_w_c = camera_pose(Eigen::Vector3d(50, 50, 50));  // whatever the tracker left there is never published
  builder.build(lost, kT0 + 2 * kDt, s);
  EXPECT_EQ(s.tracking_state, drivers::TrackingState::kLost);
  EXPECT_TRUE(s.T_map_base.isApprox(good));
  EXPECT_TRUE(s.v_base_mps.isZero());
  EXPECT_EQ(s.cov_twist(3, 3), kUnknownVariance);
  // Tracked again: the twist is unknown until two consecutive frames are tracked.
  builder.build(tracked(camera_pose(Eigen::Vector3d(0, 0, 1.2))), kT0 + 3 * kDt, s);
  EXPECT_EQ(s.cov_twist(0, 0), kUnknownVariance);
  builder.build(tracked(camera_pose(Eigen::Vector3d(0, 0, 1.25))), kT0 + 4 * kDt, s);
  EXPECT_NEAR(s.v_base_mps.x(), 1.0, 1e-9);
}

TEST(PoseSampleBuilder, HeartbeatSaysLostOnceTrackedAndNotInitialisedBefore) {
  drivers::PoseSample s;
  s.T_map_base = make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1, 2, 0));
  s.tracking_state = drivers::TrackingState::kTracking;
  s.v_base_mps = Eigen::Vector3d(1, 0, 0);
  s.frame_index = 41;
  PoseSampleBuilder::build_heartbeat(kT0, true, s);
  EXPECT_EQ(s.tracking_state, drivers::TrackingState::kLost);
  EXPECT_EQ(s.t_ns, kT0);
  EXPECT_EQ(s.frame_index, 41U);
  EXPECT_TRUE(s.v_base_mps.isZero());
  EXPECT_TRUE(s.T_map_base.translation().isApprox(Eigen::Vector3d(1, 2, 0)));
  PoseSampleBuilder::build_heartbeat(kT0, false, s);
  EXPECT_EQ(s.tracking_state, drivers::TrackingState::kNotInitialized);
}

}  // namespace
}  // namespace agvslam::daemon
