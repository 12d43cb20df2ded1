#include "agvslam/dynamic/photometric_check.h"

#include <cmath>

#include "agvslam/dynamic/bilinear.h"
#include "agvslam/dynamic/static_warp.h"

namespace agvslam::dynamic {
namespace {

constexpr double kMinDepthM = 0.1;  // a warped point nearer than this to the earlier camera is not sampled

}  // namespace

void check_superpixel_motion(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera,
                             double bf_px_m, const SE3d& T_cur_prev, const cv::Mat& labels, cv::Point origin,
                             const std::vector<DisparityPlane>& planes, const PhotometricCheckConfig& config,
                             std::vector<SuperpixelMotion>& motion) {
  CV_Assert(cur_left.type() == CV_8UC1 && prev_left.type() == CV_8UC1 && cur_left.size() == prev_left.size());
  CV_Assert(labels.type() == CV_32SC1);
  const std::size_t n = planes.size();
  motion.assign(n, SuperpixelMotion{});
  std::vector<double> sum(n, 0), sum_sq(n, 0), sum_grad(n, 0);
  const StaticWarp warp(camera, bf_px_m, T_cur_prev);
  const int w = cur_left.cols, h = cur_left.rows;
  const int step = config.sample_step_px;
  for (int ly = 0; ly < labels.rows; ly += step) {
    const int y = ly + origin.y;
    if (y < 1 || y >= h - 1) continue;
    const int32_t* lrow = labels.ptr<int32_t>(ly);
    const uint8_t* c0 = cur_left.ptr<uint8_t>(y);
    const uint8_t* cm = cur_left.ptr<uint8_t>(y - 1);
    const uint8_t* cp = cur_left.ptr<uint8_t>(y + 1);
    for (int lx = 0; lx < labels.cols; lx += step) {
      const int k = lrow[lx];
      if (k < 0 || static_cast<std::size_t>(k) >= n) continue;
      const DisparityPlane& plane = planes[static_cast<std::size_t>(k)];
      if (!plane.valid) continue;
      const int x = lx + origin.x;
      if (x < 1 || x >= w - 1) continue;
      const double d = plane.disparity_at(x, y);
      if (d < 0.5) continue;
      double u, v;
      if (!warp.at(x, y, d, u, v, kMinDepthM)) continue;
      if (!(u >= 0 && v >= 0 && u < w - 1 && v < h - 1)) continue;
      const double diff = c0[x] - bilinear_u8(prev_left, u, v);
      const double gx = 0.5 * (c0[x + 1] - c0[x - 1]), gy = 0.5 * (cp[x] - cm[x]);
      const auto u_k = static_cast<std::size_t>(k);
      sum[u_k] += diff;
      sum_sq[u_k] += diff * diff;
      sum_grad[u_k] += std::sqrt(gx * gx + gy * gy);
      ++motion[u_k].samples;
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    SuperpixelMotion& m = motion[k];
    if (m.samples < config.min_samples) continue;
    const double mean = sum[k] / m.samples;
    const double spread = std::sqrt(std::max(0.0, sum_sq[k] / m.samples - mean * mean));
    m.mean_gradient = sum_grad[k] / m.samples;
    if (m.mean_gradient < config.min_gradient) continue;
    m.apparent_motion_px = spread / m.mean_gradient;
    m.moves_with_background = m.apparent_motion_px <= config.max_motion_px;
  }
}

SuperpixelMotion region_motion(const cv::Mat& cur_left, const cv::Mat& ref_left, const PinholeCamera& camera,
                               double bf_px_m, const SE3d& T_cur_ref, const cv::Mat& mask, const cv::Mat& disparity_px,
                               cv::Point origin, const PhotometricCheckConfig& config, double max_motion_px) {
  CV_Assert(cur_left.type() == CV_8UC1 && ref_left.type() == CV_8UC1 && cur_left.size() == ref_left.size());
  CV_Assert(mask.type() == CV_8UC1 && disparity_px.type() == CV_32FC1 && mask.size() == disparity_px.size());
  SuperpixelMotion m;
  const StaticWarp warp(camera, bf_px_m, T_cur_ref);
  const int w = cur_left.cols, h = cur_left.rows, step = config.sample_step_px, inset = config.region_inset_px;
  double sum = 0, sum_sq = 0, sum_grad = 0;
  for (int ly = inset; ly < mask.rows - inset; ly += step) {
    const int y = ly + origin.y;
    if (y < 1 || y >= h - 1) continue;
    const uint8_t* m_above = mask.ptr<uint8_t>(ly - inset);
    const uint8_t* m_row = mask.ptr<uint8_t>(ly);
    const uint8_t* m_below = mask.ptr<uint8_t>(ly + inset);
    const float* d_row = disparity_px.ptr<float>(ly);
    const uint8_t* c0 = cur_left.ptr<uint8_t>(y);
    const uint8_t* cm = cur_left.ptr<uint8_t>(y - 1);
    const uint8_t* cp = cur_left.ptr<uint8_t>(y + 1);
    for (int lx = inset; lx < mask.cols - inset; lx += step) {
      if (!m_row[lx] || !m_row[lx - inset] || !m_row[lx + inset] || !m_above[lx] || !m_below[lx]) continue;
      const double d = d_row[lx];
      if (!(d > 0.5)) continue;
      const int x = lx + origin.x;
      if (x < 1 || x >= w - 1) continue;
      const double gx = 0.5 * (c0[x + 1] - c0[x - 1]), gy = 0.5 * (cp[x] - cm[x]);
      const double grad = std::sqrt(gx * gx + gy * gy);
      if (grad < config.min_gradient) continue;
      double u, v;
      if (!warp.at(x, y, d, u, v, kMinDepthM)) continue;
      if (!(u >= 0 && v >= 0 && u < w - 1 && v < h - 1)) continue;
      const double diff = c0[x] - bilinear_u8(ref_left, u, v);
      sum += diff;
      sum_sq += diff * diff;
      sum_grad += grad;
      ++m.samples;
    }
  }
  if (m.samples < config.min_samples) return m;
  const double mean = sum / m.samples;
  m.mean_gradient = sum_grad / m.samples;
  m.apparent_motion_px = std::sqrt(std::max(0.0, sum_sq / m.samples - mean * mean)) / m.mean_gradient;
  m.moves_with_background = m.apparent_motion_px <= max_motion_px;
  return m;
}

}  // namespace agvslam::dynamic
