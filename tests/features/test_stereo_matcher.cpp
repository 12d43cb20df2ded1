// StereoMatcher: depth of the left keypoints against ground-truth disparity on a synthetic shift, a simulator
// frame and the shared KITTI 2015 and Middlebury pairs, for block matching (the default) and ORB-SLAM2's
// descriptor method.
//
// Measures: "within 1 px" compares the returned disparity with the ground truth at the keypoint's pixel;
// "within 1 px (+-1)" with the ground truth at the keypoint's pixel or a neighbour within half the keypoint's
// level scale (at least 1 px): a corner on an object's outline sits on the depth edge, where the ground truth
// jumps between neighbouring pixels while the keypoint position is only known to that precision.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/features/orb_extractor.h"
#include "agvslam/features/stereo_matcher.h"
#include "agvslam/io/dataset.h"
#include "agvslam/stereo/sgbm.h"
#include "common/test_data.h"
#include "feature_test_data.h"
#include "stereo/disparity_ground_truth.h"

namespace agvslam::features {
namespace {

struct Score {
  int keypoints = 0, with_truth = 0, matched = 0, matched_with_truth = 0;
  int within_1 = 0, within_1_nbhd = 0, within_2 = 0, kitti_bad = 0;
  double rate() const { return with_truth > 0 ? static_cast<double>(matched_with_truth) / with_truth : 0; }
  double frac(int n) const { return matched_with_truth > 0 ? static_cast<double>(n) / matched_with_truth : 0; }
  void print(const char* what) const {
    std::printf(
        "%s: %d keypoints, %d with ground truth, %d matched (%.1f %% of those with truth); within 1 px "
        "%.1f %%, within 1 px (+-1) %.1f %%, within 2 px %.1f %%, KITTI D1 bad %.1f %%\n",
        what, keypoints, with_truth, matched, 100 * rate(), 100 * frac(within_1), 100 * frac(within_1_nbhd),
        100 * frac(within_2), 100 * frac(kitti_bad));
  }
};

// truth_px: CV_32F ground-truth disparity (<= 0 or not finite = none); valid: optional 255 = use.
Score score(const cv::Mat& left, const cv::Mat& right, const cv::Mat& truth_px, const cv::Mat& valid,
            const StereoCalibration& calibration, StereoMatcherConfig config) {
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(left, cv::Mat(), set);
  StereoMatcher matcher(config, calibration);
  StereoDepth depth;
  matcher.match(ex, set, right, depth);
  EXPECT_EQ(depth.u_right_px.size(), set.keypoints.size());
  EXPECT_EQ(depth.depth_m.size(), set.keypoints.size());
  auto truth_at = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= truth_px.cols || y >= truth_px.rows) return -1.0f;
    const float t = truth_px.at<float>(y, x);
    if (!std::isfinite(t) || t <= 0 || (!valid.empty() && valid.at<uint8_t>(y, x) != 255)) return -1.0f;
    return t;
  };
  Score s;
  s.keypoints = static_cast<int>(set.keypoints.size());
  int matched = 0;
  for (std::size_t i = 0; i < set.keypoints.size(); ++i) {
    const cv::KeyPoint& k = set.keypoints[i];
    const bool has = depth.u_right_px[i] >= 0;
    if (has) {
      ++matched;
      const float disparity = k.pt.x - depth.u_right_px[i];
      EXPECT_NEAR(depth.depth_m[i], calibration.bf() / disparity, 1e-3 * depth.depth_m[i]);
      EXPECT_GE(depth.depth_m[i], config.min_depth_m * 0.999);
      EXPECT_LE(depth.depth_m[i], config.max_depth_m * 1.001);
    } else {
      EXPECT_EQ(depth.depth_m[i], -1.0f);
    }
    const int x = cvRound(k.pt.x), y = cvRound(k.pt.y);
    const float t = truth_at(x, y);
    if (t <= 0) continue;
    ++s.with_truth;
    if (!has) continue;
    ++s.matched_with_truth;
    const float disparity = k.pt.x - depth.u_right_px[i];
    const float err = std::abs(disparity - t);
    s.within_1 += err <= 1.0f;
    s.within_2 += err <= 2.0f;
    s.kitti_bad += err > 3.0f && err > 0.05f * t;
    const int r =
        std::max(1, static_cast<int>(std::ceil(0.5f * ex.scale_factors()[static_cast<std::size_t>(k.octave)])));
    float best = err;
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const float tn = truth_at(x + dx, y + dy);
        if (tn > 0) best = std::min(best, std::abs(disparity - tn));
      }
    }
    s.within_1_nbhd += best <= 1.0f;
  }
  s.matched = matched;
  EXPECT_EQ(depth.matched, matched);
  return s;
}

StereoMatcherConfig with_max_disparity(StereoMatcherConfig c, const StereoCalibration& calibration,
                                       double max_disparity_px) {
  c.min_depth_m = calibration.bf() / max_disparity_px;
  return c;
}

TEST(StereoMatcher, RecoversAFractionalShiftOnEveryLevel) {
  // A textured image and its copy shifted left by 9.4 px: a fronto-parallel plane at bf / 9.4.
  cv::RNG rng(3);
  cv::Mat coarse(120, 188, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
  cv::Mat left;
  cv::resize(coarse, left, cv::Size(752, 480), 0, 0, cv::INTER_CUBIC);
  const double d_true = 9.4;
  cv::Mat right;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -d_true, 0, 1, 0);
  cv::warpAffine(left, right, shift, left.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  const StereoCalibration calibration = testing::calibration_for(left.size(), 460, 0.12);
  for (StereoMethod method : {StereoMethod::kBlockMatching, StereoMethod::kDescriptor}) {
    StereoMatcherConfig c;
    c.method = method;
    OrbExtractor ex;
    KeypointSet set;
    ex.extract(left, cv::Mat(), set);
    StereoMatcher matcher(c, calibration);
    StereoDepth depth;
    matcher.match(ex, set, right, depth);
    int matched = 0, good = 0, eligible = 0;
    std::vector<int> level_matched(8, 0);
    for (std::size_t i = 0; i < set.keypoints.size(); ++i) {
      if (set.keypoints[i].pt.x < 40) continue;  // its match would lie left of the right image
      ++eligible;
      if (depth.u_right_px[i] < 0) continue;
      ++matched;
      ++level_matched[static_cast<std::size_t>(set.keypoints[i].octave)];
      const double d = set.keypoints[i].pt.x - depth.u_right_px[i];
      const double tol = 0.25 * ex.scale_factors()[static_cast<std::size_t>(set.keypoints[i].octave)];
      good += std::abs(d - d_true) <= tol;
    }
    std::printf("%s: %d of %d matched, %d within 0.25 level px of %.1f\n", to_string(method), matched, eligible, good,
                d_true);
    const bool bm = method == StereoMethod::kBlockMatching;
    EXPECT_GE(matched, (bm ? 0.95 : 0.4) * eligible) << to_string(method);
    EXPECT_GE(good, (bm ? 0.97 : 0.8) * matched) << to_string(method);
    for (int l = 0; l < 8; ++l) EXPECT_GT(level_matched[static_cast<std::size_t>(l)], 0) << to_string(method) << l;
  }
}

TEST(StereoMatcher, DepthRangeLimitsTheMatches) {
  // The same plane at 55.2 / 9.4 = 5.9 m: nothing matches when the depth range ends before it.
  cv::RNG rng(4);
  cv::Mat coarse(120, 188, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
  cv::Mat left, right;
  cv::resize(coarse, left, cv::Size(752, 480), 0, 0, cv::INTER_CUBIC);
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -9.4, 0, 1, 0);
  cv::warpAffine(left, right, shift, left.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  const StereoCalibration calibration = testing::calibration_for(left.size(), 460, 0.12);
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(left, cv::Mat(), set);
  StereoMatcherConfig c;
  c.max_depth_m = 4.0;  // the plane is farther
  StereoMatcher far_limited(c, calibration);
  StereoDepth depth;
  far_limited.match(ex, set, right, depth);
  EXPECT_LE(depth.matched, 0.01 * set.keypoints.size());
  c = StereoMatcherConfig{};
  c.min_depth_m = 8.0;  // the plane is nearer
  c.max_depth_m = 60.0;
  StereoMatcher near_limited(c, calibration);
  near_limited.match(ex, set, right, depth);
  EXPECT_LE(depth.matched, 0.01 * set.keypoints.size());
}

TEST(StereoMatcher, SimulatorFrameAgainstGroundTruthDisparity) {
  // A driving frame of scene4 and a frame of scene1 with a person in view (ground truth everywhere).
  for (const auto& [scenario, frame] : {std::pair<const char*, int>{"scene4", 60}, {"scene1", 118}}) {
    const testing::SimPair p = testing::render_sim(scenario, frame);
    const Score s = score(p.left, p.right, p.disparity_px, cv::Mat(), p.calibration, StereoMatcherConfig{});
    s.print((std::string("simulator ") + scenario).c_str());
    EXPECT_GE(s.rate(), 0.80) << scenario;
    EXPECT_GE(s.frac(s.within_1), 0.92) << scenario;
    EXPECT_GE(s.frac(s.within_1_nbhd), 0.95) << scenario;
    EXPECT_GE(s.frac(s.within_2), 0.95) << scenario;
  }
}

TEST(StereoMatcher, KittiPairAgainstGroundTruth) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/kitti2015_training_000046");
  const stereo::testing::Pair p = stereo::testing::load_kitti(dir);
  ASSERT_FALSE(p.left.empty());
  const StereoCalibration calibration = testing::calibration_for(p.left.size(), 721.5, 0.54);
  const Score s = score(p.left, p.right, p.truth_px, cv::Mat(), calibration,
                        with_max_disparity(StereoMatcherConfig{}, calibration, 128));
  s.print("KITTI 2015 #46");
  // The lidar ground truth covers the lower part only; it is itself good to ~1 px (whole-frame SGBM agrees with
  // it within 1 px on 83 % of its pixels), so the bar is 2 px and KITTI's D1 rule.
  ASSERT_GT(s.with_truth, 150);
  EXPECT_GE(s.rate(), 0.70);
  EXPECT_GE(s.frac(s.within_2), 0.96);
  EXPECT_LE(s.frac(s.kitti_bad), 0.02);
  EXPECT_GE(s.frac(s.within_1), 0.75);
}

TEST(StereoMatcher, MiddleburyPairAgainstGroundTruth) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/middlebury2014_trainingQ_Motorcycle");
  const stereo::testing::Pair p = stereo::testing::load_middlebury(dir);
  ASSERT_FALSE(p.left.empty());
  const StereoCalibration calibration = testing::calibration_for(p.left.size(), 999.421, 0.193);
  const Score s = score(p.left, p.right, p.truth_px, p.nonocc, calibration,
                        with_max_disparity(StereoMatcherConfig{}, calibration, 96));
  s.print("Middlebury Motorcycle-Q (non-occluded)");
  ASSERT_GT(s.with_truth, 800);
  EXPECT_GE(s.rate(), 0.72);
  EXPECT_GE(s.frac(s.within_1), 0.87);
  EXPECT_GE(s.frac(s.within_1_nbhd), 0.92);
  EXPECT_GE(s.frac(s.within_2), 0.93);
}

TEST(StereoMatcher, EurocAgreesWithWholeFrameSgbm) {
  // No ground-truth disparity for EuRoC: whole-frame SGBM (its own aggregation and left-right check) is the
  // reference. The blank mats give FAST corners of sensor noise (the retry at threshold 7) that match anywhere;
  // the curvature test must keep them out.
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::err);
  const io::EurocDataset dataset(root);
  const StereoFrame f = dataset.frame(40);
  spdlog::set_level(level);
  stereo::StereoSgbm sgbm;
  cv::Mat reference_px;
  sgbm.compute(f.left, f.right, reference_px);
  const Score s = score(f.left, f.right, reference_px, cv::Mat(), dataset.calibration(), StereoMatcherConfig{});
  s.print("EuRoC V1_01 #40 against SGBM");
  EXPECT_GE(s.matched, 400);
  EXPECT_GE(s.frac(s.within_1_nbhd), 0.80);  // measured 0.85 (0.77 without the curvature test)
  EXPECT_GE(s.frac(s.within_2), 0.90);       // measured 0.93 (0.88 without the curvature test)
}

TEST(StereoMatcher, BlockMatchingMatchesMoreThanTheDescriptorMethodAtLeastAsAccurately) {
  const testing::SimPair p = testing::render_sim("scene4", 60);
  StereoMatcherConfig descriptor;
  descriptor.method = StereoMethod::kDescriptor;
  const Score bm = score(p.left, p.right, p.disparity_px, cv::Mat(), p.calibration, StereoMatcherConfig{});
  const Score orb = score(p.left, p.right, p.disparity_px, cv::Mat(), p.calibration, descriptor);
  bm.print("block matching");
  orb.print("descriptor (ORB-SLAM2)");
  EXPECT_GE(orb.rate(), 0.35);
  EXPECT_GE(orb.frac(orb.within_1_nbhd), 0.85);
  EXPECT_GT(bm.rate(), orb.rate());
  EXPECT_GE(bm.frac(bm.within_1_nbhd), orb.frac(orb.within_1_nbhd));
}

TEST(StereoMatcher, RejectsAnInvalidCalibration) {
  StereoCalibration c;
  EXPECT_THROW(StereoMatcher(StereoMatcherConfig{}, c), InputError);
}

}  // namespace
}  // namespace agvslam::features
