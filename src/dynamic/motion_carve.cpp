#include "agvslam/dynamic/motion_carve.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/bilinear.h"
#include "agvslam/dynamic/static_warp.h"

namespace agvslam::dynamic {

namespace {

constexpr double kMinDepthM = 0.1;  // a warped point nearer than this to the earlier camera is not sampled

// Mean absolute deviation of the differences from their mean.
double spread(const double* diff, int n) {
  double mean = 0;
  for (int i = 0; i < n; ++i) mean += diff[i];
  mean /= n;
  double s = 0;
  for (int i = 0; i < n; ++i) s += std::abs(diff[i] - mean);
  return s / n;
}

// One block's samples: the current grey value, its difference to the previous image under the static hypothesis,
// and its position in the previous image moved back by the object's motion.
struct BlockSamples {
  explicit BlockSamples(std::size_t capacity)
      : value(capacity), d_static(capacity), d_object(capacity), object_px(capacity) {}
  std::vector<double> value, d_static, d_object;
  std::vector<cv::Point> object_px;
  int n = 0;
};

// Samples the outline (at `origin` in the images) in `block`, every sample_step_px: its pixels with a disparity and a
// gradient >= min_gradient whose every shift of the object's motion (+- search_px) stays inside the previous image
// and whose static warp lands inside it.
void sample_block(const cv::Mat& cur_left, const cv::Mat& prev_left, const StaticWarp& warp, const cv::Mat& outline,
                  const cv::Mat& disparity_px, cv::Point origin, const cv::Rect& block, cv::Point object_motion_px,
                  const MotionCarveConfig& config, BlockSamples& samples) {
  const int w = cur_left.cols, h = cur_left.rows;
  const int step = config.sample_step_px, r = config.search_px;
  samples.n = 0;
  for (int ly = block.y; ly < block.br().y; ly += step) {
    const int y = ly + origin.y;
    if (y < 1 || y >= h - 1) continue;
    const uint8_t* m_row = outline.ptr<uint8_t>(ly);
    const float* d_row = disparity_px.ptr<float>(ly);
    const uint8_t* c0 = cur_left.ptr<uint8_t>(y);
    const uint8_t* cm = cur_left.ptr<uint8_t>(y - 1);
    const uint8_t* cp = cur_left.ptr<uint8_t>(y + 1);
    for (int lx = block.x; lx < block.br().x; lx += step) {
      if (!m_row[lx]) continue;
      const double d = d_row[lx];
      if (!(d > 0.5)) continue;
      const int x = lx + origin.x;
      if (x < 1 || x >= w - 1) continue;
      const double gx = 0.5 * (c0[x + 1] - c0[x - 1]), gy = 0.5 * (cp[x] - cm[x]);
      if (std::sqrt(gx * gx + gy * gy) < config.min_gradient) continue;
      const int ox = x - object_motion_px.x, oy = y - object_motion_px.y;
      if (ox - r < 0 || oy - r < 0 || ox + r >= w || oy + r >= h) continue;
      double u, v;
      if (!warp.at(x, y, d, u, v, kMinDepthM)) continue;
      if (!(u >= 0 && v >= 0 && u < w - 1 && v < h - 1)) continue;
      const auto k = static_cast<std::size_t>(samples.n);
      samples.value[k] = c0[x];
      samples.d_static[k] = samples.value[k] - bilinear_u8(prev_left, u, v);
      samples.object_px[k] = cv::Point(ox, oy);
      ++samples.n;
    }
  }
}

// Whether some shift of the object's motion within +- search_px fits the samples with a spread below e_needed
// (stops at the first that does).
bool object_motion_fits(const cv::Mat& prev_left, int search_px, double e_needed, BlockSamples& samples) {
  const int r = search_px;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      for (int i = 0; i < samples.n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const cv::Point q = samples.object_px[k];
        samples.d_object[k] = samples.value[k] - prev_left.ptr<uint8_t>(q.y + dy)[q.x + dx];
      }
      if (spread(samples.d_object.data(), samples.n) < e_needed) return true;
    }
  }
  return false;
}

// Clears the connected parts of the outline (at `origin` in the image) without an object point within radius_px.
void keep_parts_with_object_points(cv::Mat& outline, const std::vector<cv::Point2f>& object_points, cv::Point origin,
                                   int radius_px) {
  cv::Mat labels;
  const int n_labels = cv::connectedComponents(outline, labels, 8, CV_32S);
  std::vector<uint8_t> keep(static_cast<std::size_t>(n_labels), 0);
  for (const cv::Point2f& p : object_points) {
    const int cx = cvRound(p.x) - origin.x, cy = cvRound(p.y) - origin.y;
    for (int y = std::max(0, cy - radius_px); y <= std::min(outline.rows - 1, cy + radius_px); ++y) {
      const int* l = labels.ptr<int>(y);
      for (int x = std::max(0, cx - radius_px); x <= std::min(outline.cols - 1, cx + radius_px); ++x) {
        if (l[x] > 0) keep[static_cast<std::size_t>(l[x])] = 1;
      }
    }
  }
  for (int y = 0; y < outline.rows; ++y) {
    uint8_t* o = outline.ptr<uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    for (int x = 0; x < outline.cols; ++x) {
      if (o[x] && !keep[static_cast<std::size_t>(l[x])]) o[x] = 0;
    }
  }
}

}  // namespace

MotionCarveStats carve_by_motion(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera,
                                 double bf_px_m, const SE3d& T_cur_prev, cv::Point2f object_motion_px,
                                 double separation_px, const std::vector<cv::Point2f>& object_points,
                                 const cv::Mat& disparity_px, cv::Point origin, const MotionCarveConfig& config,
                                 cv::Mat& outline) {
  CV_Assert(cur_left.type() == CV_8UC1 && prev_left.type() == CV_8UC1 && cur_left.size() == prev_left.size());
  CV_Assert(outline.type() == CV_8UC1 && disparity_px.type() == CV_32FC1 && outline.size() == disparity_px.size());
  MotionCarveStats stats;
  if (!config.enabled || !(separation_px >= config.min_separation_px) || outline.empty() || object_points.empty()) {
    return stats;
  }
  stats.ran = true;
  const StaticWarp warp(camera, bf_px_m, T_cur_prev);
  const int B = config.block_px, step = config.sample_step_px;
  const cv::Point motion_px(static_cast<int>(std::lround(object_motion_px.x)),
                            static_cast<int>(std::lround(object_motion_px.y)));
  BlockSamples samples(static_cast<std::size_t>(((B + step - 1) / step) * ((B + step - 1) / step)));
  cv::Mat removed = cv::Mat::zeros(outline.size(), CV_8UC1);
  bool any_static = false;
  // The blocks tile the outline's bounding box.
  const cv::Rect box = cv::boundingRect(outline);
  for (int by = box.y; by < box.br().y; by += B) {
    for (int bx = box.x; bx < box.br().x; bx += B) {
      const cv::Rect block(bx, by, std::min(bx + B, box.br().x) - bx, std::min(by + B, box.br().y) - by);
      sample_block(cur_left, prev_left, warp, outline, disparity_px, origin, block, motion_px, config, samples);
      if (samples.n < config.min_samples) continue;
      ++stats.blocks_tested;
      const double e_static = spread(samples.d_static.data(), samples.n);
      if (e_static > config.max_static_error_dn) continue;
      // Static when every shift of the object's motion fits worse than this.
      const double e_needed = std::max(config.min_object_error_dn, e_static / config.max_static_ratio);
      if (object_motion_fits(prev_left, config.search_px, e_needed, samples)) continue;
      ++stats.blocks_static;
      removed(block).setTo(255);
      any_static = true;
    }
  }
  if (!any_static) return stats;
  const int before = cv::countNonZero(outline);
  outline.setTo(0, removed);
  keep_parts_with_object_points(outline, object_points, origin, config.seed_radius_px);  // the parts that stay
  stats.pixels_removed = before - cv::countNonZero(outline);
  return stats;
}

}  // namespace agvslam::dynamic
