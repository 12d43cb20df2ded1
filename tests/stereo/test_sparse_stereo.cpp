// SparseStereoMatcher: exact synthetic shifts, rejection cases, and agreement with whole-frame SGBM (and the
// ground truth) at FAST corners of the real KITTI 2015 and Middlebury pairs.
#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/sparse_stereo.h"
#include "common/test_data.h"
#include "disparity_ground_truth.h"

namespace agvslam::stereo {
namespace {
using namespace agvslam::stereo::testing;

cv::Mat smooth_texture(cv::Size size, int seed) {
  cv::RNG rng(static_cast<uint64_t>(seed));
  cv::Mat coarse(size.height / 4, size.width / 4, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
  cv::Mat out;
  cv::resize(coarse, out, size, 0, 0, cv::INTER_CUBIC);
  return out;
}

cv::Mat shift_left(const cv::Mat& img, double disparity_px) {
  cv::Mat out;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -disparity_px, 0, 1, 0);
  cv::warpAffine(img, out, shift, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

TEST(SparseStereo, FractionalShiftIsRecoveredToSubPixel) {
  const cv::Mat left = smooth_texture(cv::Size(240, 120), 3);
  SparseStereoMatcher matcher;
  for (double d_true : {6.0, 12.25, 20.5, 33.75}) {
    const cv::Mat right = shift_left(left, d_true);
    double sum_abs = 0;
    int n = 0;
    for (int y = 20; y < 100; y += 10) {
      for (int x = 80; x < 230; x += 15) {
        SparseMatchStatus status;
        const float d = matcher.match(left, right, cv::Point2f(static_cast<float>(x), static_cast<float>(y)), &status);
        ASSERT_EQ(status, SparseMatchStatus::kOk) << x << "," << y << " d_true " << d_true;
        sum_abs += std::abs(d - d_true);
        ++n;
        EXPECT_NEAR(d, d_true, 0.3) << x << "," << y;
      }
    }
    EXPECT_LT(sum_abs / n, 0.15) << "mean |error| at d = " << d_true;
  }
}

TEST(SparseStereo, RejectsFlatWindowsPointsOutsideAndOutOfRange) {
  cv::Mat left(100, 200, CV_8UC1, cv::Scalar(128));
  cv::Mat right = left.clone();
  SparseStereoMatcher matcher;
  SparseMatchStatus status;
  EXPECT_EQ(matcher.match(left, right, {100, 50}, &status), 0.0f);
  EXPECT_EQ(status, SparseMatchStatus::kNoTexture);
  EXPECT_EQ(matcher.match(left, right, {2, 50}, &status), 0.0f);
  EXPECT_EQ(status, SparseMatchStatus::kOutside);
  EXPECT_EQ(matcher.match(left, right, {100, 198}, &status), 0.0f);
  EXPECT_EQ(status, SparseMatchStatus::kOutside);

  // A shift larger than the search range has its minimum at the end of the range -> rejected.
  const cv::Mat textured = smooth_texture(cv::Size(240, 120), 5);
  SparseStereoConfig c;
  c.num_disparities = 16;
  SparseStereoMatcher short_range(c);
  const cv::Mat far_right = shift_left(textured, 30.0);
  int accepted = 0;
  for (int x = 120; x < 220; x += 10) {
    const float d = short_range.match(textured, far_right, cv::Point2f(static_cast<float>(x), 60.f), &status);
    if (d > 0) ++accepted;
  }
  EXPECT_LE(accepted, 1);
}

TEST(SparseStereo, LeftRightCheckRejectsOccludedPoints) {
  // Background at disparity 5, a foreground square at disparity 25 occluding it: background pixels just left
  // of the square are visible in the left image but hidden in the right one.
  const cv::Mat bg = smooth_texture(cv::Size(300, 120), 11);
  const cv::Mat fg = smooth_texture(cv::Size(300, 120), 12);
  cv::Mat left = bg.clone(), right = shift_left(bg, 5.0);
  const cv::Rect square_left(150, 20, 80, 80);
  fg(square_left).copyTo(left(square_left));
  fg(square_left).copyTo(right(square_left - cv::Point(25, 0)));
  SparseStereoMatcher matcher;
  SparseMatchStatus status;
  // A point in the occluded band [125, 145) left of the square (its right-image position is under the square).
  int accepted_wrong = 0;
  for (int y = 30; y < 90; y += 10) {
    const float d = matcher.match(left, right, cv::Point2f(135.f, static_cast<float>(y)), &status);
    if (d > 0 && std::abs(d - 5.0f) > 1.0f) ++accepted_wrong;
  }
  EXPECT_EQ(accepted_wrong, 0);
  // Points well inside the square and on visible background are matched.
  EXPECT_NEAR(matcher.match(left, right, {190.f, 60.f}, &status), 25.0f, 0.3f);
  EXPECT_EQ(status, SparseMatchStatus::kOk);
  EXPECT_NEAR(matcher.match(left, right, {80.f, 60.f}, &status), 5.0f, 0.3f);
}

struct Agreement {
  int points = 0, sparse_valid = 0, both_valid = 0, agree = 0, truth_checked = 0, truth_bad = 0;
  int status_count[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  std::string statuses() const {
    std::string s = "status counts (ok outside no-texture not-unique high-cost left-right range):";
    for (int i = 0; i < 7; ++i) s += " " + std::to_string(status_count[i]);
    return s;
  }
};

Agreement compare_at_corners(const Pair& p, int num_disparities, float truth_tol_px, bool kitti_rule) {
  SgbmConfig gc;
  gc.num_disparities = num_disparities;
  StereoSgbm sgbm(gc);
  cv::Mat full_px;
  sgbm.compute(p.left, p.right, full_px);
  SparseStereoConfig sc;
  sc.num_disparities = num_disparities;
  SparseStereoMatcher matcher(sc);
  std::vector<cv::KeyPoint> kps;
  cv::FAST(p.left, kps, 20, true);
  cv::KeyPointsFilter::retainBest(kps, 600);
  std::vector<cv::Point2f> pts;
  for (const auto& kp : kps) pts.push_back(kp.pt);
  std::vector<float> sparse_px(pts.size());
  Agreement a;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    SparseMatchStatus status;
    sparse_px[i] = matcher.match(p.left, p.right, pts[i], &status);
    if (pts[i].x >= static_cast<float>(num_disparities + 8)) ++a.status_count[static_cast<int>(status)];
  }
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const int x = static_cast<int>(std::lround(pts[i].x)), y = static_cast<int>(std::lround(pts[i].y));
    if (x < num_disparities + 8) continue;  // no full range left of here for either method
    ++a.points;
    const float s = sparse_px[i];
    if (!(s > 0)) continue;
    ++a.sparse_valid;
    const float f = full_px.at<float>(y, x);
    if (f > 0) {
      ++a.both_valid;
      a.agree += std::abs(s - f) <= 1.0f;
    }
    const float t = p.truth_px.at<float>(y, x);
    const bool truth_ok = kitti_rule ? t > 0 : (std::isfinite(t) && p.nonocc.at<uint8_t>(y, x) == 255);
    if (truth_ok) {
      ++a.truth_checked;
      const float err = std::abs(s - t);
      a.truth_bad += kitti_rule ? (err > 3.0f && err > 0.05f * t) : err > truth_tol_px;
    }
  }
  return a;
}

TEST(SparseStereo, AgreesWithWholeFrameSgbmOnKitti) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/kitti2015_training_000046");
  const Pair p = load_kitti(dir);
  ASSERT_FALSE(p.left.empty());
  const Agreement a = compare_at_corners(p, 96, 3.0f, true);
  ASSERT_GT(a.points, 300);
  EXPECT_GT(a.sparse_valid, 0.6 * a.points) << a.statuses();
  EXPECT_GT(a.agree, 0.9 * a.both_valid) << a.agree << " of " << a.both_valid << " within 1 px of SGBM";
  ASSERT_GT(a.truth_checked, 40);  // KITTI's lidar ground truth covers the lower image part only
  EXPECT_LT(a.truth_bad, 0.05 * a.truth_checked) << a.truth_bad << " of " << a.truth_checked << " bad (D1 rule)";
}

TEST(SparseStereo, AgreesWithWholeFrameSgbmOnMiddlebury) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/middlebury2014_trainingQ_Motorcycle");
  const Pair p = load_middlebury(dir);
  ASSERT_FALSE(p.left.empty());
  const Agreement a = compare_at_corners(p, 80, 2.0f, false);
  ASSERT_GT(a.points, 300);
  EXPECT_GT(a.sparse_valid, 0.6 * a.points) << a.statuses();
  EXPECT_GT(a.agree, 0.9 * a.both_valid) << a.agree << " of " << a.both_valid << " within 1 px of SGBM";
  ASSERT_GT(a.truth_checked, 100);
  EXPECT_LT(a.truth_bad, 0.08 * a.truth_checked) << a.truth_bad << " of " << a.truth_checked << " bad-2.0";
}

}  // namespace
}  // namespace agvslam::stereo
