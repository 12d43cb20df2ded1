// LinearExactResizer: pixel-for-pixel equal to cv::resize(INTER_LINEAR_EXACT) for the pyramid sizes of the
// supported images and for odd sizes and factors; falls back to cv::resize outside its scheme.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/features/linear_resize.h"

namespace agvslam::features {
namespace {

// A source with 16 readable bytes after every row (a view into a wider buffer), as the resizer requires.
cv::Mat padded_random(cv::Size size, uint64_t seed) {
  cv::Mat buffer(size.height + 1, size.width + 16, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(buffer, cv::RNG::UNIFORM, 0, 256);
  return buffer(cv::Rect(0, 0, size.width, size.height));
}

void expect_equal_to_opencv(cv::Size src_size, cv::Size dst_size, bool fast_expected, uint64_t seed) {
  const cv::Mat src = padded_random(src_size, seed);
  LinearExactResizer resizer;
  cv::Mat ours(dst_size, CV_8UC1), theirs;
  for (int pass = 0; pass < 2; ++pass) {  // the second pass reuses the tables
    resizer.resize(src, ours);
    cv::resize(src, theirs, dst_size, 0, 0, cv::INTER_LINEAR_EXACT);
    ASSERT_EQ(cv::norm(ours, theirs, cv::NORM_INF), 0)
        << src_size << " -> " << dst_size << ": " << cv::countNonZero(ours != theirs) << " pixels differ";
  }
  EXPECT_EQ(resizer.last_was_fast(), fast_expected) << src_size << " -> " << dst_size;
}

TEST(LinearResize, EqualsOpenCvOnThePyramidSizes) {
  for (cv::Size image : {cv::Size(752, 480), cv::Size(1226, 370), cv::Size(1241, 376), cv::Size(640, 480)}) {
    cv::Size src = image;
    for (int level = 1; level < 8; ++level) {
      const float s = static_cast<float>(std::pow(static_cast<double>(1.2f), level));
      const cv::Size dst(cvRound(static_cast<float>(image.width) / s), cvRound(static_cast<float>(image.height) / s));
      expect_equal_to_opencv(src, dst, true, static_cast<uint64_t>(level));
      src = dst;
    }
  }
}

TEST(LinearResize, EqualsOpenCvForOtherFactorsAndFallsBackOutsideItsScheme) {
  expect_equal_to_opencv({753, 481}, {500, 321}, true, 1);   // 1.5
  expect_equal_to_opencv({101, 37}, {99, 36}, true, 2);      // barely smaller
  expect_equal_to_opencv({64, 20}, {33, 11}, true, 3);       // almost 2x
  expect_equal_to_opencv({17, 9}, {13, 7}, true, 4);         // narrower than one block of 8 outputs... and wider
  expect_equal_to_opencv({752, 480}, {376, 240}, false, 5);  // exact halving: OpenCV averages areas
  expect_equal_to_opencv({100, 50}, {40, 20}, false, 6);     // 2.5x
  expect_equal_to_opencv({100, 50}, {120, 60}, false, 7);    // upscaling
}

}  // namespace
}  // namespace agvslam::features
