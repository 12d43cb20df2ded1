#include "agvslam/features/orb_blur.h"

#include <opencv2/imgproc.hpp>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define AGVSLAM_BLUR_X86 1
#endif

namespace agvslam::features {

OrbBlur::OrbBlur() {
  const cv::Mat k = cv::getGaussianKernel(7, 2.0, CV_32F);
  for (int i = 0; i < 7; ++i) kernel_[i] = k.at<float>(i);
#ifdef AGVSLAM_BLUR_X86
  __builtin_cpu_init();
  fma_ = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#endif
}

#ifdef AGVSLAM_BLUR_X86
namespace {

// One source row (pointer to column -3) to its row-filtered floats (width values).
__attribute__((target("avx2,fma"))) void row_pass(const uint8_t* src, int width, const float* k, float* convert,
                                                  float* out) {
  const int n = width + 6;
  int x = 0;
  for (; x + 8 <= n; x += 8) {
    const __m256i v = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(src + x)));
    _mm256_storeu_ps(convert + x, _mm256_cvtepi32_ps(v));
  }
  for (; x < n; ++x) convert[x] = static_cast<float>(src[x]);
  const __m256 k0 = _mm256_set1_ps(k[0]), k1 = _mm256_set1_ps(k[1]), k2 = _mm256_set1_ps(k[2]),
               k3 = _mm256_set1_ps(k[3]), k4 = _mm256_set1_ps(k[4]), k5 = _mm256_set1_ps(k[5]),
               k6 = _mm256_set1_ps(k[6]);
  for (x = 0; x < width; x += 8) {
    if (x + 8 > width) x = width - 8;
    const float* c = convert + x;
    __m256 s = _mm256_mul_ps(_mm256_loadu_ps(c), k0);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 1), k1, s);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 2), k2, s);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 3), k3, s);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 4), k4, s);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 5), k5, s);
    s = _mm256_fmadd_ps(_mm256_loadu_ps(c + 6), k6, s);
    _mm256_storeu_ps(out + x, s);
  }
}

// Column pass over 7 filtered rows r[0..6] (centre r[3]) into 8-bit output.
__attribute__((target("avx2,fma"))) void column_pass(const float* const* r, int width, const float* k, uint8_t* out) {
  const __m256 k0 = _mm256_set1_ps(k[0]), k1 = _mm256_set1_ps(k[1]), k2 = _mm256_set1_ps(k[2]),
               k3 = _mm256_set1_ps(k[3]);
  for (int x = 0; x < width; x += 8) {
    if (x + 8 > width) x = width - 8;
    __m256 s = _mm256_mul_ps(_mm256_loadu_ps(r[3] + x), k3);
    s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(r[2] + x), _mm256_loadu_ps(r[4] + x)), k2, s);
    s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(r[1] + x), _mm256_loadu_ps(r[5] + x)), k1, s);
    s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(r[0] + x), _mm256_loadu_ps(r[6] + x)), k0, s);
    const __m256i i32 = _mm256_cvtps_epi32(s);  // round half to even, as cvRound
    const __m128i i16 = _mm_packs_epi32(_mm256_castsi256_si128(i32), _mm256_extracti128_si256(i32, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(i16, i16));
  }
}

}  // namespace
#endif

bool OrbBlur::blur(const cv::Mat& src, cv::Mat& dst) {
#ifdef AGVSLAM_BLUR_X86
  const int width = src.cols, height = src.rows;
  if (!fma_ || width < 8) return false;
  CV_Assert(src.type() == CV_8UC1 && dst.type() == CV_8UC1 && dst.size() == src.size());
  const std::size_t w = static_cast<std::size_t>(width);
  rows_.resize(7 * w);
  convert_.resize(w + 6 + 8);
  const int step = static_cast<int>(src.step);
  auto filtered = [&](int y) { return rows_.data() + static_cast<std::size_t>((y + 7) % 7) * w; };
  // Rows -3 .. 2 first, then one new row per output row.
  for (int y = -3; y < 3; ++y)
    row_pass(src.ptr<uint8_t>(0) + y * step - 3, width, kernel_, convert_.data(), filtered(y));
  const float* r[7];
  for (int y = 0; y < height; ++y) {
    row_pass(src.ptr<uint8_t>(0) + (y + 3) * step - 3, width, kernel_, convert_.data(), filtered(y + 3));
    for (int i = 0; i < 7; ++i) r[i] = filtered(y - 3 + i);
    column_pass(r, width, kernel_, dst.ptr<uint8_t>(y));
  }
  return true;
#else
  (void)src;
  (void)dst;
  return false;
#endif
}

}  // namespace agvslam::features
