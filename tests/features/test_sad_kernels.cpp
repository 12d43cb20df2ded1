// The block-matching kernels: the SIMD ones (SSE4.1 mpsadbw, AVX2) give exactly the scalar kernel's costs, for
// every window width, on random data with the padding the matcher provides.
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/core.hpp>
#include <vector>

#include "sad_kernels.h"

namespace agvslam::features::detail {
namespace {

TEST(SadKernels, SimdKernelsEqualTheScalarOne) {
  const char* best_name = nullptr;
  ASSERT_NE(best_sad_kernel(&best_name), nullptr);
  std::printf("best SAD kernel on this CPU: %s\n", best_name);
  cv::RNG rng(11);
  cv::Mat left(40, 200, CV_8UC1), right(40, 300, CV_8UC1);
  rng.fill(left, cv::RNG::UNIFORM, 0, 256);
  rng.fill(right, cv::RNG::UNIFORM, 0, 256);
  int compared = 0;
  for (const char* name : {"sse41", "avx2"}) {
    const SadRowKernel kernel = sad_kernel(name);
    if (!kernel) {
      std::printf("%s: not available here\n", name);
      continue;
    }
    for (int blocks = 1; blocks <= 4; ++blocks) {
      for (int rows : {3, 11, 15}) {
        for (int n : {1, 7, 8, 9, 16, 17, 100, 183}) {
          const uint8_t* lr[16];
          const uint8_t* rr[16];
          for (int r = 0; r < rows; ++r) {
            lr[r] = left.ptr<uint8_t>(5 + r) + 20;
            rr[r] = right.ptr<uint8_t>(3 + r) + 10;  // n + 48 bytes stay inside the 300-byte row
          }
          std::vector<uint16_t> expected(static_cast<std::size_t>(n + 16)), got(expected.size());
          sad_costs_scalar(lr, rr, rows, blocks, n, expected.data());
          kernel(lr, rr, rows, blocks, n, got.data());
          for (int k = 0; k < n; ++k) {
            ASSERT_EQ(got[static_cast<std::size_t>(k)], expected[static_cast<std::size_t>(k)])
                << name << " blocks " << blocks << " rows " << rows << " n " << n << " k " << k;
          }
          ++compared;
        }
      }
    }
  }
  // Where no SIMD kernel exists the matcher uses the scalar one, which this test then only exercises.
  EXPECT_GE(compared, 0);
}

TEST(SadKernels, ScalarKernelIsTheSumOfAbsoluteDifferences) {
  uint8_t l[3][16], r[3][40];
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 16; ++x) l[y][x] = static_cast<uint8_t>(20 + 10 * y + x);
    for (int x = 0; x < 40; ++x) r[y][x] = static_cast<uint8_t>(20 + 10 * y + x - 5 + (x == 20 ? 7 : 0));
  }
  const uint8_t* lr[3] = {l[0], l[1], l[2]};
  const uint8_t* rr[3] = {r[0], r[1], r[2]};
  uint16_t costs[32];
  sad_costs_scalar(lr, rr, 3, 2, 10, costs);
  // Window 3 x 8; candidate k compares l[x] with r[k + x] = l[x] + k - 5 (plus 7 at column 20): minimum at k = 5.
  EXPECT_EQ(costs[5], 0);
  EXPECT_EQ(costs[4], 3 * 8 * 1);
  EXPECT_EQ(costs[0], 3 * 8 * 5);
  EXPECT_EQ(costs[9], 3 * 8 * 4);
}

}  // namespace
}  // namespace agvslam::features::detail
