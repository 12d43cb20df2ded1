#include "agvslam/stereo/sparse_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "agvslam/core/cpu_clones.h"

namespace agvslam::stereo {

namespace {
constexpr int32_t kQuarter = 4;  // intensities in quarter grey levels inside the matcher

// The matching costs of one window row for every candidate: rc[e] = sum_i |ref_row[i] - strip[i + e] + means[e]|,
// then added to costs[e]. In an AVX2 and a baseline copy (agvslam/core/cpu_clones.h): 16-lane integer arithmetic
// where the CPU has it, identical results in either.
AGVSLAM_CPU_CLONES
void accumulate_row_costs(const int16_t* ref_row, int side, const int16_t* strip, const int16_t* means, int m,
                          uint16_t* rc, int32_t* costs) {
  for (int e = 0; e < m; ++e) rc[e] = 0;
  for (int i = 0; i < side; ++i) {
    const int16_t lv = ref_row[i];
    const int16_t* sv = strip + i;
    for (int e = 0; e < m; ++e) {
      const int16_t diff = static_cast<int16_t>(lv - sv[e] + means[e]);
      rc[e] = static_cast<uint16_t>(rc[e] + static_cast<uint16_t>(diff < 0 ? -diff : diff));
    }
  }
  for (int e = 0; e < m; ++e) costs[e] += rc[e];
}

// Least of c[lo, hi) (INT32_MAX for an empty range).
int32_t range_min(const int32_t* c, int lo, int hi) {
  int32_t mn = std::numeric_limits<int32_t>::max();
  for (int e = std::max(lo, 0); e < hi; ++e) mn = std::min(mn, c[e]);
  return mn;
}
}  // namespace

const char* to_string(SparseMatchStatus status) {
  switch (status) {
    case SparseMatchStatus::kOk:
      return "ok";
    case SparseMatchStatus::kOutside:
      return "outside";
    case SparseMatchStatus::kNoTexture:
      return "no texture";
    case SparseMatchStatus::kNotUnique:
      return "not unique";
    case SparseMatchStatus::kHighCost:
      return "high cost";
    case SparseMatchStatus::kLeftRight:
      return "left-right check";
    case SparseMatchStatus::kRange:
      return "out of range";
  }
  return "?";
}

SparseStereoMatcher::SparseStereoMatcher(const SparseStereoConfig& config) : config_(config) {
  config_.validate("SparseStereoConfig");
}

SparseStereoMatcher::Search SparseStereoMatcher::search(const cv::Mat& ref, const cv::Mat& other, int x, int y,
                                                        int direction, int d_lo, int d_hi) {
  Search out;
  const int r = config_.half_window;
  const int side = 2 * r + 1;
  const int n = side * side;
  const int width = ref.cols;
  // Candidate columns in `other`, clipped so that each window lies inside the image.
  int c_lo = direction < 0 ? x - d_hi : x + d_lo;
  int c_hi = direction < 0 ? x - d_lo : x + d_hi;
  c_lo = std::max(c_lo, r);
  c_hi = std::min(c_hi, width - 1 - r);
  const int m = c_hi - c_lo + 1;
  if (m < 3) return out;
  out.first_column = c_lo;

  // Zero-mean SAD in 16-bit integers, intensities in quarter grey levels (kQuarter): the reference window
  // minus its mean, and each candidate window minus its own mean, |difference| accumulated per window row in
  // 16 bits (at most 21 columns x 2040) and per window in 32 bits. The inner loops run over the candidates,
  // contiguous in memory, so the compiler vectorises them (8 lanes with SSE2).
  ref_zero_mean_.resize(static_cast<std::size_t>(n));
  int32_t sum_ref = 0;
  for (int j = 0; j < side; ++j) {
    const uint8_t* row = ref.ptr<uint8_t>(y - r + j) + (x - r);
    for (int i = 0; i < side; ++i) sum_ref += row[i];
  }
  const int32_t mean_ref_q = (kQuarter * sum_ref + n / 2) / n;
  int64_t abs_dev = 0;
  for (int j = 0; j < side; ++j) {
    const uint8_t* row = ref.ptr<uint8_t>(y - r + j) + (x - r);
    for (int i = 0; i < side; ++i) {
      const int16_t v = static_cast<int16_t>(kQuarter * static_cast<int32_t>(row[i]) - mean_ref_q);
      ref_zero_mean_[static_cast<std::size_t>(j * side + i)] = v;
      abs_dev += std::abs(static_cast<int32_t>(v));
    }
  }
  out.texture = static_cast<double>(abs_dev) / (static_cast<double>(kQuarter) * n);

  // Window means of `other` for every candidate column (column sums, then a running sum).
  const int strip_width = m + 2 * r;
  const int strip_x0 = c_lo - r;
  col_sums_.assign(static_cast<std::size_t>(strip_width), 0);
  for (int j = 0; j < side; ++j) {
    const uint8_t* row = other.ptr<uint8_t>(y - r + j) + strip_x0;
    for (int k = 0; k < strip_width; ++k) col_sums_[static_cast<std::size_t>(k)] += row[k];
  }
  // (4 sum + n/2) / n rounded down, without a division per candidate: the numerator is below 2^19 and a quotient
  // that is not whole lies at least 1/n from the next integer, so adding half a unit and multiplying by the
  // float reciprocal (relative error < 1e-7) gives the same integer.
  const float inv_n = 1.0f / static_cast<float>(n);
  auto window_mean = [&](int32_t sum) {
    return static_cast<int16_t>((static_cast<float>(kQuarter * sum + n / 2) + 0.5f) * inv_n);
  };
  win_means_.resize(static_cast<std::size_t>(m));
  int32_t running = 0;
  for (int k = 0; k < side; ++k) running += col_sums_[static_cast<std::size_t>(k)];
  win_means_[0] = window_mean(running);
  for (int e = 1; e < m; ++e) {
    running += col_sums_[static_cast<std::size_t>(e + side - 1)] - col_sums_[static_cast<std::size_t>(e - 1)];
    win_means_[static_cast<std::size_t>(e)] = window_mean(running);
  }

  costs_.assign(static_cast<std::size_t>(m), 0);
  strip_scaled_.resize(static_cast<std::size_t>(strip_width));
  row_costs_.resize(static_cast<std::size_t>(m));
  const int16_t* wm = win_means_.data();
  int32_t* cs = costs_.data();
  uint16_t* rc = row_costs_.data();
  for (int j = 0; j < side; ++j) {
    const uint8_t* row = other.ptr<uint8_t>(y - r + j) + strip_x0;
    for (int k = 0; k < strip_width; ++k) {
      strip_scaled_[static_cast<std::size_t>(k)] = static_cast<int16_t>(kQuarter * static_cast<int32_t>(row[k]));
    }
    accumulate_row_costs(ref_zero_mean_.data() + static_cast<std::size_t>(j * side), side, strip_scaled_.data(), wm, m,
                         rc, cs);
  }

  // The first minimum and the least cost more than one column from it. Minima over plain ranges (vectorised),
  // not a running arg-min (a chain of dependent compares per candidate).
  const int32_t* c = costs_.data();
  const int32_t best_cost = range_min(c, 0, m);
  int best = 0;
  while (c[best] != best_cost) ++best;
  const int32_t second_cost = std::min(range_min(c, 0, best - 1), range_min(c, best + 2, m));
  const int64_t second =
      second_cost == std::numeric_limits<int32_t>::max() ? std::numeric_limits<int64_t>::max() : second_cost;
  out.ok = true;
  out.best_column = c_lo + best;
  out.best_cost = costs_[static_cast<std::size_t>(best)];
  out.second_cost = second;
  return out;
}

float SparseStereoMatcher::match(const cv::Mat& left, const cv::Mat& right, cv::Point2f point_px,
                                 SparseMatchStatus* status) {
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  auto fail = [&](SparseMatchStatus s) {
    if (status) *status = s;
    return 0.0f;
  };
  const int r = config_.half_window;
  const int n = (2 * r + 1) * (2 * r + 1);
  const int x = static_cast<int>(std::lround(point_px.x));
  const int y = static_cast<int>(std::lround(point_px.y));
  if (!(point_px.x == point_px.x) || x < r || y < r || x >= left.cols - r || y >= left.rows - r) {
    return fail(SparseMatchStatus::kOutside);
  }
  const Search s = search(left, right, x, y, -1, config_.min_disparity, config_.max_disparity());
  if (!s.ok) return fail(SparseMatchStatus::kOutside);
  if (s.texture < config_.min_texture) return fail(SparseMatchStatus::kNoTexture);
  const double mean_cost = static_cast<double>(s.best_cost) / (static_cast<double>(kQuarter) * n);
  if (mean_cost > config_.max_mean_cost || mean_cost > config_.max_cost_ratio * s.texture) {
    return fail(SparseMatchStatus::kHighCost);
  }
  if (s.second_cost != std::numeric_limits<int64_t>::max() &&
      static_cast<double>(s.second_cost) <= static_cast<double>(s.best_cost) * (1.0 + config_.uniqueness_margin)) {
    return fail(SparseMatchStatus::kNotUnique);
  }
  const int e = s.best_column - s.first_column;
  const int m = static_cast<int>(costs_.size());
  if (e <= 0 || e >= m - 1) return fail(SparseMatchStatus::kRange);  // minimum at the end of the range
  const int d_int = x - s.best_column;
  double d = d_int;
  if (config_.subpixel) {
    const double c_minus = static_cast<double>(costs_[static_cast<std::size_t>(e - 1)]);
    const double c_zero = static_cast<double>(costs_[static_cast<std::size_t>(e)]);
    const double c_plus = static_cast<double>(costs_[static_cast<std::size_t>(e + 1)]);
    const double denom = c_minus - 2.0 * c_zero + c_plus;
    if (denom > 0) {
      const double offset = std::clamp(0.5 * (c_minus - c_plus) / denom, -0.5, 0.5);  // in columns
      d = d_int - offset;
    }
  }
  if (config_.lr_max_diff_px >= 0) {
    const int xr = s.best_column;
    const Search back = search(right, left, xr, y, +1, config_.min_disparity, config_.max_disparity());
    if (!back.ok || std::abs((back.best_column - xr) - d_int) > config_.lr_max_diff_px) {
      return fail(SparseMatchStatus::kLeftRight);
    }
  }
  if (d <= 0) return fail(SparseMatchStatus::kRange);
  if (status) *status = SparseMatchStatus::kOk;
  return static_cast<float>(d);
}

void SparseStereoMatcher::match(const cv::Mat& left, const cv::Mat& right, const std::vector<cv::Point2f>& points_px,
                                std::vector<float>& disparity_px) {
  disparity_px.resize(points_px.size());
  for (std::size_t i = 0; i < points_px.size(); ++i) disparity_px[i] = match(left, right, points_px[i]);
}

}  // namespace agvslam::stereo
