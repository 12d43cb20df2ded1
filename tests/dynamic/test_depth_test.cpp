// Depth-consistency test: PnP ego-motion from tracks with stereo depth; points whose 3-D position disagrees
// with it (motion along the viewing ray, invisible to the epipolar test) are flagged.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/epipolar.h"

namespace agvslam::dynamic {
namespace {

struct Scene {
  PinholeCamera cam;
  double bf = 0;
  SE3d T_cur_prev = SE3d::Identity();
  std::vector<cv::Point2f> prev, cur;
  std::vector<float> d_prev, d_cur;
  std::vector<uint8_t> usable;
};

cv::Point2f project(const PinholeCamera& c, const Eigen::Vector3d& X) {
  const Eigen::Vector2d p = c.project(X);
  return {static_cast<float>(p.x()), static_cast<float>(p.y())};
}

// n static points; the first `movers` move by `motion_m` (in the previous camera frame) between the frames.
// Depths in [z_min, 12] m.
Scene make_scene(int n, int movers, const Eigen::Vector3d& motion_m, double noise_px, uint64_t seed, double z_min = 2.0,
                 double z_max = 12.0) {
  Scene s;
  s.cam.fx = s.cam.fy = 460;
  s.cam.cx = 375.5;
  s.cam.cy = 239.5;
  s.cam.width = 752;
  s.cam.height = 480;
  s.bf = 460 * 0.12;
  // The camera drives 0.15 m straight ahead and turns 1 degree.
  SE3d T_prev_cur = SE3d::Identity();
  T_prev_cur.linear() = Eigen::AngleAxisd(1.0 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_prev_cur.translation() = Eigen::Vector3d(0, 0, 0.15);
  s.T_cur_prev = T_prev_cur.inverse();
  cv::RNG rng(seed);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d X(rng.uniform(-3.0, 3.0), rng.uniform(-1.5, 0.8), rng.uniform(z_min, z_max));
    const Eigen::Vector3d X_moved = i < movers ? Eigen::Vector3d(X + motion_m) : X;
    const Eigen::Vector3d Xc = s.T_cur_prev * X_moved;
    const auto noise = [&] { return static_cast<float>(rng.gaussian(noise_px)); };
    s.prev.push_back(project(s.cam, X) + cv::Point2f(noise(), noise()));
    s.cur.push_back(project(s.cam, Xc) + cv::Point2f(noise(), noise()));
    s.d_prev.push_back(static_cast<float>(s.bf / X.z()) + 0.5f * noise());
    s.d_cur.push_back(static_cast<float>(s.bf / Xc.z()) + 0.5f * noise());
    s.usable.push_back(1);
  }
  return s;
}

// The estimated motion is the scene's within 1 cm and 0.2 degrees.
void expect_true_motion(const DepthTestResult& r, const Scene& s) {
  EXPECT_LT((r.T_cur_prev.translation() - s.T_cur_prev.translation()).norm(), 0.01);
  EXPECT_LT(rotation_angle_rad(r.T_cur_prev.inverse() * s.T_cur_prev), 0.2 * M_PI / 180);
}

TEST(DepthTest, RecoversTheEgoMotionAndPassesStaticPoints) {
  const Scene s = make_scene(150, 0, Eigen::Vector3d::Zero(), 0.2, 3);
  DepthConsistencyTest test;
  DepthTestResult r;
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, r);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.used, 150);
  EXPECT_GT(r.inliers, 140);
  expect_true_motion(r, s);
  int flagged = 0;
  for (uint8_t f : r.dynamic) flagged += f;
  EXPECT_LE(flagged, 2);
}

TEST(DepthTest, FlagsMotionAlongTheViewingRayThatTheEpipolarTestMisses) {
  // 20 points 2-3.5 m away walk 0.4 m towards the camera along the optical axis: their image motion is
  // radial from the principal point, (almost) along the epipolar lines through the focus of expansion.
  // (The disparity change of such a walker is bf dz / z^2: 1.8-5.5 px here, but only 0.15 px at 12 m.)
  Scene s = make_scene(150, 0, Eigen::Vector3d::Zero(), 0.15, 4);
  const Scene moving = make_scene(20, 20, Eigen::Vector3d(0, 0, -0.4), 0.15, 5, 2.0, 3.5);
  for (std::size_t i = 0; i < moving.prev.size(); ++i) {
    s.prev.insert(s.prev.begin(), moving.prev[i]);
    s.cur.insert(s.cur.begin(), moving.cur[i]);
    s.d_prev.insert(s.d_prev.begin(), moving.d_prev[i]);
    s.d_cur.insert(s.d_cur.begin(), moving.d_cur[i]);
    s.usable.insert(s.usable.begin(), 1);
  }
  DepthConsistencyTest test;
  DepthTestResult r;
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, r);
  ASSERT_TRUE(r.valid);
  int movers = 0, statics = 0;
  for (std::size_t i = 0; i < s.prev.size(); ++i) (i < 20 ? movers : statics) += r.dynamic[i];
  EXPECT_GE(movers, 19);
  EXPECT_LE(statics, 2);
  for (std::size_t i = 0; i < 20; ++i) EXPECT_GT(r.disparity_residual_px[i], 1.0);

  // The epipolar test on the same tracks flags far fewer of the movers (motion mostly along the lines).
  EpipolarTestConfig ec;
  EpipolarResult er;
  EpipolarTest(ec).run(s.prev, s.cur, s.usable, s.d_cur, er);
  ASSERT_TRUE(er.valid);
  int epi_movers = 0;
  for (std::size_t i = 0; i < 20; ++i) epi_movers += er.dynamic[i];
  EXPECT_LT(epi_movers, movers);
}

TEST(DepthTest, AMotionPriorReplacesRansacOnlyWhenMostTracksAgreeWithIt) {
  // 150 static tracks and 40 movers (0.3 m sideways): 79 % of the tracks agree with the true motion.
  Scene s = make_scene(150, 0, Eigen::Vector3d::Zero(), 0.2, 7);
  const Scene moving = make_scene(40, 40, Eigen::Vector3d(0.3, 0, 0), 0.2, 8, 2.0, 5.0);
  s.prev.insert(s.prev.begin(), moving.prev.begin(), moving.prev.end());
  s.cur.insert(s.cur.begin(), moving.cur.begin(), moving.cur.end());
  s.d_prev.insert(s.d_prev.begin(), moving.d_prev.begin(), moving.d_prev.end());
  s.d_cur.insert(s.d_cur.begin(), moving.d_cur.begin(), moving.d_cur.end());
  s.usable.insert(s.usable.begin(), moving.usable.begin(), moving.usable.end());
  DepthTestConfig c;
  c.prior_min_inlier_fraction = 0.5;
  DepthConsistencyTest test(c);

  // A prior 1 cm and 0.1 degrees off the truth: its inliers are static tracks, and the refinement lands on the truth
  // (as RANSAC does without the prior).
  SE3d near_truth = s.T_cur_prev;
  near_truth.translation() += Eigen::Vector3d(0.01, 0, 0);
  near_truth.linear() =
      Eigen::AngleAxisd(0.1 * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix() * near_truth.linear();
  DepthTestResult with_prior, without;
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, with_prior, &near_truth);
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, without);
  ASSERT_TRUE(with_prior.valid);
  ASSERT_TRUE(without.valid);
  EXPECT_TRUE(with_prior.from_prior);
  EXPECT_FALSE(without.from_prior);
  // Its inliers: static tracks only (the movers are >= 25 px off), the nearest ones lost to the prior's 1 cm.
  EXPECT_GE(with_prior.inliers, 120);
  EXPECT_LE(with_prior.inliers, 150);
  expect_true_motion(with_prior, s);
  int movers = 0, statics = 0, same = 0;
  for (std::size_t i = 0; i < s.prev.size(); ++i) {
    (i < 40 ? movers : statics) += with_prior.dynamic[i];
    same += with_prior.dynamic[i] == without.dynamic[i];
  }
  EXPECT_GE(movers, 38);
  EXPECT_LE(statics, 2);
  EXPECT_GE(same, static_cast<int>(s.prev.size()) - 2);

  // A prior 0.3 m off (a broken chain) holds too few tracks: RANSAC decides, and finds the truth.
  SE3d wrong = s.T_cur_prev;
  wrong.translation() += Eigen::Vector3d(0.3, 0, 0);
  DepthTestResult fallback;
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, fallback, &wrong);
  ASSERT_TRUE(fallback.valid);
  EXPECT_FALSE(fallback.from_prior);
  expect_true_motion(fallback, s);

  // With prior_min_inlier_fraction 0 the prior is ignored.
  DepthTestConfig never;
  never.prior_min_inlier_fraction = 0;
  DepthTestResult ignored;
  DepthConsistencyTest(never).run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, ignored, &near_truth);
  EXPECT_FALSE(ignored.from_prior);
}

TEST(DepthTest, RansacFindsTheMotionAmongThirtyPercentOutliersAndRepeatsItself) {
  // 140 static tracks and 60 gross mismatches (tracked 5-40 px off): the P3P RANSAC's motion is the true one, its
  // inliers are the static tracks, and a second run gives the same motion (fixed seed).
  Scene s = make_scene(200, 0, Eigen::Vector3d::Zero(), 0.2, 9);
  cv::RNG rng(10);
  for (std::size_t i = 0; i < 60; ++i) {
    const double angle = rng.uniform(0.0, 2 * M_PI), length = rng.uniform(5.0, 40.0);
    s.cur[i] += cv::Point2f(static_cast<float>(length * std::cos(angle)), static_cast<float>(length * std::sin(angle)));
  }
  DepthConsistencyTest test;
  DepthTestResult a, b;
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, a);
  test.run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, b);
  ASSERT_TRUE(a.valid);
  EXPECT_FALSE(a.from_prior);
  EXPECT_GE(a.inliers, 130);
  EXPECT_LE(a.inliers, 142);
  expect_true_motion(a, s);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_TRUE(a.T_cur_prev.isApprox(b.T_cur_prev, 0.0));
  int mismatches_flagged = 0, statics_flagged = 0;
  for (std::size_t i = 0; i < s.prev.size(); ++i) (i < 60 ? mismatches_flagged : statics_flagged) += a.dynamic[i];
  EXPECT_GE(mismatches_flagged, 57);
  EXPECT_LE(statics_flagged, 2);
}

TEST(DepthTest, NeedsEnoughPointsWithDepth) {
  Scene s = make_scene(30, 0, Eigen::Vector3d::Zero(), 0.1, 6);
  for (std::size_t i = 0; i < 25; ++i) s.d_prev[i] = 0;  // no previous disparity
  DepthTestResult r;
  DepthConsistencyTest().run(s.cam, s.bf, s.prev, s.d_prev, s.cur, s.d_cur, s.usable, r);
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.used, 5);
  for (uint8_t f : r.dynamic) EXPECT_EQ(f, 0);
  for (double v : r.reprojection_px) EXPECT_EQ(v, -1.0);
}

TEST(DepthTest, TheDisparitySlackPassesANearStaticPointAtSpeedButNotAMover) {
  // KITTI's camera (fx 718 px, bf 387 px m) drives 2.5 m ahead in one frame. A road point 7 m ahead and 3 m left
  // was matched 5 % off in disparity: its prediction moves by several px.
  PinholeCamera cam;
  cam.fx = cam.fy = 718;
  cam.cx = 607;
  cam.cy = 185;
  cam.width = 1241;
  cam.height = 376;
  const double bf = 387;
  SE3d T_cur_prev = SE3d::Identity();
  T_cur_prev.translation() = Eigen::Vector3d(0, 0, -2.5);
  const Eigen::Vector3d X(-3.0, 1.6, 7.0);
  const cv::Point2f prev = project(cam, X);
  const cv::Point2f cur = project(cam, T_cur_prev * X);
  const float d_true = static_cast<float>(bf / X.z());
  const float d_measured = 1.05f * d_true;
  const float d_cur = static_cast<float>(bf / (T_cur_prev * X).z());

  DepthTestConfig c;
  c.disparity_slack_px = 0;
  c.disparity_slack_rel = 0;
  const DepthConsistencyTest exact(c);
  c.disparity_slack_px = 0.5;
  c.disparity_slack_rel = 0.08;
  const DepthConsistencyTest slack(c);
  double reproj_exact = -1, reproj_slack = -1, disp_exact = -1, disp_slack = -1;
  exact.slack_residuals(cam, bf, T_cur_prev, prev, d_measured, cur, d_cur, reproj_exact, disp_exact);
  slack.slack_residuals(cam, bf, T_cur_prev, prev, d_measured, cur, d_cur, reproj_slack, disp_slack);
  EXPECT_GT(reproj_exact, 5.0);
  EXPECT_LT(reproj_slack, 0.5);
  // The disparity residual is not relaxed: a slack there would hide motion along the viewing ray.
  EXPECT_DOUBLE_EQ(disp_slack, disp_exact);

  // A car beside the road moving 0.5 m sideways is still far off: the slack only moves the prediction along its ray.
  const cv::Point2f moved = project(cam, T_cur_prev * (X + Eigen::Vector3d(0.5, 0, 0)));
  slack.slack_residuals(cam, bf, T_cur_prev, prev, d_measured, moved, d_cur, reproj_slack, disp_slack);
  EXPECT_GT(reproj_slack, 20.0);
  // ... and so is one that came 1 m nearer along the ray (the slack hides a fraction of the translation, 0.2 m here),
  // whose disparity residual is not relaxed at all.
  const Eigen::Vector3d X_nearer = T_cur_prev * (X * (6.0 / 7.0));
  slack.slack_residuals(cam, bf, T_cur_prev, prev, d_true, project(cam, X_nearer),
                        static_cast<float>(bf / X_nearer.z()), reproj_slack, disp_slack);
  EXPECT_GT(reproj_slack, 10.0);
  EXPECT_GT(disp_slack, 10.0);
}

TEST(DepthTest, InvalidConfigNamesTheField) {
  DepthTestConfig c;
  c.max_scale = 0.5;
  EXPECT_THROW(c.validate("x.yaml"), InputError);
  try {
    c.validate("x.yaml");
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "depth_test.max_scale");
  }
}

TEST(DepthTest, APriorFractionOutsideZeroToOneIsRejected) {
  DepthTestConfig c;
  c.prior_min_inlier_fraction = 1.5;
  try {
    c.validate("x.yaml");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "depth_test.prior_min_inlier_fraction");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
