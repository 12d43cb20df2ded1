#include "agvslam/features/stereo_matcher.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "sad_kernels.h"

namespace agvslam::features {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

StereoMatcher::StereoMatcher(const StereoMatcherConfig& config, const StereoCalibration& calibration)
    : config_(config), calibration_(calibration) {
  config_.validate("StereoMatcherConfig");
  if (!(calibration_.bf() > 0)) {
    throw InputError("StereoMatcher", "calibration", "expected fx > 0 and baseline_m > 0");
  }
  min_disparity_px_ = calibration_.bf() / config_.max_depth_m;
  sad_kernel_ = detail::best_sad_kernel(&sad_kernel_name_);
  max_disparity_px_ = calibration_.bf() / config_.min_depth_m;
}

// The right pyramid, resampled exactly like the left one, in buffers with kRightPadding spare bytes after each
// row (the SAD kernels read past the last candidate).
void StereoMatcher::build_right_pyramid(const OrbExtractor& left, const cv::Mat& right) {
  const std::size_t n = left.pyramid().size();
  right_padded_.resize(n);
  right_pyramid_.resize(n);
  right_resizers_.resize(n);
  for (std::size_t level = 0; level < n; ++level) {
    const cv::Size sz = left.pyramid()[level].size();
    cv::Mat& buffer = right_padded_[level];
    buffer.create(sz.height, sz.width + kRightPadding, CV_8UC1);
    cv::Mat roi = buffer(cv::Rect(0, 0, sz.width, sz.height));
    if (level == 0) {
      right.copyTo(roi);
    } else {
      right_resizers_[level].resize(right_pyramid_[level - 1], roi);  // == cv::resize INTER_LINEAR_EXACT
    }
    right_pyramid_[level] = roi;
  }
}

const std::vector<cv::Mat>& StereoMatcher::right_pyramid() const {
  return right_extractor_ ? right_extractor_->pyramid() : right_pyramid_;
}

void StereoMatcher::match(const OrbExtractor& left, const KeypointSet& keypoints, const cv::Mat& right,
                          StereoDepth& out) {
  CV_Assert(right.type() == CV_8UC1 && !left.pyramid().empty() && right.size() == left.pyramid()[0].size());
  const std::size_t n = keypoints.keypoints.size();
  out.u_right_px.assign(n, -1.0f);
  out.depth_m.assign(n, -1.0f);
  out.matched = 0;
  match_costs_.clear();

  Clock::time_point t = Clock::now();
  if (config_.method == StereoMethod::kBlockMatching) {
    build_right_pyramid(left, right);
  } else {
    if (!right_extractor_) right_extractor_.emplace(left.config());
    right_extractor_->extract(right, cv::Mat(), right_keypoints_);
  }
  t_right_ms_ = ms_since(t);

  t = Clock::now();
  if (config_.method == StereoMethod::kBlockMatching) {
    match_blocks(left, keypoints, out);
  } else {
    match_descriptors(left, keypoints, out);
  }
  reject_outliers(out);
  t_match_ms_ = ms_since(t);
}

// Accepts a sub-pixel disparity (level-0 px) for keypoint i when it lies in [min, max) of the depth range.
// Returns false for disparities outside (too near, or too far to get a depth).
namespace {
bool accept(float u_left_px, float disparity_px, double min_disparity_px, double max_disparity_px, double bf,
            float& u_right_px, float& depth_m) {
  if (!(disparity_px >= min_disparity_px && disparity_px < max_disparity_px)) return false;
  if (disparity_px <= 0) disparity_px = 0.01f;  // ORB-SLAM2: only reachable when max_depth is infinite
  u_right_px = u_left_px - disparity_px;
  depth_m = static_cast<float>(bf / disparity_px);
  return true;
}
}  // namespace

void StereoMatcher::match_blocks(const OrbExtractor& left, const KeypointSet& keypoints, StereoDepth& out) {
  const std::vector<cv::Mat>& left_pyramid = left.pyramid();
  const int h = config_.sad_half_window;
  const int rows = 2 * h + 1;
  const int blocks = (2 * h + 1 + 3) / 4;
  const int cols = 4 * blocks;
  const double bf = calibration_.bf();
  const uint8_t* left_rows[16];
  const uint8_t* right_rows[16];
  for (std::size_t i = 0; i < keypoints.keypoints.size(); ++i) {
    const cv::KeyPoint& kp = keypoints.keypoints[i];
    const int level = kp.octave;
    const float s = left.scale_factors()[static_cast<std::size_t>(level)];
    const float inv = left.inv_scale_factors()[static_cast<std::size_t>(level)];
    const cv::Mat& li = left_pyramid[static_cast<std::size_t>(level)];
    const cv::Mat& ri = right_pyramid_[static_cast<std::size_t>(level)];
    const int xl = cvRound(kp.pt.x * inv), yl = cvRound(kp.pt.y * inv);
    // The kernels read 16 bytes of each left window row.
    if (yl - h < 0 || yl + h >= li.rows || xl - h < 0 || xl - h + 16 > li.cols) continue;
    // Candidate disparities at this level: from -1 (so that points beyond max_depth find their true minimum, near
    // 0, instead of a false one inside the range; they are refused below) to one beyond the largest disparity.
    // Candidate k is the right window starting at column xr_lo + k (disparity xl - h - xr_lo - k), all inside
    // the image.
    const int d_hi = static_cast<int>(std::ceil(max_disparity_px_ * inv)) + 1;
    const int x0 = xl - h;
    const int xr_lo = std::max(0, x0 - d_hi);
    const int xr_hi = std::min(ri.cols - cols, x0 + 1);
    const int n = xr_hi - xr_lo + 1;
    if (n < 3) continue;
    const int y0 = yl - h;
    for (int r = 0; r < rows; ++r) {
      left_rows[r] = li.ptr<uint8_t>(y0 + r) + x0;
      right_rows[r] = ri.ptr<uint8_t>(y0 + r) + xr_lo;
    }
    const std::size_t padded = static_cast<std::size_t>((n + 15) / 16 * 16);
    if (costs_.size() < padded) costs_.resize(padded);
    uint16_t* c = costs_.data();
    sad_kernel_(left_rows, right_rows, rows, blocks, n, c);
    int best = 0;
    for (int k = 1; k < n; ++k) {
      if (c[k] < c[best]) best = k;
    }
    if (best == 0 || best == n - 1) continue;  // minimum at the end of the range or of the image
    uint16_t second = UINT16_MAX;
    for (int k = 0; k < best - 1; ++k) second = std::min(second, c[k]);
    for (int k = best + 2; k < n; ++k) second = std::min(second, c[k]);
    const int32_t c0 = c[best];
    if (static_cast<double>(c0) > config_.uniqueness_ratio * static_cast<double>(second)) continue;
    // Parabola through the costs around the minimum (in right-image columns).
    const double c_minus = c[best - 1];
    const double c_plus = c[best + 1];
    const double denom = c_minus + c_plus - 2.0 * c0;
    // Texture along the row: how much the SAD rises one pixel off the minimum, per window pixel (grey levels).
    // Windows of sensor noise on a blank surface rise little and match anywhere.
    if (0.5 * denom < config_.min_curvature * rows * cols) continue;
    const double delta = denom > 0 ? (c_minus - c_plus) / (2.0 * denom) : 0.0;
    const double xr_window = xr_lo + best + delta;
    const float disparity = kp.pt.x - s * static_cast<float>(xr_window + h);
    float u_right = -1, depth = -1;
    if (!accept(kp.pt.x, disparity, min_disparity_px_, max_disparity_px_, bf, u_right, depth)) continue;
    out.u_right_px[i] = u_right;
    out.depth_m[i] = depth;
    match_costs_.emplace_back(c0, static_cast<int>(i));
  }
}

// ORB-SLAM2's Frame::ComputeStereoMatches.
void StereoMatcher::match_descriptors(const OrbExtractor& left, const KeypointSet& keypoints, StereoDepth& out) {
  const std::vector<cv::Mat>& left_pyramid = left.pyramid();
  const std::vector<cv::Mat>& right_levels = right_extractor_->pyramid();
  const std::vector<cv::KeyPoint>& right_kps = right_keypoints_.keypoints;
  const int n_rows = left_pyramid[0].rows;
  const double bf = calibration_.bf();

  // Right keypoints per row, over a band of +-2 scale rows.
  row_index_.resize(static_cast<std::size_t>(n_rows));
  for (auto& row : row_index_) row.clear();
  for (std::size_t r = 0; r < right_kps.size(); ++r) {
    const cv::KeyPoint& kp = right_kps[r];
    const float band = 2.0f * left.scale_factors()[static_cast<std::size_t>(kp.octave)];
    const int max_r = std::min(n_rows - 1, static_cast<int>(std::ceil(kp.pt.y + band)));
    const int min_r = std::max(0, static_cast<int>(std::floor(kp.pt.y - band)));
    for (int y = min_r; y <= max_r; ++y) row_index_[static_cast<std::size_t>(y)].push_back(static_cast<int>(r));
  }

  const int w = config_.sad_half_window;
  const int search = config_.sad_search_px;
  const int th_high = 100;  // ORB-SLAM2's TH_HIGH: the first candidate must beat it
  for (std::size_t i = 0; i < keypoints.keypoints.size(); ++i) {
    const cv::KeyPoint& kpl = keypoints.keypoints[i];
    const int level = kpl.octave;
    const float u_l = kpl.pt.x;
    const int v_l = static_cast<int>(kpl.pt.y);
    if (v_l < 0 || v_l >= n_rows) continue;
    const std::vector<int>& candidates = row_index_[static_cast<std::size_t>(v_l)];
    if (candidates.empty()) continue;
    const double min_u = u_l - max_disparity_px_;
    const double max_u = u_l - min_disparity_px_;
    if (max_u < 0) continue;
    int best_dist = th_high;
    int best_r = -1;
    const uint8_t* dl = keypoints.descriptors.ptr<uint8_t>(static_cast<int>(i));
    for (int r : candidates) {
      const cv::KeyPoint& kpr = right_kps[static_cast<std::size_t>(r)];
      if (kpr.octave < level - 1 || kpr.octave > level + 1) continue;
      if (kpr.pt.x >= min_u && kpr.pt.x <= max_u) {
        const int dist = descriptor_distance(dl, right_keypoints_.descriptors.ptr<uint8_t>(r));
        if (dist < best_dist) {
          best_dist = dist;
          best_r = r;
        }
      }
    }
    if (best_r < 0 || best_dist >= config_.max_descriptor_distance) continue;

    // SAD refinement at the left keypoint's level, windows minus their centre pixel (brightness offset).
    const float s = left.scale_factors()[static_cast<std::size_t>(level)];
    const float inv = left.inv_scale_factors()[static_cast<std::size_t>(level)];
    const int su_l = cvRound(u_l * inv), sv_l = cvRound(kpl.pt.y * inv);
    const int su_r0 = cvRound(right_kps[static_cast<std::size_t>(best_r)].pt.x * inv);
    const cv::Mat& li = left_pyramid[static_cast<std::size_t>(level)];
    const cv::Mat& ri = right_levels[static_cast<std::size_t>(level)];
    if (sv_l - w < 0 || sv_l + w >= li.rows || su_l - w < 0 || su_l + w >= li.cols) continue;
    if (su_r0 - search - w < 0 || su_r0 + search + w >= ri.cols) continue;
    const int center_l = li.at<uint8_t>(sv_l, su_l);
    int best_sad = INT_MAX, best_inc = 0;
    descriptor_costs_.assign(static_cast<std::size_t>(2 * search + 1), 0);
    for (int inc = -search; inc <= search; ++inc) {
      const int xr = su_r0 + inc;
      const int center_r = ri.at<uint8_t>(sv_l, xr);
      int sad = 0;
      for (int dy = -w; dy <= w; ++dy) {
        const uint8_t* pl = li.ptr<uint8_t>(sv_l + dy) + su_l - w;
        const uint8_t* pr = ri.ptr<uint8_t>(sv_l + dy) + xr - w;
        for (int dx = 0; dx <= 2 * w; ++dx) sad += std::abs((pl[dx] - center_l) - (pr[dx] - center_r));
      }
      if (sad < best_sad) {
        best_sad = sad;
        best_inc = inc;
      }
      descriptor_costs_[static_cast<std::size_t>(search + inc)] = sad;
    }
    if (best_inc == -search || best_inc == search) continue;
    const float dist1 = static_cast<float>(descriptor_costs_[static_cast<std::size_t>(search + best_inc - 1)]);
    const float dist2 = static_cast<float>(descriptor_costs_[static_cast<std::size_t>(search + best_inc)]);
    const float dist3 = static_cast<float>(descriptor_costs_[static_cast<std::size_t>(search + best_inc + 1)]);
    const float delta_r = (dist1 - dist3) / (2.0f * (dist1 + dist3 - 2.0f * dist2));
    if (delta_r < -1 || delta_r > 1) continue;
    const float best_u_r = s * (static_cast<float>(su_r0 + best_inc) + delta_r);
    float u_right = -1, depth = -1;
    if (!accept(u_l, u_l - best_u_r, min_disparity_px_, max_disparity_px_, bf, u_right, depth)) continue;
    out.u_right_px[i] = u_right;
    out.depth_m[i] = depth;
    match_costs_.emplace_back(best_sad, static_cast<int>(i));
  }
}

// Matches whose SAD exceeds outlier_factor x the median SAD (ORB-SLAM2: 1.5 x 1.4 x median) lose their depth.
void StereoMatcher::reject_outliers(StereoDepth& out) {
  out.matched = static_cast<int>(match_costs_.size());
  if (match_costs_.empty()) return;
  auto mid = match_costs_.begin() + static_cast<std::ptrdiff_t>(match_costs_.size() / 2);
  std::nth_element(match_costs_.begin(), mid, match_costs_.end());
  const double threshold = config_.outlier_factor * static_cast<double>(mid->first);
  for (const auto& [cost, index] : match_costs_) {
    if (static_cast<double>(cost) > threshold) {
      out.u_right_px[static_cast<std::size_t>(index)] = -1.0f;
      out.depth_m[static_cast<std::size_t>(index)] = -1.0f;
      --out.matched;
    }
  }
}

}  // namespace agvslam::features
