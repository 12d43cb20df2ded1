#include "agvslam/dynamic/edge_refine.h"

#include <algorithm>
#include <cmath>

#include "agvslam/dynamic/median.h"

namespace agvslam::dynamic {

EdgeRefiner::EdgeRefiner(const EdgeRefineConfig& config) : config_(config) { config_.validate("EdgeRefineConfig"); }

namespace {

// Linear interpolation of row `row` at column x (0 <= x <= cols - 1).
inline float sample(const uint8_t* row, int cols, float x) {
  const int x0 = static_cast<int>(x);
  const int x1 = std::min(x0 + 1, cols - 1);
  const float a = x - static_cast<float>(x0);
  return (1.0f - a) * row[x0] + a * row[x1];
}

// Mean |left(xl, y') - right(xr, y')| over y' in [y0, y1], both sampled linearly between columns; -1 when a
// column leaves its image.
float column_cost(const cv::Mat& left, const cv::Mat& right, float xl, float xr, int y0, int y1) {
  const float last = static_cast<float>(left.cols - 1);
  if (xl < 0.0f || xr < 0.0f || xl > last || xr > last) return -1.0f;
  float sum = 0.0f;
  for (int y = y0; y <= y1; ++y) {
    sum += std::fabs(sample(left.ptr<uint8_t>(y), left.cols, xl) - sample(right.ptr<uint8_t>(y), right.cols, xr));
  }
  return sum / static_cast<float>(y1 - y0 + 1);
}

// out[i] = column_cost(left, right, xl0 + i, xr0 + i, y0, y1) for i in [0, n): one fraction per image, so the
// rows are walked once with fixed weights. False when a column leaves its image.
bool run_costs(const cv::Mat& left, const cv::Mat& right, float xl0, float xr0, int n, int y0, int y1, float* out) {
  if (xl0 < 0.0f || xr0 < 0.0f) return false;
  const int bl = static_cast<int>(xl0), br = static_cast<int>(xr0);
  const float al = xl0 - static_cast<float>(bl), ar = xr0 - static_cast<float>(br);
  if (bl + n > left.cols - 1 || br + n > right.cols - 1) {  // at the right border: one column at a time
    for (int i = 0; i < n; ++i) {
      out[i] = column_cost(left, right, xl0 + static_cast<float>(i), xr0 + static_cast<float>(i), y0, y1);
      if (out[i] < 0.0f) return false;
    }
    return true;
  }
  std::fill(out, out + n, 0.0f);
  for (int y = y0; y <= y1; ++y) {
    const uint8_t* l = left.ptr<uint8_t>(y) + bl;
    const uint8_t* r = right.ptr<uint8_t>(y) + br;
    for (int i = 0; i < n; ++i) {
      const float lv = (1.0f - al) * l[i] + al * l[i + 1];
      const float rv = (1.0f - ar) * r[i] + ar * r[i + 1];
      out[i] += std::fabs(lv - rv);
    }
  }
  const float inv = 1.0f / static_cast<float>(y1 - y0 + 1);
  for (int i = 0; i < n; ++i) out[i] *= inv;
  return true;
}

// The object's disparity of the row run [xs, xe]: the median away from its ends (where SGBM fattened it), else of
// the whole run, at most ~16 samples; 0 when the run has none.
float run_disparity(const float* disp, int xs, int xe, int band_px, std::vector<float>& values) {
  values.clear();
  const bool long_run = xe - xs + 1 > 2 * band_px + 2;
  const int k0 = long_run ? xs + band_px : xs, k1 = long_run ? xe - band_px : xe;
  const int stride = std::max(1, (k1 - k0 + 1) / 16);
  for (int k = k0; k <= k1; k += stride) {
    if (disp[k] > 0.0f) values.push_back(disp[k]);
  }
  return median_in_place(values, 0.0f);
}

// One end of a row run: the ROI columns [lo, hi] that may change, and where the run ends now (as a split of them).
struct Side {
  bool left;  // the run's left end
  int lo, hi;
  int e0;  // the split the outline has, counted from lo: the run's first column, or the one after its last
};

// The side of the run [xs, xe] that may move: band_px either way, but not past the run's middle nor past half the gap
// to the previous run (ending at prev_end, -1: none) or the next one (starting at next_start, w: none).
Side side_of(bool left, int xs, int xe, int prev_end, int next_start, int w, int band_px) {
  const int mid = (xs + xe) / 2;
  Side s{left, 0, 0, 0};
  if (left) {
    s.lo = std::max(xs - band_px, prev_end < 0 ? 0 : (prev_end + xs) / 2 + 1);
    s.hi = std::min(xs + band_px, mid);
    s.e0 = xs - s.lo;
  } else {
    s.lo = std::max(xe - band_px, mid + 1);
    s.hi = std::min(xe + band_px, next_start >= w ? w - 1 : (xe + next_start) / 2);
    s.e0 = xe + 1 - s.lo;
  }
  return s;
}

// The background's disparity beside a side: the median of the first background_px disparities outside the outline
// beyond it, searched up to 4 * background_px outward (left of an object's left side lies the strip the object
// hides from the right camera, without disparity); 0 when there are none.
float background_disparity(const float* disp, const uint8_t* outline_row, int w, const Side& s, int background_px,
                           std::vector<float>& values) {
  values.clear();
  for (int k = s.left ? s.lo - 1 : s.hi + 1, steps = 0;
       k >= 0 && k < w && steps < 4 * background_px && static_cast<int>(values.size()) < background_px;
       k += s.left ? -1 : 1, ++steps) {
    if (!outline_row[k] && disp[k] > 0.0f) values.push_back(disp[k]);
  }
  return values.empty() ? 0.0f : median_in_place(values, 0.0f);
}

// The split e in [0, n] with the least cost first[0, e) + second[e, n), ties going to the one nearest e0; gain: the
// cost at e0 less the best one's.
int best_split(const std::vector<float>& first, const std::vector<float>& second, int n, int e0, double& gain) {
  double total = 0.0;
  for (int i = 0; i < n; ++i) total += second[static_cast<std::size_t>(i)];
  double best = total, at_e0 = total;  // split 0 (for e0 = 0 the split as it is)
  int best_e = 0;
  for (int e = 1; e <= n; ++e) {
    total += first[static_cast<std::size_t>(e - 1)] - second[static_cast<std::size_t>(e - 1)];
    if (e == e0) at_e0 = total;
    if (total < best - 1e-6 || (std::fabs(total - best) <= 1e-6 && std::abs(e - e0) < std::abs(best_e - e0))) {
      best = total;
      best_e = e;
    }
  }
  gain = at_e0 - best;
  return best_e;
}

// The matching costs of the side's columns (from image column roi_x + s.lo) at the object's disparity d_f (cost_fg)
// and at the background's d_b (cost_bg, capped at occlusion_cost); false when a column leaves an image.
bool side_costs(const cv::Mat& left, const cv::Mat& right, int roi_x, const Side& s, float d_f, float d_b, int y0,
                int y1, double occlusion_cost, std::vector<float>& cost_fg, std::vector<float>& cost_bg) {
  const int n = s.hi - s.lo + 1;
  cost_fg.resize(static_cast<std::size_t>(n));
  cost_bg.resize(static_cast<std::size_t>(n));
  // Object: left pixel x against right x - d_f. Background beside the right side: left x against right x - d_b.
  // Beside the left side the left camera sees background the right one does not (the object hides it there), so
  // the split is made in the right image, where the side lies at x - d_f: right x - d_f against left x - d_f + d_b.
  const float x0 = static_cast<float>(roi_x + s.lo);
  const bool ok = run_costs(left, right, x0, x0 - d_f, n, y0, y1, cost_fg.data()) &&
                  (s.left ? run_costs(left, right, x0 - d_f + d_b, x0 - d_f, n, y0, y1, cost_bg.data())
                          : run_costs(left, right, x0, x0 - d_b, n, y0, y1, cost_bg.data()));
  if (!ok) return false;
  for (float& cost : cost_bg) cost = std::min(cost, static_cast<float>(occlusion_cost));
  return true;
}

}  // namespace

EdgeRefineStats EdgeRefiner::refine(const cv::Mat& left, const cv::Mat& right, cv::Rect roi,
                                    const cv::Mat& disparity_px, cv::Mat& outline) {
  EdgeRefineStats stats;
  const EdgeRefineConfig& c = config_;
  if (c.band_px <= 0 || outline.empty()) return stats;
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  CV_Assert(outline.type() == CV_8UC1 && disparity_px.type() == CV_32FC1 && outline.size() == disparity_px.size());
  CV_Assert(outline.size() == roi.size() && (roi & cv::Rect(cv::Point(0, 0), left.size())) == roi);
  const int w = outline.cols;
  row_.resize(static_cast<std::size_t>(w));
  for (int y = 0; y < outline.rows; ++y) {
    uint8_t* out = outline.ptr<uint8_t>(y);
    const float* disp = disparity_px.ptr<float>(y);
    std::copy(out, out + w, row_.begin());  // the runs and the background are read from the row as it was
    const int img_y = roi.y + y;
    const int y0 = std::max(0, img_y - c.half_rows), y1 = std::min(left.rows - 1, img_y + c.half_rows);
    int x = 0;
    int prev_end = -1;
    while (x < w) {
      while (x < w && !row_[static_cast<std::size_t>(x)]) ++x;
      if (x >= w) break;
      const int xs = x;
      while (x < w && row_[static_cast<std::size_t>(x)]) ++x;
      const int xe = x - 1;
      int next_start = x;
      while (next_start < w && !row_[static_cast<std::size_t>(next_start)]) ++next_start;
      const float d_f = run_disparity(disp, xs, xe, c.band_px, values_);
      for (int end = 0; end < 2 && d_f > 0.0f; ++end) {
        const Side s = side_of(end == 0, xs, xe, prev_end, next_start, w, c.band_px);
        if (s.lo > s.hi) continue;
        ++stats.sides;
        const float d_b = background_disparity(disp, row_.data(), w, s, c.background_px, values_);
        if (!(d_b > 0.0f) || d_f - d_b < c.min_disparity_gap_px) continue;
        const int n = s.hi - s.lo + 1;
        if (!side_costs(left, right, roi.x, s, d_f, d_b, y0, y1, c.occlusion_cost, cost_fg_, cost_bg_)) continue;
        // Left end: [0, e) background, [e, n) object; right end: the other way round.
        double gain = 0.0;
        const int best_e = best_split(s.left ? cost_bg_ : cost_fg_, s.left ? cost_fg_ : cost_bg_, n, s.e0, gain);
        if (best_e == s.e0 || gain < c.min_gain * std::abs(best_e - s.e0)) continue;
        ++stats.moved;
        for (int i = 0; i < n; ++i) {
          const bool object = s.left ? i >= best_e : i < best_e;
          uint8_t& px = out[s.lo + i];
          if (object && !px) ++stats.pixels_added;
          if (!object && px) ++stats.pixels_removed;
          px = object ? 255 : 0;
        }
      }
      prev_end = xe;
      x = next_start;
    }
  }
  return stats;
}

}  // namespace agvslam::dynamic
