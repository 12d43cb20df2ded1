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

}  // namespace

EdgeRefineStats EdgeRefiner::refine(const cv::Mat& left, const cv::Mat& right, cv::Rect roi, const cv::Mat& disparity_px,
                                    cv::Mat& outline) {
  EdgeRefineStats stats;
  const EdgeRefineConfig& c = config_;
  if (c.band_px <= 0 || outline.empty()) return stats;
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  CV_Assert(outline.type() == CV_8UC1 && disparity_px.type() == CV_32FC1 && outline.size() == disparity_px.size());
  CV_Assert(outline.size() == roi.size() && (roi & cv::Rect(cv::Point(0, 0), left.size())) == roi);
  const int w = outline.cols;
  const int band = c.band_px;
  row_.resize(static_cast<std::size_t>(w));
  for (int y = 0; y < outline.rows; ++y) {
    uint8_t* out = outline.ptr<uint8_t>(y);
    const float* disp = disparity_px.ptr<float>(y);
    std::copy(out, out + w, row_.begin());
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
      // The object's disparity: the run away from its ends (where SGBM fattened it), else the whole run.
      values_.clear();
      const bool long_run = xe - xs + 1 > 2 * band + 2;
      const int k0 = long_run ? xs + band : xs, k1 = long_run ? xe - band : xe;
      const int stride = std::max(1, (k1 - k0 + 1) / 16);  // at most ~16 samples
      for (int k = k0; k <= k1; k += stride) {
        if (disp[k] > 0.0f) values_.push_back(disp[k]);
      }
      const float d_f = median_in_place(values_, 0.0f);
      const int mid = (xs + xe) / 2;
      for (int side = 0; side < 2 && d_f > 0.0f; ++side) {
        const bool left_side = side == 0;
        int lo, hi;
        if (left_side) {
          lo = std::max(xs - band, prev_end < 0 ? 0 : (prev_end + xs) / 2 + 1);  // gaps between runs: halved
          hi = std::min(xs + band, mid);
        } else {
          lo = std::max(xe - band, mid + 1);
          hi = std::min(xe + band, next_start >= w ? w - 1 : (xe + next_start) / 2);
        }
        if (lo > hi) continue;
        ++stats.sides;
        // The background's disparity: beside the band, outside the outline.
        values_.clear();
        // (Left of an object's left side lies the strip the object hides from the right camera, without
        // disparity: the search goes on outward, up to 4 * background_px.)
        for (int k = left_side ? lo - 1 : hi + 1, steps = 0;
             k >= 0 && k < w && steps < 4 * c.background_px && static_cast<int>(values_.size()) < c.background_px;
             k += left_side ? -1 : 1, ++steps) {
          if (!row_[static_cast<std::size_t>(k)] && disp[k] > 0.0f) values_.push_back(disp[k]);
        }
        if (values_.empty()) continue;
        const float d_b = median_in_place(values_, 0.0f);
        if (d_f - d_b < c.min_disparity_gap_px) continue;
        const int n = hi - lo + 1;
        cost_fg_.resize(static_cast<std::size_t>(n));
        cost_bg_.resize(static_cast<std::size_t>(n));
        // Object: left pixel x against right x - d_f. Background beside the right side: left x against right
        // x - d_b. Beside the left side the left camera sees background the right one does not (the object hides
        // it there), so the split is made in the right image, where the side lies at x - d_f: right x - d_f
        // against left x - d_f + d_b.
        const float x0 = static_cast<float>(roi.x + lo);
        bool ok = run_costs(left, right, x0, x0 - d_f, n, y0, y1, cost_fg_.data()) &&
                  (left_side ? run_costs(left, right, x0 - d_f + d_b, x0 - d_f, n, y0, y1, cost_bg_.data())
                             : run_costs(left, right, x0, x0 - d_b, n, y0, y1, cost_bg_.data()));
        for (int i = 0; i < n && ok; ++i) {
          cost_bg_[static_cast<std::size_t>(i)] = std::min(cost_bg_[static_cast<std::size_t>(i)], static_cast<float>(c.occlusion_cost));
        }
        if (!ok) continue;
        // Split e in [0, n]: left side: [0, e) background, [e, n) object; right side: the other way round.
        const std::vector<float>& first = left_side ? cost_bg_ : cost_fg_;
        const std::vector<float>& second = left_side ? cost_fg_ : cost_bg_;
        double total = 0.0;
        for (int i = 0; i < n; ++i) total += second[static_cast<std::size_t>(i)];
        const int e0 = (left_side ? xs : xe + 1) - lo;  // the split as it is
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
        if (best_e == e0 || at_e0 - best < c.min_gain * std::abs(best_e - e0)) continue;
        ++stats.moved;
        for (int i = 0; i < n; ++i) {
          const bool object = left_side ? i >= best_e : i < best_e;
          uint8_t& px = out[lo + i];
          const bool was = px != 0;
          if (object && !was) ++stats.pixels_added;
          if (!object && was) ++stats.pixels_removed;
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
