// Epipolar test (paper 004, eqs. 1-3), LK tracking, adaptive threshold, static-camera fallback.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/epipolar.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {

cv::Matx33d skew(const cv::Vec3d& t) { return {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0}; }

struct TwoViews {
  cv::Matx33d K{450, 0, 376, 0, 450, 240, 0, 0, 1};
  cv::Matx33d R;  // R_cur_prev
  cv::Vec3d t;    // t_cur_prev
  cv::Matx33d F;  // x_cur^T F x_prev = 0
  TwoViews() {
    cv::Mat r;
    cv::Rodrigues(cv::Vec3d(0.01, -0.03, 0.005), r);
    R = cv::Matx33d(r);
    t = cv::Vec3d(0.2, 0.03, 0.5);
    F = K.inv().t() * skew(t) * R * K.inv();
  }
  cv::Point2f project(const cv::Vec3d& X_cam) const {
    const cv::Vec3d p = K * X_cam;
    return {static_cast<float>(p[0] / p[2]), static_cast<float>(p[1] / p[2])};
  }
  // Unit normal of the epipolar line of p_prev in the current image.
  cv::Point2f line_normal(const cv::Point2f& p_prev) const {
    const cv::Vec3d l = F * cv::Vec3d(p_prev.x, p_prev.y, 1);
    const double n = std::hypot(l[0], l[1]);
    return {static_cast<float>(l[0] / n), static_cast<float>(l[1] / n)};
  }
};

TEST(EpipolarDistance, ZeroOnTheLineAndTheOffsetOffIt) {
  const TwoViews v;
  cv::RNG rng(5);
  for (int i = 0; i < 50; ++i) {
    const cv::Vec3d X(rng.uniform(-3.0, 3.0), rng.uniform(-2.0, 2.0), rng.uniform(2.0, 15.0));
    const cv::Point2f p_prev = v.project(X);
    const cv::Point2f p_cur = v.project(v.R * X + v.t);
    EXPECT_NEAR(epipolar_distance_px(v.F, p_prev, p_cur), 0.0, 2e-3);
    const double offset = rng.uniform(0.5, 10.0);
    const cv::Point2f n = v.line_normal(p_prev);
    EXPECT_NEAR(epipolar_distance_px(v.F, p_prev, p_cur + static_cast<float>(offset) * n), offset, 2e-3);
    EXPECT_NEAR(epipolar_distance_px(v.F, p_prev, p_cur - static_cast<float>(offset) * n), offset, 2e-3);
    // Moving along the line changes nothing.
    const cv::Point2f along(-n.y, n.x);
    EXPECT_NEAR(epipolar_distance_px(v.F, p_prev, p_cur + 7.0f * along), 0.0, 2e-3);
    // Scale of F does not matter.
    EXPECT_NEAR(epipolar_distance_px(v.F * 1e4, p_prev, p_cur + static_cast<float>(offset) * n), offset, 2e-3);
  }
}

struct Tracks {
  std::vector<cv::Point2f> prev, cur;
  std::vector<uint8_t> usable;
  std::vector<float> disparity;
  std::vector<int> moving;  // indices of moved points
};

Tracks make_tracks(const TwoViews& v, int n, double noise_px, int movers, double move_px, uint64_t seed) {
  Tracks t;
  cv::RNG rng(seed);
  for (int i = 0; i < n; ++i) {
    const cv::Vec3d X(rng.uniform(-4.0, 4.0), rng.uniform(-2.5, 2.5), rng.uniform(2.0, 20.0));
    cv::Point2f a = v.project(X), b = v.project(v.R * X + v.t);
    b += cv::Point2f(static_cast<float>(rng.gaussian(noise_px)), static_cast<float>(rng.gaussian(noise_px)));
    if (i < movers) {
      b += static_cast<float>(move_px) * v.line_normal(a);
      t.moving.push_back(i);
    }
    t.prev.push_back(a);
    t.cur.push_back(b);
    t.usable.push_back(1);
    t.disparity.push_back(static_cast<float>(450 * 0.12 / X[2]));
  }
  return t;
}

TEST(EpipolarTest, FlagsPointsOffTheirEpipolarLines) {
  const TwoViews v;
  const Tracks t = make_tracks(v, 200, 0.15, 20, 6.0, 7);
  EpipolarTestConfig c;
  c.adaptive = false;
  EpipolarTest test(c);
  EpipolarResult r;
  test.run(t.prev, t.cur, t.usable, t.disparity, r);
  ASSERT_TRUE(r.valid);
  EXPECT_FALSE(r.static_camera);
  EXPECT_GE(r.inliers, 170);
  int flagged_movers = 0, flagged_static = 0;
  for (std::size_t i = 0; i < t.prev.size(); ++i) {
    const bool mover = static_cast<int>(i) < 20;
    (mover ? flagged_movers : flagged_static) += r.dynamic[i];
    EXPECT_NEAR(r.t_epi_px[i], c.a_epi_px + c.b_epi * t.disparity[i], 1e-9);  // eq. 3
  }
  EXPECT_EQ(flagged_movers, 20);
  EXPECT_LE(flagged_static, 2);
}

TEST(EpipolarTest, AdaptiveThresholdFollowsTheResidualScale) {
  const TwoViews v;
  // Noisy tracks (sigma 0.8 px per axis): with the fixed a_epi = 1 px many static points would be flagged.
  const Tracks t = make_tracks(v, 300, 0.8, 15, 12.0, 8);
  EpipolarTestConfig fixed;
  fixed.adaptive = false;
  fixed.ransac_threshold_px = 2.0;
  EpipolarTestConfig adaptive = fixed;
  adaptive.adaptive = true;
  adaptive.a_epi_max_px = 5.0;
  EpipolarResult rf, ra;
  EpipolarTest(fixed).run(t.prev, t.cur, t.usable, t.disparity, rf);
  EpipolarTest(adaptive).run(t.prev, t.cur, t.usable, t.disparity, ra);
  auto static_flags = [&](const EpipolarResult& r) {
    int n = 0;
    for (std::size_t i = 15; i < r.dynamic.size(); ++i) n += r.dynamic[i];
    return n;
  };
  EXPECT_GT(static_flags(rf), 15);
  EXPECT_LE(static_flags(ra), 3);
  // The distance of a point to its line is ~ N(0, 0.8): sigma estimate about 0.8, a = 3 sigma.
  EXPECT_NEAR(ra.robust_sigma_px, 0.8, 0.2);
  EXPECT_NEAR(ra.a_epi_used_px, 3 * ra.robust_sigma_px, 1e-9);
  int movers = 0;
  for (int i = 0; i < 15; ++i) movers += ra.dynamic[static_cast<std::size_t>(i)];
  EXPECT_GE(movers, 14);
  // Clamped below by a_epi_px when the residuals are tiny.
  const Tracks clean = make_tracks(v, 100, 0.0, 0, 0.0, 9);
  EpipolarResult rc;
  EpipolarTest(adaptive).run(clean.prev, clean.cur, clean.usable, clean.disparity, rc);
  EXPECT_DOUBLE_EQ(rc.a_epi_used_px, adaptive.a_epi_px);
}

TEST(EpipolarTest, StaticCameraUsesTheTrackLength) {
  std::vector<cv::Point2f> prev, cur;
  std::vector<uint8_t> usable;
  std::vector<float> d;
  cv::RNG rng(4);
  for (int i = 0; i < 60; ++i) {
    const cv::Point2f p(rng.uniform(20.f, 700.f), rng.uniform(20.f, 460.f));
    prev.push_back(p);
    cur.push_back(p + cv::Point2f(static_cast<float>(rng.gaussian(0.05)), static_cast<float>(rng.gaussian(0.05))));
    usable.push_back(1);
    d.push_back(10.f);
  }
  for (int i = 0; i < 5; ++i) cur[static_cast<std::size_t>(i)] += cv::Point2f(3.f, 1.f);  // movers
  usable[59] = 0;
  cur[59] += cv::Point2f(30.f, 0.f);  // unusable: ignored
  EpipolarResult r;
  EpipolarTest().run(prev, cur, usable, d, r);
  ASSERT_TRUE(r.valid);
  EXPECT_TRUE(r.static_camera);
  for (int i = 0; i < 59; ++i) EXPECT_EQ(r.dynamic[static_cast<std::size_t>(i)] != 0, i < 5) << i;
  EXPECT_EQ(r.dynamic[59], 0);
  EXPECT_NEAR(r.d_epi_px[0], std::hypot(3.0, 1.0), 0.3);
}

TEST(EpipolarTest, TooFewTracksIsNotATest) {
  std::vector<cv::Point2f> p(10, cv::Point2f(5, 5));
  std::vector<uint8_t> u(10, 1);
  std::vector<float> d(10, 1.f);
  EpipolarResult r;
  EpipolarTest().run(p, p, u, d, r);
  EXPECT_FALSE(r.valid);
  for (uint8_t f : r.dynamic) EXPECT_EQ(f, 0);
}

TEST(RobustSigma, IsTheScaledMedian) {
  std::vector<double> r = {0.1, 0.2, 0.3, 100.0, 0.4};
  EXPECT_NEAR(robust_sigma(r), 1.4826 * 0.3, 1e-12);
  std::vector<double> empty;
  EXPECT_EQ(robust_sigma(empty), 0.0);
}

// The LK pyramids of `image` and of `image` shifted by `shift_px` (cubic interpolation, reflected borders).
struct ShiftedPyramids {
  std::vector<cv::Mat> before, after;
};
ShiftedPyramids shifted_pyramids(const LkTracker& tracker, const cv::Mat& image, cv::Point2f shift_px) {
  cv::Mat moved;
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, shift_px.x, 0, 1, shift_px.y);
  cv::warpAffine(image, moved, M, image.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  ShiftedPyramids p;
  tracker.build_pyramid(image, p.before);
  tracker.build_pyramid(moved, p.after);
  return p;
}

TEST(LkTracker, TracksAKnownShiftAndRejectsFlatPoints) {
  const cv::Mat tex = testing::make_texture(512, 128, 140, 31)(cv::Rect(0, 0, 400, 300)).clone();
  cv::Mat flat_patch = tex.clone();
  flat_patch(cv::Rect(0, 0, 60, 60)).setTo(100);
  const cv::Point2f shift(3.3f, -2.1f);
  LkTracker tracker;
  const ShiftedPyramids p = shifted_pyramids(tracker, flat_patch, shift);
  std::vector<cv::Point2f> prev = {{100, 100}, {200, 150}, {300, 220}, {150, 250}, {25, 25}};
  std::vector<cv::Point2f> cur;
  std::vector<uint8_t> ok;
  tracker.track(p.before, p.after, prev, cur, ok);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ok[static_cast<std::size_t>(i)]) << i;
    EXPECT_NEAR(cur[static_cast<std::size_t>(i)].x, prev[static_cast<std::size_t>(i)].x + shift.x, 0.1);
    EXPECT_NEAR(cur[static_cast<std::size_t>(i)].y, prev[static_cast<std::size_t>(i)].y + shift.y, 0.1);
  }
  EXPECT_FALSE(ok[4]) << "a point in a flat region cannot be tracked";
}

TEST(LkTracker, LevelsFollowTheLastMotion) {
  LkTrackerConfig c;  // 11x11 window: (11 / 2) * 2^L = 22, 44, 88 px on 2, 3, 4 levels
  c.min_levels = 2;
  c.levels = 4;
  c.motion_margin = 2.0;
  const LkTracker tracker(c);
  EXPECT_EQ(tracker.levels_for_motion(-1), 4) << "unknown motion (no tracks before): every level";
  EXPECT_EQ(tracker.levels_for_motion(0.0), 2);
  EXPECT_EQ(tracker.levels_for_motion(11.0), 2);
  EXPECT_EQ(tracker.levels_for_motion(11.5), 3);
  EXPECT_EQ(tracker.levels_for_motion(22.0), 3);
  EXPECT_EQ(tracker.levels_for_motion(22.5), 4);
  EXPECT_EQ(tracker.levels_for_motion(300.0), 4) << "never more than `levels`";
  c.min_levels = 6;  // above `levels`: `levels`
  EXPECT_EQ(LkTracker(c).levels_for_motion(0.0), 4);
  c.min_levels = 2;
  c.levels = 1;
  EXPECT_EQ(LkTracker(c).levels_for_motion(0.0), 1);
}

TEST(LkTracker, LargeMotionNeedsTheLevelsItIsGiven) {
  const cv::Mat tex = testing::make_texture(512, 128, 140, 31)(cv::Rect(0, 0, 400, 300)).clone();
  const cv::Point2f shift(36.0f, 5.0f);  // an AGV turning: 36 px in one frame
  LkTracker tracker;
  const ShiftedPyramids p = shifted_pyramids(tracker, tex, shift);
  std::vector<cv::Point2f> prev;
  for (int y = 80; y <= 220; y += 35) {
    for (int x = 80; x <= 300; x += 44) prev.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
  auto correct = [&](int levels) {
    std::vector<cv::Point2f> cur;
    std::vector<uint8_t> ok;
    tracker.track(p.before, p.after, prev, cur, ok, levels);
    int n = 0;
    for (std::size_t i = 0; i < prev.size(); ++i) {
      const cv::Point2f e = cur[i] - (prev[i] + shift);
      n += ok[i] && e.dot(e) < 0.01f ? 1 : 0;
    }
    return n;
  };
  const int chosen = tracker.levels_for_motion(std::hypot(shift.x, shift.y));
  EXPECT_EQ(chosen, 4);
  EXPECT_EQ(correct(chosen), static_cast<int>(prev.size()));
  EXPECT_LT(correct(1), static_cast<int>(prev.size()) / 2) << "one level (~11 px of reach) loses most of them";
}

// Road hatching / rack uprights: a stripe pattern (period 20 px along x) with faint texture, moved by 2.3 periods in
// one frame. Searched from the old position on every level, most tracks are lost (the coarse levels cannot tell the
// stripes apart); started a few px from where the point went, on the two finest levels, all but a few are right and
// none is wrong.
TEST(LkTracker, ARepeatedPatternIsFollowedFromAStartNearThePrediction) {
  const cv::Mat tex = testing::make_texture(512, 128, 140, 31)(cv::Rect(0, 0, 400, 300)).clone();
  cv::Mat stripes(tex.size(), CV_8UC1);
  for (int y = 0; y < stripes.rows; ++y) {
    for (int x = 0; x < stripes.cols; ++x) {
      const bool white = ((x + y / 2) % 20) < 8;  // slanted like road hatching
      stripes.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>((white ? 200 : 60) + (tex.at<uint8_t>(y, x) - 128) / 8);
    }
  }
  const cv::Point2f shift(46.0f, 3.0f);
  LkTracker tracker;
  const ShiftedPyramids p = shifted_pyramids(tracker, stripes, shift);
  std::vector<cv::Point2f> prev, start;
  for (int y = 60; y <= 240; y += 30) {
    for (int x = 60; x <= 280; x += 37) {
      prev.emplace_back(static_cast<float>(x) + 0.5f, static_cast<float>(y));
      start.push_back(prev.back() + shift + cv::Point2f(2.0f, -1.5f));  // a prediction a few px off
    }
  }
  auto count = [&](const std::vector<cv::Point2f>* from, int& right, int& slipped) {
    std::vector<cv::Point2f> cur;
    std::vector<uint8_t> ok;
    tracker.track(p.before, p.after, prev, cur, ok, from != nullptr ? 2 : 4, from);
    right = slipped = 0;
    for (std::size_t i = 0; i < prev.size(); ++i) {
      if (!ok[i]) continue;
      const cv::Point2f e = cur[i] - (prev[i] + shift);
      (e.dot(e) < 0.04f ? right : slipped) += 1;
    }
  };
  int right = 0, slipped = 0;
  count(&start, right, slipped);
  EXPECT_GE(right, static_cast<int>(prev.size()) - 3);
  EXPECT_EQ(slipped, 0);
  count(nullptr, right, slipped);
  EXPECT_LT(right, static_cast<int>(prev.size()) / 3);
}

}  // namespace
}  // namespace agvslam::dynamic
