#include "fast_kernels.h"

#include <algorithm>

#if defined(__x86_64__) || defined(__i386__) || defined(__SSE2__)
#include <immintrin.h>
#define AGVSLAM_FAST_X86 1
#endif

namespace agvslam::features::detail {

namespace {
// OpenCV's circle of radius 3 (makeOffsets, pattern size 16): (dx, dy), in circular order.
constexpr int kCircle[16][2] = {{0, 3},  {1, 3},   {2, 2},   {3, 1},   {3, 0},  {3, -1}, {2, -2}, {1, -3},
                                {0, -3}, {-1, -3}, {-2, -2}, {-3, -1}, {-3, 0}, {-3, 1}, {-2, 2}, {-1, 3}};

int circle_offset(int k, int stride) { return kCircle[k][0] + kCircle[k][1] * stride; }

// max over k of min(a[k], ..., a[k + 8]) (indices mod 16), by doubling: min of 2, 4, 8, then 9.
template <class V, class Ops>
V arc_max(const V* a) {
  V m2[16], m4[16];
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) m2[k] = Ops::min(a[k], a[(k + 1) & 15]);
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) m4[k] = Ops::min(m2[k], m2[(k + 2) & 15]);
  V best = Ops::min(Ops::min(m4[0], m4[4]), a[8]);
#pragma GCC unroll 16
  for (int k = 1; k < 16; ++k) best = Ops::max(best, Ops::min(Ops::min(m4[k], m4[(k + 4) & 15]), a[(k + 8) & 15]));
  return best;
}

struct ScalarOps {
  static int min(int a, int b) { return std::min(a, b); }
  static int max(int a, int b) { return std::max(a, b); }
};

#ifdef AGVSLAM_FAST_X86
struct Sse2Ops {
  static __m128i min(__m128i a, __m128i b) { return _mm_min_epu8(a, b); }
  static __m128i max(__m128i a, __m128i b) { return _mm_max_epu8(a, b); }
};

void strength_sse2(const uint8_t* row, int stride, int n, uint8_t* out) {
  int off[16];
  for (int k = 0; k < 16; ++k) off[k] = circle_offset(k, stride);
  for (int x = 0; x < n; x += 16) {
    if (x + 16 > n) x = n - 16;  // last block overlaps the previous one (n >= 16 here)
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    __m128i dark[16], bright[16];
#pragma GCC unroll 16
    for (int k = 0; k < 16; ++k) {
      const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x + off[k]));
      dark[k] = _mm_subs_epu8(v, c);    // how much darker the circle pixel is (0 if not)
      bright[k] = _mm_subs_epu8(c, v);  // how much brighter
    }
    const __m128i s = _mm_max_epu8(arc_max<__m128i, Sse2Ops>(dark), arc_max<__m128i, Sse2Ops>(bright));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), s);
  }
}

struct Avx2Ops {
  __attribute__((target("avx2"))) static __m256i min(__m256i a, __m256i b) { return _mm256_min_epu8(a, b); }
  __attribute__((target("avx2"))) static __m256i max(__m256i a, __m256i b) { return _mm256_max_epu8(a, b); }
};

template <class V, class Ops>
__attribute__((target("avx2"))) V arc_max_avx2(const V* a) {
  V m2[16], m4[16];
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) m2[k] = Ops::min(a[k], a[(k + 1) & 15]);
#pragma GCC unroll 16
  for (int k = 0; k < 16; ++k) m4[k] = Ops::min(m2[k], m2[(k + 2) & 15]);
  V best = Ops::min(Ops::min(m4[0], m4[4]), a[8]);
#pragma GCC unroll 16
  for (int k = 1; k < 16; ++k) best = Ops::max(best, Ops::min(Ops::min(m4[k], m4[(k + 4) & 15]), a[(k + 8) & 15]));
  return best;
}

__attribute__((target("avx2"))) void strength_avx2(const uint8_t* row, int stride, int n, uint8_t* out) {
  int off[16];
  for (int k = 0; k < 16; ++k) off[k] = circle_offset(k, stride);
  for (int x = 0; x < n; x += 32) {
    if (x + 32 > n) x = n - 32;  // n >= 32 here
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x));
    __m256i dark[16], bright[16];
#pragma GCC unroll 16
    for (int k = 0; k < 16; ++k) {
      const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row + x + off[k]));
      dark[k] = _mm256_subs_epu8(v, c);
      bright[k] = _mm256_subs_epu8(c, v);
    }
    const __m256i s = _mm256_max_epu8(arc_max_avx2<__m256i, Avx2Ops>(dark), arc_max_avx2<__m256i, Avx2Ops>(bright));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x), s);
  }
}

bool has_avx2() {
  static const bool avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return avx2;
}
#endif
}  // namespace

void fast_strength_row_scalar(const uint8_t* row, int stride, int n, uint8_t* out) {
  int off[16];
  for (int k = 0; k < 16; ++k) off[k] = circle_offset(k, stride);
  for (int x = 0; x < n; ++x) {
    const int v = row[x];
    int dark[16], bright[16];
    for (int k = 0; k < 16; ++k) {
      const int c = row[x + off[k]];
      dark[k] = std::max(v - c, 0);
      bright[k] = std::max(c - v, 0);
    }
    out[x] = static_cast<uint8_t>(std::max(arc_max<int, ScalarOps>(dark), arc_max<int, ScalarOps>(bright)));
  }
}

void fast_strength_row(const uint8_t* row, int stride, int n, uint8_t* out) {
#ifdef AGVSLAM_FAST_X86
  if (n >= 32 && has_avx2()) {
    strength_avx2(row, stride, n, out);
    return;
  }
  if (n >= 16) {
    strength_sse2(row, stride, n, out);
    return;
  }
#endif
  fast_strength_row_scalar(row, stride, n, out);
}

int local_maxima_row(const uint8_t* row, int step, int x0, int x1, int threshold, int* xs) {
  const uint8_t* up = row - step;
  const uint8_t* down = row + step;
  int count = 0;
  int x = x0;
#if defined(__SSE2__)
  // Unsigned a > b as signed compares after flipping the top bit.
  const __m128i flip = _mm_set1_epi8(static_cast<char>(0x80));
  const __m128i th = _mm_xor_si128(_mm_set1_epi8(static_cast<char>(threshold)), flip);
  auto load = [&](const uint8_t* p) {
    return _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)), flip);
  };
  for (; x + 16 <= x1; x += 16) {
    const __m128i v = load(row + x);
    __m128i m = _mm_cmpgt_epi8(v, th);
    if (_mm_movemask_epi8(m) == 0) continue;
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(row + x - 1)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(row + x + 1)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(up + x - 1)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(up + x)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(up + x + 1)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(down + x - 1)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(down + x)));
    m = _mm_and_si128(m, _mm_cmpgt_epi8(v, load(down + x + 1)));
    unsigned bits = static_cast<unsigned>(_mm_movemask_epi8(m));
    while (bits != 0) {
      xs[count++] = x + __builtin_ctz(bits);
      bits &= bits - 1;
    }
  }
#endif
  for (; x < x1; ++x) {
    const int v = row[x];
    if (v <= threshold) continue;
    if (v > row[x - 1] && v > row[x + 1] && v > up[x - 1] && v > up[x] && v > up[x + 1] && v > down[x - 1] &&
        v > down[x] && v > down[x + 1]) {
      xs[count++] = x;
    }
  }
  return count;
}

}  // namespace agvslam::features::detail
