// Disparity planes per superpixel (paper 004, eq. 8): RANSAC + least squares.
#include <gtest/gtest.h>

#include "agvslam/dynamic/disparity_plane.h"

namespace agvslam::dynamic {
namespace {

TEST(DisparityPlane, RansacRecoversThePlaneWithThirtyPercentOutliers) {
  const double a = 0.05, b = -0.12, c = 31.5;
  cv::RNG rng(17);
  for (double noise : {0.0, 0.2}) {
    std::vector<cv::Point3f> samples;
    int outliers = 0;
    for (int i = 0; i < 300; ++i) {
      const double x = rng.uniform(200.0, 240.0), y = rng.uniform(100.0, 130.0);
      double d = a * x + b * y + c + rng.gaussian(noise);
      if (i % 10 < 3) {  // 30 % gross outliers (mismatches), both sides
        d += (i % 2 ? 1 : -1) * rng.uniform(3.0, 20.0);
        ++outliers;
      }
      samples.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(d));
    }
    ASSERT_EQ(outliers, 90);
    PlaneFitConfig cfg;
    uint32_t state = 99;
    const DisparityPlane p = fit_disparity_plane(samples, cfg, state);
    ASSERT_TRUE(p.valid);
    const double tol = noise == 0 ? 1e-4 : 0.01;
    EXPECT_NEAR(p.a, a, tol);
    EXPECT_NEAR(p.b, b, tol);
    EXPECT_NEAR(p.disparity_at(220, 115), a * 220 + b * 115 + c, noise == 0 ? 1e-3 : 0.1);
    EXPECT_NEAR(p.inliers, 210, noise == 0 ? 0 : 10);
    EXPECT_EQ(p.support, 300);
    EXPECT_LT(p.rms_px, noise + 1e-3);
  }
}

TEST(DisparityPlane, TooFewOrInconsistentSamplesGiveNoPlane) {
  PlaneFitConfig cfg;
  uint32_t state = 1;
  EXPECT_FALSE(fit_disparity_plane({{1, 1, 1}, {2, 1, 1}}, cfg, state).valid);
  // Pure noise: no plane has half of the samples within 1 px.
  cv::RNG rng(3);
  std::vector<cv::Point3f> noise;
  for (int i = 0; i < 100; ++i) {
    noise.emplace_back(rng.uniform(0.f, 20.f), rng.uniform(0.f, 20.f), rng.uniform(0.f, 60.f));
  }
  EXPECT_FALSE(fit_disparity_plane(noise, cfg, state).valid);
}

TEST(DisparityPlane, OnePlanePerSuperpixelInFullImageCoordinates) {
  // A 40x20 ROI at (100, 50): label 0 left half with d = 20 + 0.1 x, label 1 right half front-parallel d = 8,
  // label 2 a 4x4 block with no disparity.
  cv::Mat labels(20, 40, CV_32SC1, cv::Scalar(0));
  labels(cv::Rect(20, 0, 20, 20)).setTo(1);
  labels(cv::Rect(0, 0, 4, 4)).setTo(2);
  cv::Mat disparity(20, 40, CV_32FC1);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 40; ++x) disparity.at<float>(y, x) = x < 20 ? 20.f + 0.1f * static_cast<float>(x + 100) : 8.f;
  }
  disparity(cv::Rect(0, 0, 4, 4)).setTo(0);
  std::vector<DisparityPlane> planes;
  fit_superpixel_planes(labels, 3, disparity, cv::Point(100, 50), PlaneFitConfig{}, planes);
  ASSERT_EQ(planes.size(), 3u);
  ASSERT_TRUE(planes[0].valid);
  EXPECT_NEAR(planes[0].a, 0.1, 1e-4);
  EXPECT_NEAR(planes[0].b, 0.0, 1e-4);
  EXPECT_NEAR(planes[0].c, 20.0, 1e-2);
  ASSERT_TRUE(planes[1].valid);
  EXPECT_NEAR(planes[1].disparity_at(130, 60), 8.0, 1e-4);
  EXPECT_FALSE(planes[2].valid);
  EXPECT_EQ(planes[2].support, 0);
}

}  // namespace
}  // namespace agvslam::dynamic
