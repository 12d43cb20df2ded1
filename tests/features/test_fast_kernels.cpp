// The FAST strength map: SIMD rows equal the scalar definition, and its local maxima above t are exactly
// cv::FAST(t, non-maximum suppression) with OpenCV's scores, at the ORB thresholds.
#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "fast_kernels.h"
#include "feature_test_data.h"

namespace agvslam::features::detail {
namespace {

cv::Mat strength_of(const cv::Mat& img) {
  cv::Mat s(img.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 3; y < img.rows - 3; ++y) {
    fast_strength_row(img.ptr<uint8_t>(y) + 3, static_cast<int>(img.step), img.cols - 6, s.ptr<uint8_t>(y) + 3);
  }
  return s;
}

TEST(FastKernels, SimdStrengthEqualsTheScalarDefinition) {
  cv::RNG rng(9);
  cv::Mat img(40, 120, CV_8UC1);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  for (int n : {10, 16, 31, 32, 33, 100, 114}) {
    for (int y = 3; y < 37; ++y) {
      uint8_t a[128], b[128];
      fast_strength_row_scalar(img.ptr<uint8_t>(y) + 3, static_cast<int>(img.step), n, a);
      fast_strength_row(img.ptr<uint8_t>(y) + 3, static_cast<int>(img.step), n, b);
      for (int x = 0; x < n; ++x) ASSERT_EQ(a[x], b[x]) << "n " << n << " y " << y << " x " << x;
    }
  }
}

void expect_equal_to_cv_fast(const cv::Mat& img, int threshold, const char* what) {
  const cv::Mat s = strength_of(img);
  std::vector<cv::KeyPoint> cv_kps;
  cv::FAST(img, cv_kps, threshold, true);
  // Compare where both see every neighbour: [4, w - 4) x [4, h - 4).
  std::vector<std::pair<int, int>> theirs, ours;
  std::vector<int> their_score;
  for (const cv::KeyPoint& k : cv_kps) {
    const int x = static_cast<int>(k.pt.x), y = static_cast<int>(k.pt.y);
    if (x < 4 || y < 4 || x >= img.cols - 4 || y >= img.rows - 4) continue;
    theirs.emplace_back(y, x);
    EXPECT_EQ(static_cast<int>(k.response), s.at<uint8_t>(y, x) - 1) << what;
  }
  std::vector<int> xs(static_cast<std::size_t>(img.cols));
  for (int y = 4; y < img.rows - 4; ++y) {
    const int n = local_maxima_row(s.ptr<uint8_t>(y), static_cast<int>(s.step), 4, img.cols - 4, threshold, xs.data());
    for (int i = 0; i < n; ++i) ours.emplace_back(y, xs[static_cast<std::size_t>(i)]);
  }
  std::sort(theirs.begin(), theirs.end());
  EXPECT_GT(theirs.size(), 100u) << what;
  EXPECT_EQ(ours, theirs) << what << " threshold " << threshold << ": " << ours.size() << " vs " << theirs.size();
}

TEST(FastKernels, LocalMaximaOfTheStrengthAreOpenCvFastWithSuppression) {
  const testing::SimPair p = testing::render_sim("scene4", 60);
  for (int t : {7, 12, 20}) expect_equal_to_cv_fast(p.left, t, "simulator");
  cv::RNG rng(10);
  cv::Mat noise(120, 200, CV_8UC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(noise, noise, cv::Size(5, 5), 1.2);
  for (int t : {7, 20}) expect_equal_to_cv_fast(noise, t, "noise");
}

}  // namespace
}  // namespace agvslam::features::detail
