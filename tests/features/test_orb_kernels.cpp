// The ORB extractor's per-keypoint kernels: the SIMD moments and descriptor equal the plain loops (OpenCV's
// code) for random patches and any angle.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "orb_kernels.h"

namespace agvslam::features::detail {
namespace {

std::vector<int> opencv_umax() {
  std::vector<int> umax(17, 0);
  const int vmax = cvFloor(15 * std::sqrt(2.f) / 2 + 1), vmin = cvCeil(15 * std::sqrt(2.f) / 2);
  for (int v = 0; v <= vmax; ++v) umax[static_cast<std::size_t>(v)] = cvRound(std::sqrt(225.0 - v * v));
  for (int v = 15, v0 = 0; v >= vmin; --v) {
    while (umax[static_cast<std::size_t>(v0)] == umax[static_cast<std::size_t>(v0) + 1]) ++v0;
    umax[static_cast<std::size_t>(v)] = v0;
    ++v0;
  }
  return umax;
}

TEST(OrbKernels, MomentsEqualThePlainLoop) {
  cv::RNG rng(5);
  cv::Mat img(80, 100, CV_8UC1);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  const std::vector<int> umax = opencv_umax();
  for (int y = 20; y < 60; y += 3) {
    for (int x = 20; x < 80; x += 7) {
      int a01, a10, b01, b10;
      ic_moments_scalar(img.ptr<uint8_t>(y) + x, static_cast<int>(img.step), umax.data(), a01, a10);
      ic_moments(img.ptr<uint8_t>(y) + x, static_cast<int>(img.step), umax.data(), b01, b10);
      ASSERT_EQ(a01, b01) << x << "," << y;
      ASSERT_EQ(a10, b10) << x << "," << y;
    }
  }
}

TEST(OrbKernels, DescriptorEqualsThePlainLoopForAnyAngle) {
  cv::RNG rng(6);
  cv::Mat img(80, 100, CV_8UC1);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  int n = 0;
  for (int i = 0; i < 2000; ++i) {
    const float angle = rng.uniform(0.f, 360.f) * static_cast<float>(CV_PI / 180.f);
    const float a = static_cast<float>(std::cos(static_cast<double>(angle)));
    const float b = static_cast<float>(std::sin(static_cast<double>(angle)));
    const uint8_t* center = img.ptr<uint8_t>(rng.uniform(20, 60)) + rng.uniform(20, 80);
    uint8_t d0[32], d1[32];
    orb_descriptor_scalar(center, static_cast<int>(img.step), a, b, d0);
    orb_descriptor(center, static_cast<int>(img.step), a, b, d1);
    for (int k = 0; k < 32; ++k) ASSERT_EQ(d0[k], d1[k]) << "angle " << angle << " byte " << k;
    ++n;
  }
  // Exactly representable angles (multiples of 90 degrees) round the pattern at .5 boundaries: same there too.
  for (float deg : {0.f, 90.f, 180.f, 270.f, 45.f}) {
    const float angle = deg * static_cast<float>(CV_PI / 180.f);
    const float a = static_cast<float>(std::cos(static_cast<double>(angle)));
    const float b = static_cast<float>(std::sin(static_cast<double>(angle)));
    uint8_t d0[32], d1[32];
    orb_descriptor_scalar(img.ptr<uint8_t>(40) + 50, static_cast<int>(img.step), a, b, d0);
    orb_descriptor(img.ptr<uint8_t>(40) + 50, static_cast<int>(img.step), a, b, d1);
    for (int k = 0; k < 32; ++k) ASSERT_EQ(d0[k], d1[k]) << deg;
  }
  EXPECT_EQ(n, 2000);
}

}  // namespace
}  // namespace agvslam::features::detail
