// OrbBlur: the descriptor image equals cv::GaussianBlur of the same bordered view (what cv::ORB blurs), on every
// pyramid level of simulator and real images and on odd sizes.
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/features/orb_blur.h"
#include "common/test_data.h"
#include "feature_test_data.h"

namespace agvslam::features {
namespace {

int differing_pixels(const cv::Mat& img) {
  cv::Mat ext;
  cv::copyMakeBorder(img, ext, 3, 3, 3, 3, cv::BORDER_REFLECT_101);
  const cv::Mat view = ext(cv::Rect(3, 3, img.cols, img.rows));
  cv::Mat theirs, ours(img.size(), CV_8UC1);
  cv::GaussianBlur(view, theirs, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  OrbBlur blur;
  if (!blur.blur(view, ours)) return -1;  // this CPU takes OpenCV's path
  return cv::countNonZero(ours != theirs);
}

void expect_equal_on_pyramid(cv::Mat img, const char* what) {
  for (int level = 0; level < 8; ++level) {
    const int d = differing_pixels(img);
    if (d < 0) GTEST_SKIP() << "no AVX2 + FMA: the extractor uses cv::GaussianBlur itself";
    EXPECT_EQ(d, 0) << what << " level " << level << " (" << img.cols << "x" << img.rows << ")";
    cv::Mat next;
    cv::resize(img, next, cv::Size(cvRound(img.cols / 1.2f), cvRound(img.rows / 1.2f)), 0, 0, cv::INTER_LINEAR_EXACT);
    img = next;
  }
}

TEST(OrbBlur, EqualsOpenCvOnEveryPyramidLevel) {
  expect_equal_on_pyramid(testing::render_sim("scene4", 60).left, "simulator");
  cv::Mat noise(97, 131, CV_8UC1);
  cv::RNG(12).fill(noise, cv::RNG::UNIFORM, 0, 256);
  expect_equal_on_pyramid(noise, "noise");
  AGVSLAM_REQUIRE_SHARED(kitti, "data/kitti06_f000-050");
  expect_equal_on_pyramid(cv::imread(kitti + "/image_l/000010.png", cv::IMREAD_GRAYSCALE), "KITTI");
  AGVSLAM_REQUIRE_SHARED(mb, "data/disparity_pairs/middlebury2014_trainingQ_Motorcycle");
  expect_equal_on_pyramid(cv::imread(mb + "/im0.png", cv::IMREAD_GRAYSCALE), "Middlebury");
}

}  // namespace
}  // namespace agvslam::features
