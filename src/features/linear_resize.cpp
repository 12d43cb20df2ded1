#include "agvslam/features/linear_resize.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define AGVSLAM_RESIZE_X86 1
#endif

namespace agvslam::features {

namespace {

// OpenCV's interpolationLinear::getCoeffs for one axis: the source offset and the two 8-bit fixed-point weights
// of each output position. Positions before the first source pixel or beyond the last take that pixel.
void axis_coefficients(int src_len, int dst_len, std::vector<int>& ofs, std::vector<uint16_t>& c0,
                       std::vector<uint16_t>& c1) {
  ofs.resize(static_cast<std::size_t>(dst_len));
  c0.resize(static_cast<std::size_t>(dst_len));
  c1.resize(static_cast<std::size_t>(dst_len));
  const double inv_scale = static_cast<double>(dst_len) / static_cast<double>(src_len);
  const double scale = 1.0 / inv_scale;
  for (int d = 0; d < dst_len; ++d) {
    const double f = scale * (static_cast<double>(d) + 0.5) - 0.5;
    const int i = static_cast<int>(std::floor(f));
    std::size_t k = static_cast<std::size_t>(d);
    if (i < 0) {
      ofs[k] = 0;
      c0[k] = 256;
      c1[k] = 0;
    } else if (i >= src_len - 1) {
      ofs[k] = src_len - 1;
      c0[k] = 256;
      c1[k] = 0;
    } else {
      ofs[k] = i;
      // ufixedpoint16(double): round half to even of f * 256.
      const double frac = (f - static_cast<double>(i)) * 256.0;
      c1[k] = static_cast<uint16_t>(std::nearbyint(frac));
      c0[k] = static_cast<uint16_t>(256 - c1[k]);
    }
  }
}

#ifdef AGVSLAM_RESIZE_X86
__attribute__((target("ssse3"))) void horizontal_ssse3(const uint8_t* src, const int* block_base,
                                                       const uint8_t* shuffles, const uint16_t* c0, const uint16_t* c1,
                                                       int blocks, uint16_t* out) {
  for (int b = 0; b < blocks; ++b) {
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + block_base[b]));
    const __m128i p0 = _mm_shuffle_epi8(s, _mm_loadu_si128(reinterpret_cast<const __m128i*>(shuffles + 32 * b)));
    const __m128i p1 = _mm_shuffle_epi8(s, _mm_loadu_si128(reinterpret_cast<const __m128i*>(shuffles + 32 * b + 16)));
    const __m128i w0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(c0 + 8 * b));
    const __m128i w1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(c1 + 8 * b));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 8 * b),
                     _mm_add_epi16(_mm_mullo_epi16(p0, w0), _mm_mullo_epi16(p1, w1)));
  }
}
#endif

// (h0 m0 + h1 m1 + 2^15) >> 16 for one output row (the exact sum fits 32 bits; OpenCV rounds once, here too).
void vertical(const uint16_t* h0, const uint16_t* h1, uint16_t m0, uint16_t m1, int width, uint8_t* out) {
  int x = 0;
#if defined(__SSE2__)
  // Signed trick (as OpenCV): (h - 2^15) fits int16; sum (h_i - 2^15) m_i = sum h_i m_i - 2^15 * 256.
  const __m128i bias16 = _mm_set1_epi16(static_cast<short>(0x8000));
  const __m128i weights =
      _mm_set1_epi32(static_cast<int>(static_cast<uint32_t>(m0) | (static_cast<uint32_t>(m1) << 16)));
  const __m128i add_back = _mm_set1_epi32((1 << 23) + (1 << 15));
  for (; x + 8 <= width; x += 8) {
    const __m128i a = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h0 + x)), bias16);
    const __m128i b = _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(h1 + x)), bias16);
    const __m128i lo = _mm_srli_epi32(_mm_add_epi32(_mm_madd_epi16(_mm_unpacklo_epi16(a, b), weights), add_back), 16);
    const __m128i hi = _mm_srli_epi32(_mm_add_epi32(_mm_madd_epi16(_mm_unpackhi_epi16(a, b), weights), add_back), 16);
    const __m128i packed = _mm_packs_epi32(lo, hi);  // values <= 255
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(packed, packed));
  }
#endif
  for (; x < width; ++x) {
    const uint32_t v = static_cast<uint32_t>(h0[x]) * m0 + static_cast<uint32_t>(h1[x]) * m1 + (1u << 15);
    out[x] = static_cast<uint8_t>(std::min<uint32_t>(v >> 16, 255));
  }
}

}  // namespace

void LinearExactResizer::prepare(cv::Size src, cv::Size dst) {
  src_size_ = src;
  dst_size_ = dst;
  row_id_[0] = row_id_[1] = -1;
  const double fx = static_cast<double>(dst.width) / src.width, fy = static_cast<double>(dst.height) / src.height;
  // OpenCV halves by area averaging; upscaling and factors above 2 are outside this scheme.
  usable_ = !(fx == 0.5 && fy == 0.5) && fx >= 0.5 && fy >= 0.5 && fx < 1.0 && fy <= 1.0 && dst.width >= 1 &&
            dst.height >= 1 && src.width >= 2 && src.height >= 2;
  if (!usable_) return;
  axis_coefficients(src.width, dst.width, x_ofs_, x_c0_, x_c1_);
  axis_coefficients(src.height, dst.height, y_ofs_, y_c0_, y_c1_);
  const int blocks = dst.width / 8;
  block_base_.resize(static_cast<std::size_t>(blocks));
  block_shuffle_.assign(static_cast<std::size_t>(blocks) * 32, 0x80);
  for (int b = 0; b < blocks; ++b) {
    const int base = x_ofs_[static_cast<std::size_t>(8 * b)];
    block_base_[static_cast<std::size_t>(b)] = base;
    for (int k = 0; k < 8; ++k) {
      const int o = x_ofs_[static_cast<std::size_t>(8 * b + k)] - base;
      if (o + 1 > 15) usable_ = false;  // eight outputs must read within 16 source bytes
      block_shuffle_[static_cast<std::size_t>(32 * b + 2 * k)] = static_cast<uint8_t>(o);
      block_shuffle_[static_cast<std::size_t>(32 * b + 16 + 2 * k)] = static_cast<uint8_t>(o + 1);
    }
  }
  for (auto& r : rows_) r.resize(static_cast<std::size_t>(dst.width) + 8);
#ifdef AGVSLAM_RESIZE_X86
  __builtin_cpu_init();
  ssse3_ = __builtin_cpu_supports("ssse3");
#endif
}

void LinearExactResizer::horizontal(const uint8_t* src_row, uint16_t* out) const {
  const int width = dst_size_.width;
  int x = 0;
#ifdef AGVSLAM_RESIZE_X86
  if (ssse3_) {
    const int blocks = width / 8;
    horizontal_ssse3(src_row, block_base_.data(), block_shuffle_.data(), x_c0_.data(), x_c1_.data(), blocks, out);
    x = 8 * blocks;
  }
#endif
  for (; x < width; ++x) {
    const std::size_t k = static_cast<std::size_t>(x);
    const uint8_t* p = src_row + x_ofs_[k];
    out[k] = static_cast<uint16_t>(x_c0_[k] * p[0] + x_c1_[k] * p[1]);
  }
}

void LinearExactResizer::resize(const cv::Mat& src, cv::Mat& dst) {
  CV_Assert(src.type() == CV_8UC1 && dst.type() == CV_8UC1);
  if (src.size() != src_size_ || dst.size() != dst_size_) prepare(src.size(), dst.size());
  last_fast_ = usable_;
  if (!usable_) {
    cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_LINEAR_EXACT);
    return;
  }
  row_id_[0] = row_id_[1] = -1;
  const int last_row = src.rows - 1;
  auto row = [&](int y) -> const uint16_t* {
    for (int k = 0; k < 2; ++k) {
      if (row_id_[k] == y) return rows_[k].data();
    }
    // Replace the row not needed any more (rows are requested in increasing order).
    const int slot = row_id_[0] < row_id_[1] ? 0 : 1;
    horizontal(src.ptr<uint8_t>(y), rows_[slot].data());
    row_id_[slot] = y;
    return rows_[slot].data();
  };
  for (int dy = 0; dy < dst.rows; ++dy) {
    const std::size_t k = static_cast<std::size_t>(dy);
    const int y0 = y_ofs_[k];
    const int y1 = std::min(y0 + 1, last_row);
    const uint16_t* h0 = row(y0);
    const uint16_t* h1 = y_c1_[k] != 0 ? row(y1) : h0;
    vertical(h0, h1, y_c0_[k], y_c1_[k], dst.cols, dst.ptr<uint8_t>(dy));
  }
}

}  // namespace agvslam::features
