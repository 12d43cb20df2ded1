#include "sad_kernels.h"

#include <cstdlib>
#include <cstring>
#include <initializer_list>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define AGVSLAM_SAD_X86 1
#endif

namespace agvslam::features::detail {

void sad_costs_scalar(const uint8_t* const* left_rows, const uint8_t* const* right_rows, int rows, int blocks, int n,
                      uint16_t* costs) {
  const int cols = 4 * blocks;
  for (int k = 0; k < n; ++k) {
    uint32_t sum = 0;
    for (int r = 0; r < rows; ++r) {
      const uint8_t* l = left_rows[r];
      const uint8_t* rr = right_rows[r] + k;
      for (int c = 0; c < cols; ++c)
        sum += static_cast<uint32_t>(std::abs(static_cast<int>(l[c]) - static_cast<int>(rr[c])));
    }
    costs[k] = static_cast<uint16_t>(sum);
  }
}

#ifdef AGVSLAM_SAD_X86
namespace {

// mpsadbw: for 8 consecutive offsets j, sum_i |a[off + j + i] - b[4 s + i]| over i < 4, where off (0 or 4) and
// the block s come from the immediate. Block s of the window sits at right columns 4 s .. 4 s + 3: load a at
// 8 (s / 2) and use off = 4 (s % 2).
template <int Blocks>
__attribute__((target("sse4.1"))) void sad_sse41(const uint8_t* const* left_rows, const uint8_t* const* right_rows,
                                                 int rows, int n, uint16_t* costs) {
  for (int k = 0; k < n; k += 8) {
    __m128i acc = _mm_setzero_si128();
    for (int r = 0; r < rows; ++r) {
      const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(left_rows[r]));
      const uint8_t* rr = right_rows[r] + k;
      const __m128i a0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rr));
      acc = _mm_add_epi16(acc, _mm_mpsadbw_epu8(a0, l, 0));
      if (Blocks > 1) acc = _mm_add_epi16(acc, _mm_mpsadbw_epu8(a0, l, 5));
      if (Blocks > 2) {
        const __m128i a1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(rr + 8));
        acc = _mm_add_epi16(acc, _mm_mpsadbw_epu8(a1, l, 2));
        if (Blocks > 3) acc = _mm_add_epi16(acc, _mm_mpsadbw_epu8(a1, l, 7));
      }
    }
    _mm_storeu_si128(reinterpret_cast<__m128i*>(costs + k), acc);
  }
}

// AVX2: the low 128-bit lane handles offsets k .. k + 7, the high lane k + 8 .. k + 15 (its data starts 8 bytes
// further: qwords (0, 1 | 1, 2) of a 32-byte load).
template <int Blocks>
__attribute__((target("avx2"))) void sad_avx2(const uint8_t* const* left_rows, const uint8_t* const* right_rows,
                                              int rows, int n, uint16_t* costs) {
  for (int k = 0; k < n; k += 16) {
    __m256i acc = _mm256_setzero_si256();
    for (int r = 0; r < rows; ++r) {
      const __m256i l = _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(left_rows[r])));
      const uint8_t* rr = right_rows[r] + k;
      const __m256i a0 = _mm256_permute4x64_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(rr)), 0x94);
      acc = _mm256_add_epi16(acc, _mm256_mpsadbw_epu8(a0, l, 0));
      if (Blocks > 1) acc = _mm256_add_epi16(acc, _mm256_mpsadbw_epu8(a0, l, 5 | (5 << 3)));
      if (Blocks > 2) {
        const __m256i a1 = _mm256_permute4x64_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(rr + 8)), 0x94);
        acc = _mm256_add_epi16(acc, _mm256_mpsadbw_epu8(a1, l, 2 | (2 << 3)));
        if (Blocks > 3) acc = _mm256_add_epi16(acc, _mm256_mpsadbw_epu8(a1, l, 7 | (7 << 3)));
      }
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(costs + k), acc);
  }
}

__attribute__((target("sse4.1"))) void sse41_entry(const uint8_t* const* left_rows, const uint8_t* const* right_rows,
                                                   int rows, int blocks, int n, uint16_t* costs) {
  switch (blocks) {
    case 1:
      sad_sse41<1>(left_rows, right_rows, rows, n, costs);
      break;
    case 2:
      sad_sse41<2>(left_rows, right_rows, rows, n, costs);
      break;
    case 3:
      sad_sse41<3>(left_rows, right_rows, rows, n, costs);
      break;
    default:
      sad_sse41<4>(left_rows, right_rows, rows, n, costs);
      break;
  }
}

__attribute__((target("avx2"))) void avx2_entry(const uint8_t* const* left_rows, const uint8_t* const* right_rows,
                                                int rows, int blocks, int n, uint16_t* costs) {
  switch (blocks) {
    case 1:
      sad_avx2<1>(left_rows, right_rows, rows, n, costs);
      break;
    case 2:
      sad_avx2<2>(left_rows, right_rows, rows, n, costs);
      break;
    case 3:
      sad_avx2<3>(left_rows, right_rows, rows, n, costs);
      break;
    default:
      sad_avx2<4>(left_rows, right_rows, rows, n, costs);
      break;
  }
}

}  // namespace
#endif

SadRowKernel sad_kernel(const char* name) {
  if (std::strcmp(name, "scalar") == 0) return &sad_costs_scalar;
#ifdef AGVSLAM_SAD_X86
  __builtin_cpu_init();
  if (std::strcmp(name, "sse41") == 0 && __builtin_cpu_supports("sse4.1")) return &sse41_entry;
  if (std::strcmp(name, "avx2") == 0 && __builtin_cpu_supports("avx2")) return &avx2_entry;
#endif
  return nullptr;
}

SadRowKernel best_sad_kernel(const char** name) {
  for (const char* candidate : {"avx2", "sse41", "scalar"}) {
    if (SadRowKernel k = sad_kernel(candidate)) {
      if (name) *name = candidate;
      return k;
    }
  }
  return &sad_costs_scalar;
}

}  // namespace agvslam::features::detail
