#include "orb_kernels.h"

#include <opencv2/core.hpp>

#include "orb_pattern.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#define AGVSLAM_ORB_SSE2 1
#endif

namespace agvslam::features::detail {

namespace {
constexpr int kHalfPatch = 15;

// The pattern as separate float arrays: first point (a) and second point (b) of each of the 256 tests, in test
// order (bit t of the descriptor compares point 2 t with point 2 t + 1 of OpenCV's table).
struct PatternTable {
  alignas(16) float ax[256], ay[256], bx[256], by[256];
  PatternTable() {
    for (int t = 0; t < 256; ++t) {
      ax[t] = static_cast<float>(kOrbBitPattern31[4 * t + 0]);
      ay[t] = static_cast<float>(kOrbBitPattern31[4 * t + 1]);
      bx[t] = static_cast<float>(kOrbBitPattern31[4 * t + 2]);
      by[t] = static_cast<float>(kOrbBitPattern31[4 * t + 3]);
    }
  }
};
const PatternTable& pattern_table() {
  static const PatternTable table;
  return table;
}

#ifdef AGVSLAM_ORB_SSE2
// Weights for one row pair of the disc: u (or 0 outside [-d, d]) and v (or 0), over u = -15 .. 16.
struct MomentWeights {
  alignas(16) int16_t u[16][32];
  alignas(16) int16_t v[16][32];
  int built_for[16];
};
#endif
}  // namespace

void ic_moments_scalar(const uint8_t* center, int step, const int* umax, int& m_01, int& m_10) {
  m_01 = 0;
  m_10 = 0;
  for (int u = -kHalfPatch; u <= kHalfPatch; ++u) m_10 += u * center[u];
  for (int v = 1; v <= kHalfPatch; ++v) {
    int v_sum = 0;
    const int d = umax[v];
    for (int u = -d; u <= d; ++u) {
      const int val_plus = center[u + v * step], val_minus = center[u - v * step];
      v_sum += val_plus - val_minus;
      m_10 += u * (val_plus + val_minus);
    }
    m_01 += v * v_sum;
  }
}

void orb_descriptor_scalar(const uint8_t* center, int step, float a, float b, uint8_t* descriptor) {
  const PatternTable& p = pattern_table();
  auto value = [&](float px, float py) {
    const float x = px * a - py * b;
    const float y = px * b + py * a;
    return static_cast<int>(center[cvRound(y) * step + cvRound(x)]);
  };
  for (int i = 0; i < 32; ++i) {
    int val = 0;
    for (int bit = 0; bit < 8; ++bit) {
      const int t = 8 * i + bit;
      val |= (value(p.ax[t], p.ay[t]) < value(p.bx[t], p.by[t]) ? 1 : 0) << bit;
    }
    descriptor[i] = static_cast<uint8_t>(val);
  }
}

#ifdef AGVSLAM_ORB_SSE2

void ic_moments(const uint8_t* center, int step, const int* umax, int& m_01, int& m_10) {
  // Row weights depend only on umax (fixed for the extractor); build them on first use.
  thread_local MomentWeights w = [] {
    MomentWeights m{};
    for (int& b : m.built_for) b = -1;
    return m;
  }();
  for (int v = 0; v <= kHalfPatch; ++v) {
    if (w.built_for[v] == umax[v]) continue;
    for (int k = 0; k < 32; ++k) {
      const int u = k - kHalfPatch;
      const bool inside = u >= -umax[v] && u <= umax[v];
      w.u[v][k] = static_cast<int16_t>(inside ? u : 0);
      w.v[v][k] = static_cast<int16_t>(inside ? v : 0);
    }
    w.built_for[v] = umax[v];
  }
  const __m128i zero = _mm_setzero_si128();
  auto load_row = [&](const uint8_t* row, __m128i out[4]) {
    const __m128i lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row - kHalfPatch));
    const __m128i hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row - kHalfPatch + 16));
    out[0] = _mm_unpacklo_epi8(lo, zero);
    out[1] = _mm_unpackhi_epi8(lo, zero);
    out[2] = _mm_unpacklo_epi8(hi, zero);
    out[3] = _mm_unpackhi_epi8(hi, zero);
  };
  __m128i acc10 = _mm_setzero_si128(), acc01 = _mm_setzero_si128();
  __m128i r0[4];
  load_row(center, r0);
  for (int k = 0; k < 4; ++k) {
    acc10 =
        _mm_add_epi32(acc10, _mm_madd_epi16(r0[k], _mm_load_si128(reinterpret_cast<const __m128i*>(w.u[0] + 8 * k))));
  }
  for (int v = 1; v <= kHalfPatch; ++v) {
    __m128i plus[4], minus[4];
    load_row(center + v * step, plus);
    load_row(center - v * step, minus);
    for (int k = 0; k < 4; ++k) {
      const __m128i wu = _mm_load_si128(reinterpret_cast<const __m128i*>(w.u[v] + 8 * k));
      const __m128i wv = _mm_load_si128(reinterpret_cast<const __m128i*>(w.v[v] + 8 * k));
      acc10 = _mm_add_epi32(acc10, _mm_madd_epi16(_mm_add_epi16(plus[k], minus[k]), wu));
      acc01 = _mm_add_epi32(acc01, _mm_madd_epi16(_mm_sub_epi16(plus[k], minus[k]), wv));
    }
  }
  alignas(16) int32_t s10[4], s01[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(s10), acc10);
  _mm_store_si128(reinterpret_cast<__m128i*>(s01), acc01);
  m_10 = s10[0] + s10[1] + s10[2] + s10[3];
  m_01 = s01[0] + s01[1] + s01[2] + s01[3];
}

void orb_descriptor(const uint8_t* center, int step, float a, float b, uint8_t* descriptor) {
  const PatternTable& p = pattern_table();
  alignas(16) int32_t off_a[256], off_b[256];
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b), vstep = _mm_set1_ps(static_cast<float>(step));
  auto offsets = [&](const float* px, const float* py, int32_t* out) {
    for (int t = 0; t < 256; t += 4) {
      const __m128 x = _mm_load_ps(px + t), y = _mm_load_ps(py + t);
      // OpenCV: x' = px a - py b, y' = px b + py a, each rounded half to even (cvRound).
      const __m128i ix = _mm_cvtps_epi32(_mm_sub_ps(_mm_mul_ps(x, va), _mm_mul_ps(y, vb)));
      const __m128i iy = _mm_cvtps_epi32(_mm_add_ps(_mm_mul_ps(x, vb), _mm_mul_ps(y, va)));
      // iy * step + ix in float is exact (|value| < 2^24).
      const __m128 off = _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(iy), vstep), _mm_cvtepi32_ps(ix));
      _mm_store_si128(reinterpret_cast<__m128i*>(out + t), _mm_cvttps_epi32(off));
    }
  };
  offsets(p.ax, p.ay, off_a);
  offsets(p.bx, p.by, off_b);
  alignas(16) uint8_t val_a[256], val_b[256];
  for (int t = 0; t < 256; ++t) {
    val_a[t] = center[off_a[t]];
    val_b[t] = center[off_b[t]];
  }
  const __m128i bias = _mm_set1_epi8(static_cast<char>(0x80));
  for (int t = 0; t < 256; t += 16) {
    const __m128i x = _mm_xor_si128(_mm_load_si128(reinterpret_cast<const __m128i*>(val_a + t)), bias);
    const __m128i y = _mm_xor_si128(_mm_load_si128(reinterpret_cast<const __m128i*>(val_b + t)), bias);
    const int bits = _mm_movemask_epi8(_mm_cmplt_epi8(x, y));  // bit k: test t + k
    descriptor[t / 8] = static_cast<uint8_t>(bits & 0xff);
    descriptor[t / 8 + 1] = static_cast<uint8_t>((bits >> 8) & 0xff);
  }
}

#else

void ic_moments(const uint8_t* center, int step, const int* umax, int& m_01, int& m_10) {
  ic_moments_scalar(center, step, umax, m_01, m_10);
}
void orb_descriptor(const uint8_t* center, int step, float a, float b, uint8_t* descriptor) {
  orb_descriptor_scalar(center, step, a, b, descriptor);
}

#endif

}  // namespace agvslam::features::detail
