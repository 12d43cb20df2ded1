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
  const int w = cur_left.cols, h = cur_left.rows;
  const int B = config.block_px, step = config.sample_step_px, r = config.search_px;
  const int mx = static_cast<int>(std::lround(object_motion_px.x)), my = static_cast<int>(std::lround(object_motion_px.y));
  const auto max_samples = static_cast<std::size_t>(((B + step - 1) / step) * ((B + step - 1) / step));
  std::vector<double> d_static(max_samples), d_object(max_samples), value(max_samples);
  std::vector<cv::Point> object_px(max_samples);  // each sample's position moved back by the object's motion
  cv::Mat removed = cv::Mat::zeros(outline.size(), CV_8UC1);
  bool any_static = false;
  // The blocks tile the outline's bounding box.
  const cv::Rect box = cv::boundingRect(outline);
  for (int by = box.y; by < box.br().y; by += B) {
    for (int bx = box.x; bx < box.br().x; bx += B) {
      int n = 0;
      const int y_end = std::min(by + B, box.br().y), x_end = std::min(bx + B, box.br().x);
      for (int ly = by; ly < y_end; ly += step) {
        const int y = ly + origin.y;
        if (y < 1 || y >= h - 1) continue;
        const uint8_t* m_row = outline.ptr<uint8_t>(ly);
        const float* d_row = disparity_px.ptr<float>(ly);
        const uint8_t* c0 = cur_left.ptr<uint8_t>(y);
        const uint8_t* cm = cur_left.ptr<uint8_t>(y - 1);
        const uint8_t* cp = cur_left.ptr<uint8_t>(y + 1);
        for (int lx = bx; lx < x_end; lx += step) {
          if (!m_row[lx]) continue;
          const double d = d_row[lx];
          if (!(d > 0.5)) continue;
          const int x = lx + origin.x;
          if (x < 1 || x >= w - 1) continue;
          const double gx = 0.5 * (c0[x + 1] - c0[x - 1]), gy = 0.5 * (cp[x] - cm[x]);
          if (std::sqrt(gx * gx + gy * gy) < config.min_gradient) continue;
          // The object hypothesis: every shift must stay inside the previous image.
          const int ox = x - mx, oy = y - my;
          if (ox - r < 0 || oy - r < 0 || ox + r >= w || oy + r >= h) continue;
          double u, v;
          if (!warp.at(x, y, d, u, v, kMinDepthM)) continue;
          if (!(u >= 0 && v >= 0 && u < w - 1 && v < h - 1)) continue;
          const auto k = static_cast<std::size_t>(n);
          value[k] = c0[x];
          d_static[k] = value[k] - bilinear_u8(prev_left, u, v);
          object_px[k] = cv::Point(ox, oy);
          ++n;
        }
      }
      if (n < config.min_samples) continue;
      ++stats.blocks_tested;
      const double e_static = spread(d_static.data(), n);
      if (e_static > config.max_static_error_dn) continue;
      // Static when every shift of the object's motion fits worse than this (stops at the first that fits).
      const double e_needed = std::max(config.min_object_error_dn, e_static / config.max_static_ratio);
      bool object_fits = false;
      for (int dy = -r; dy <= r && !object_fits; ++dy) {
        for (int dx = -r; dx <= r && !object_fits; ++dx) {
          for (int i = 0; i < n; ++i) {
            const cv::Point q = object_px[static_cast<std::size_t>(i)];
            d_object[static_cast<std::size_t>(i)] = value[static_cast<std::size_t>(i)] - prev_left.ptr<uint8_t>(q.y + dy)[q.x + dx];
          }
          object_fits = spread(d_object.data(), n) < e_needed;
        }
      }
      if (object_fits) continue;
      ++stats.blocks_static;
      removed(cv::Rect(bx, by, x_end - bx, y_end - by)).setTo(255);
      any_static = true;
    }
  }
  if (!any_static) return stats;
  const int before = cv::countNonZero(outline);
  outline.setTo(0, removed);
  // The connected parts holding an object point stay.
  cv::Mat labels;
  const int n_labels = cv::connectedComponents(outline, labels, 8, CV_32S);
  std::vector<uint8_t> keep(static_cast<std::size_t>(n_labels), 0);
  const int rad = config.seed_radius_px;
  for (const cv::Point2f& p : object_points) {
    const int cx = cvRound(p.x) - origin.x, cy = cvRound(p.y) - origin.y;
    for (int y = std::max(0, cy - rad); y <= std::min(outline.rows - 1, cy + rad); ++y) {
      const int* l = labels.ptr<int>(y);
      for (int x = std::max(0, cx - rad); x <= std::min(outline.cols - 1, cx + rad); ++x) {
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
  stats.pixels_removed = before - cv::countNonZero(outline);
  return stats;
}

}  // namespace agvslam::dynamic
