#include "agvslam/features/orb_extractor.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "fast_kernels.h"
#include "orb_kernels.h"

namespace agvslam::features {

namespace {

using Clock = std::chrono::steady_clock;

// FAST searches start this far inside a level (ORB-SLAM2: EDGE_THRESHOLD - 3); FAST itself needs 3 more pixels.
constexpr int kFastBorder = kOrbEdgeThreshold - 3;

// The scale of `level` exactly as OpenCV's ORB computes it (cv::ORB stores its float scale factor as a double).
float layer_scale(double scale_factor, int level) {
  return static_cast<float>(
      std::pow(static_cast<double>(static_cast<float>(scale_factor)), static_cast<double>(level)));
}

// Rows of `m` for a CV_8UC1 N x cols matrix, reusing its allocation when nobody else holds it (no allocation per
// frame once the capacity is there). capacity_rows: rows to allocate when a new buffer is needed.
void prepare_rows(cv::Mat& m, int rows, int cols, int capacity_rows) {
  const bool reusable = m.u != nullptr && m.u->refcount == 1 && m.type() == CV_8UC1 && m.cols == cols &&
                        m.data == m.datastart && m.isContinuous() &&
                        m.datastart + static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) <= m.datalimit;
  if (!reusable) {
    m.release();
    m.create(std::max(rows, capacity_rows), cols, CV_8UC1);
  }
  if (m.rows != rows) m.resize(static_cast<std::size_t>(rows));
}

}  // namespace

std::vector<int> OrbExtractorConfig::features_per_level() const {
  // ORB-SLAM2's geometric series: level l wants n * (1 - f) / (1 - f^L) * f^l, the last level the remainder.
  const double side = 1.0 / scale_factor;
  const float factor = static_cast<float>(level_allocation == LevelAllocation::kArea ? side * side : side);
  std::vector<int> out(static_cast<std::size_t>(std::max(n_levels, 1)), 0);
  float desired = static_cast<float>(n_features) * (1.0f - factor) /
                  (1.0f - static_cast<float>(std::pow(static_cast<double>(factor), static_cast<double>(n_levels))));
  int sum = 0;
  for (int level = 0; level + 1 < n_levels; ++level) {
    out[static_cast<std::size_t>(level)] = cvRound(desired);
    sum += out[static_cast<std::size_t>(level)];
    desired *= factor;
  }
  out.back() = std::max(n_features - sum, 0);
  return out;
}

OrbExtractor::OrbExtractor(const OrbExtractorConfig& config) : config_(config) {
  config_.validate("OrbExtractorConfig");
  const int n = config_.n_levels;
  scale_factors_.resize(static_cast<std::size_t>(n));
  inv_scale_factors_.resize(static_cast<std::size_t>(n));
  level_sigma2_.resize(static_cast<std::size_t>(n));
  inv_level_sigma2_.resize(static_cast<std::size_t>(n));
  for (int level = 0; level < n; ++level) {
    const float s = layer_scale(config_.scale_factor, level);
    scale_factors_[static_cast<std::size_t>(level)] = s;
    inv_scale_factors_[static_cast<std::size_t>(level)] = 1.0f / s;
    level_sigma2_[static_cast<std::size_t>(level)] = s * s;
    inv_level_sigma2_[static_cast<std::size_t>(level)] = 1.0f / (s * s);
  }
  features_per_level_ = config_.features_per_level();

  // Half-width of each row of the orientation disc (OpenCV's ORB / ORB-SLAM2: rounded circle, made symmetric).
  umax_.assign(kOrbHalfPatchSize + 2, 0);
  const int vmax = cvFloor(kOrbHalfPatchSize * std::sqrt(2.f) / 2 + 1);
  const int vmin = cvCeil(kOrbHalfPatchSize * std::sqrt(2.f) / 2);
  const double hp2 = kOrbHalfPatchSize * kOrbHalfPatchSize;
  for (int v = 0; v <= vmax; ++v) umax_[static_cast<std::size_t>(v)] = cvRound(std::sqrt(hp2 - v * v));
  for (int v = kOrbHalfPatchSize, v0 = 0; v >= vmin; --v) {
    while (umax_[static_cast<std::size_t>(v0)] == umax_[static_cast<std::size_t>(v0) + 1]) ++v0;
    umax_[static_cast<std::size_t>(v)] = v0;
    ++v0;
  }
  pyramid_.resize(static_cast<std::size_t>(n));
  bordered_.resize(static_cast<std::size_t>(n));
  resizers_.resize(static_cast<std::size_t>(n));
  blurred_.resize(static_cast<std::size_t>(n));
  level_nodes_.resize(static_cast<std::size_t>(n));
  stats_.keypoints_per_level.assign(static_cast<std::size_t>(n), 0);
}

cv::Size OrbExtractor::level_size(cv::Size image_size, int level) const {
  const float s = scale_factors_.at(static_cast<std::size_t>(level));
  return {cvRound(static_cast<float>(image_size.width) / s), cvRound(static_cast<float>(image_size.height) / s)};
}

void OrbExtractor::build_pyramid(const cv::Mat& image, std::vector<cv::Mat>& levels) const {
  CV_Assert(image.type() == CV_8UC1 && !image.empty());
  levels.resize(static_cast<std::size_t>(config_.n_levels));
  image.copyTo(levels[0]);
  for (int level = 1; level < config_.n_levels; ++level) {
    // Cascaded like OpenCV's ORB: each level from the previous one, bit-exact bilinear.
    cv::resize(levels[static_cast<std::size_t>(level) - 1], levels[static_cast<std::size_t>(level)],
               level_size(image.size(), level), 0, 0, cv::INTER_LINEAR_EXACT);
  }
}

// The left pyramid lives inside buffers with a kBlurBorder-pixel reflected border, like OpenCV's ORB pyramid:
// cv::GaussianBlur of a submatrix reads the real neighbours (here the reflected border) and takes OpenCV's
// separable-filter path, which rounds differently from its whole-image bit-exact path. Blurring the same way is
// what makes the descriptors equal to cv::ORB::compute's.
void OrbExtractor::build_bordered_pyramid(const cv::Mat& image) {
  const int b = kBlurBorder;
  for (int level = 0; level < config_.n_levels; ++level) {
    const cv::Size sz = level == 0 ? image.size() : level_size(image.size(), level);
    cv::Mat& ext = bordered_[static_cast<std::size_t>(level)];
    ext.create(sz.height + 2 * b, sz.width + 2 * b, CV_8UC1);
    cv::Mat roi = ext(cv::Rect(b, b, sz.width, sz.height));
    if (level == 0) {
      image.copyTo(roi);
    } else {
      resizers_[static_cast<std::size_t>(level)].resize(pyramid_[static_cast<std::size_t>(level) - 1],
                                                        roi);  // == cv::resize INTER_LINEAR_EXACT
    }
    cv::copyMakeBorder(roi, ext, b, b, b, b, cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
    pyramid_[static_cast<std::size_t>(level)] = roi;
  }
}

void OrbExtractor::prepare_mask(const cv::Mat& dynamic_mask, cv::Size image_size) {
  mask_active_ = false;
  if (dynamic_mask.empty()) return;
  CV_Assert(dynamic_mask.type() == CV_8UC1 && dynamic_mask.size() == image_size);
  if (cv::countNonZero(dynamic_mask) == 0) return;
  // Integral image of the mask (255 per dynamic pixel): a keypoint is refused when the square of half-side
  // dilation * scale around it holds any dynamic pixel (the square contains the disc of that radius).
  cv::threshold(dynamic_mask, mask_binary_, 0, 255, cv::THRESH_BINARY);  // any non-zero value is dynamic
  cv::integral(mask_binary_, mask_integral_, CV_32S);
  mask_active_ = true;
}

bool OrbExtractor::masked(float x0_px, float y0_px, int level) const {
  if (!mask_active_) return false;
  const float r = static_cast<float>(config_.mask_dilation_px) * scale_factors_[static_cast<std::size_t>(level)];
  const int cols = mask_integral_.cols - 1, rows = mask_integral_.rows - 1;
  const int xa = std::max(0, static_cast<int>(std::floor(x0_px - r)));
  const int ya = std::max(0, static_cast<int>(std::floor(y0_px - r)));
  const int xb = std::min(cols, static_cast<int>(std::ceil(x0_px + r)) + 1);  // exclusive
  const int yb = std::min(rows, static_cast<int>(std::ceil(y0_px + r)) + 1);
  if (xa >= xb || ya >= yb) return false;
  const int32_t* top = mask_integral_.ptr<int32_t>(ya);
  const int32_t* bottom = mask_integral_.ptr<int32_t>(yb);
  return bottom[xb] - bottom[xa] - top[xb] + top[xa] != 0;
}

// FAST corners of one level, outside the dilated mask, with ORB-SLAM2's per-cell retry at the lower threshold.
// ORB-SLAM2 runs cv::FAST (with non-maximum suppression) at ini_fast_threshold in cells of cell_size_px and again
// at min_fast_threshold in the cells that got nothing. Here the FAST strength of every pixel is computed once
// (fast_kernels.h) and both passes read it: the local maxima of the strength above min_fast_threshold are the
// corners of the low pass, those above ini_fast_threshold the corners of the first pass (non-maximum
// suppression at either threshold is the same test on the strength). A cell keeps its first-pass corners, or,
// when it has none, its low-pass corners. Responses are OpenCV's FAST scores.
void OrbExtractor::detect_level(int level) {
  candidates_.clear();
  const cv::Mat& img = pyramid_[static_cast<std::size_t>(level)];
  const float s = scale_factors_[static_cast<std::size_t>(level)];
  const int min_b = kFastBorder;
  const int max_bx = img.cols - kFastBorder;
  const int max_by = img.rows - kFastBorder;
  const int width = max_bx - min_b, height = max_by - min_b;
  if (width < 9 || height < 9) return;
  const int w = config_.cell_size_px;
  const int n_cols = std::max(1, width / w), n_rows = std::max(1, height / w);
  const int w_cell = (width + n_cols - 1) / n_cols;
  const int h_cell = (height + n_rows - 1) / n_rows;
  cell_counts_.assign(static_cast<std::size_t>(n_cols) * static_cast<std::size_t>(n_rows), 0);

  // Strength where corners may lie ([min_b + 3, max_b - 3), as cv::FAST on ORB-SLAM2's area) and one pixel
  // around them (their neighbours in the suppression).
  // One buffer for all levels (sized by the largest), viewed at this level's size: no reallocation per level.
  const std::size_t needed = img.total();
  if (strength_buffer_.size() < needed) strength_buffer_.resize(needed);
  strength_ = cv::Mat(img.rows, img.cols, CV_8UC1, strength_buffer_.data());
  const int sx0 = min_b + 2, sx1 = max_bx - 2, sy0 = min_b + 2, sy1 = max_by - 2;
  for (int y = sy0; y < sy1; ++y) {
    detail::fast_strength_row(img.ptr<uint8_t>(y) + sx0, static_cast<int>(img.step), sx1 - sx0,
                              strength_.ptr<uint8_t>(y) + sx0);
  }
  const int low = config_.min_fast_threshold, high = config_.ini_fast_threshold;
  const int step = static_cast<int>(strength_.step);
  maxima_.resize(static_cast<std::size_t>(img.cols));
  for (int y = min_b + 3; y < max_by - 3; ++y) {
    const uint8_t* row = strength_.ptr<uint8_t>(y);
    const int found = detail::local_maxima_row(row, step, min_b + 3, max_bx - 3, low, maxima_.data());
    for (int i = 0; i < found; ++i) {
      const int x = maxima_[static_cast<std::size_t>(i)];
      if (masked(static_cast<float>(x) * s, static_cast<float>(y) * s, level)) {
        ++stats_.masked_candidates;
        continue;
      }
      const int strength = row[x];
      const int cx = std::clamp((x - min_b - 3) / w_cell, 0, n_cols - 1);
      const int cy = std::clamp((y - min_b - 3) / h_cell, 0, n_rows - 1);
      const int cell = cy * n_cols + cx;
      if (strength > high) ++cell_counts_[static_cast<std::size_t>(cell)];
      candidates_.push_back({static_cast<int16_t>(x), static_cast<int16_t>(y), static_cast<int16_t>(strength - 1),
                             static_cast<int16_t>(cell)});
    }
  }
  // Cells with first-pass corners keep only those; the others keep their low-threshold corners.
  std::size_t kept = 0;
  for (const Candidate& c : candidates_) {
    if (c.score + 1 > high || cell_counts_[static_cast<std::size_t>(c.cell)] == 0) candidates_[kept++] = c;
  }
  candidates_.resize(kept);
  for (int count : cell_counts_) stats_.retry_cells += count == 0;
}

// Intensity-centroid angle (degrees) of each keypoint of one level: OpenCV's / ORB-SLAM2's IC_Angle on the
// level image (not blurred), over the disc of radius 15.
// keypoints[first + k] is candidates_[kept_[k]].
void OrbExtractor::compute_orientation(int level, std::size_t first, std::vector<cv::KeyPoint>& keypoints) const {
  const cv::Mat& img = pyramid_[static_cast<std::size_t>(level)];
  const int step = static_cast<int>(img.step1());
  for (std::size_t k = 0; k < kept_.size(); ++k) {
    const Candidate& c = candidates_[static_cast<std::size_t>(kept_[k])];
    const uint8_t* center = img.ptr<uint8_t>(c.y) + c.x;
    int m_01 = 0, m_10 = 0;
    detail::ic_moments(center, step, umax_.data(), m_01, m_10);
    keypoints[first + k].angle = cv::fastAtan2(static_cast<float>(m_01), static_cast<float>(m_10));
  }
}

void compute_orb_descriptors(const std::vector<cv::Mat>& blurred_pyramid, const std::vector<float>& scale_factors,
                             const std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  CV_Assert(descriptors.type() == CV_8UC1 && descriptors.cols == kOrbDescriptorBytes &&
            descriptors.rows == static_cast<int>(keypoints.size()));
  const float deg_to_rad = static_cast<float>(CV_PI / 180.f);
  for (std::size_t j = 0; j < keypoints.size(); ++j) {
    const cv::KeyPoint& kpt = keypoints[j];
    const cv::Mat& img = blurred_pyramid[static_cast<std::size_t>(kpt.octave)];
    const float scale = 1.f / scale_factors[static_cast<std::size_t>(kpt.octave)];
    // OpenCV's ORB: the angle in float radians, cos and sin in double, then float.
    const float angle = kpt.angle * deg_to_rad;
    const float a = static_cast<float>(std::cos(static_cast<double>(angle)));
    const float b = static_cast<float>(std::sin(static_cast<double>(angle)));
    const uint8_t* center = img.ptr<uint8_t>(cvRound(kpt.pt.y * scale)) + cvRound(kpt.pt.x * scale);
    detail::orb_descriptor(center, static_cast<int>(img.step), a, b, descriptors.ptr<uint8_t>(static_cast<int>(j)));
  }
}

void OrbExtractor::compute_descriptors(const std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) const {
  compute_orb_descriptors(blurred_, scale_factors_, keypoints, descriptors);
}

void OrbExtractor::extract(const cv::Mat& image, const cv::Mat& dynamic_mask, KeypointSet& out) {
  CV_Assert(image.type() == CV_8UC1 && !image.empty());
  stats_.candidates = 0;
  stats_.masked_candidates = 0;
  stats_.retry_cells = 0;
  stats_.t_fast_ms = stats_.t_distribute_ms = stats_.t_orientation_ms = 0;

  Clock::time_point t = Clock::now();
  build_bordered_pyramid(image);
  stats_.t_pyramid_ms = ms_since(t);

  t = Clock::now();
  prepare_mask(dynamic_mask, image.size());
  stats_.t_mask_ms = ms_since(t);

  std::vector<cv::KeyPoint>& keypoints = out.keypoints;
  keypoints.clear();
  keypoints.reserve(static_cast<std::size_t>(config_.n_features));
  for (int level = 0; level < config_.n_levels; ++level) {
    t = Clock::now();
    detect_level(level);
    stats_.candidates += static_cast<int>(candidates_.size());
    stats_.t_fast_ms += ms_since(t);

    t = Clock::now();
    quadtree_input_.resize(candidates_.size());
    for (std::size_t i = 0; i < candidates_.size(); ++i) {
      quadtree_input_[i] = {static_cast<float>(candidates_[i].x - kFastBorder),
                            static_cast<float>(candidates_[i].y - kFastBorder),
                            static_cast<float>(candidates_[i].score)};
    }
    const cv::Mat& img = pyramid_[static_cast<std::size_t>(level)];
    distributor_.set_collect_nodes(collect_nodes_);
    distributor_.distribute(quadtree_input_, img.cols - 2 * kFastBorder, img.rows - 2 * kFastBorder,
                            features_per_level_[static_cast<std::size_t>(level)], kept_);
    std::vector<cv::Rect>& nodes = level_nodes_[static_cast<std::size_t>(level)];
    nodes.clear();
    if (collect_nodes_) {
      for (cv::Rect r : distributor_.nodes()) nodes.push_back(r + cv::Point(kFastBorder, kFastBorder));
    }
    const float s = scale_factors_[static_cast<std::size_t>(level)];
    const std::size_t first = keypoints.size();
    for (int i : kept_) {
      const Candidate& c = candidates_[static_cast<std::size_t>(i)];
      keypoints.emplace_back(static_cast<float>(c.x) * s, static_cast<float>(c.y) * s,
                             static_cast<float>(kOrbPatchSize) * s, -1.0f, static_cast<float>(c.score), level);
    }
    stats_.keypoints_per_level[static_cast<std::size_t>(level)] = static_cast<int>(keypoints.size() - first);
    stats_.t_distribute_ms += ms_since(t);

    t = Clock::now();
    compute_orientation(level, first, keypoints);
    stats_.t_orientation_ms += ms_since(t);
  }

  t = Clock::now();
  for (int level = 0; level < config_.n_levels; ++level) {
    if (stats_.keypoints_per_level[static_cast<std::size_t>(level)] == 0) continue;
    const cv::Mat& src = pyramid_[static_cast<std::size_t>(level)];
    cv::Mat& dst = blurred_[static_cast<std::size_t>(level)];
    dst.create(src.size(), CV_8UC1);
    if (!blur_.blur(src, dst)) cv::GaussianBlur(src, dst, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  }
  stats_.t_blur_ms = ms_since(t);

  t = Clock::now();
  prepare_rows(out.descriptors, static_cast<int>(keypoints.size()), kOrbDescriptorBytes, config_.n_features);
  compute_descriptors(keypoints, out.descriptors);
  stats_.t_descriptor_ms = ms_since(t);
}

int descriptor_distance(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int k = 0; k < 4; ++k) {
    uint64_t x, y;
    std::memcpy(&x, a + 8 * k, 8);
    std::memcpy(&y, b + 8 * k, 8);
    d += __builtin_popcountll(x ^ y);
  }
  return d;
}

}  // namespace agvslam::features
