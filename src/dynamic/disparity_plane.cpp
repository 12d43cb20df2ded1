#include "agvslam/dynamic/disparity_plane.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace agvslam::dynamic {

namespace {

uint32_t next_random(uint32_t& s) {
  // xorshift32 (state must be non-zero).
  s ^= s << 13;
  s ^= s >> 17;
  s ^= s << 5;
  return s;
}

// Least-squares plane in coordinates relative to (mx, my) for conditioning; false when degenerate.
bool least_squares(const std::vector<cv::Point3f>& samples, const std::vector<int>& use, double mx, double my,
                   DisparityPlane& plane) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int i : use) {
    const cv::Point3f& s = samples[static_cast<std::size_t>(i)];
    const Eigen::Vector3d row(s.x - mx, s.y - my, 1.0);
    A += row * row.transpose();
    rhs += row * static_cast<double>(s.z);
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
  if (ldlt.info() != Eigen::Success || !(std::abs(A.determinant()) > 1e-9)) return false;
  const Eigen::Vector3d sol = ldlt.solve(rhs);
  plane.a = sol[0];
  plane.b = sol[1];
  plane.c = sol[2] - sol[0] * mx - sol[1] * my;
  return std::isfinite(plane.a) && std::isfinite(plane.b) && std::isfinite(plane.c);
}

}  // namespace

DisparityPlane fit_disparity_plane(const std::vector<cv::Point3f>& samples, const PlaneFitConfig& config,
                                   uint32_t& rng_state) {
  DisparityPlane best;
  const int n = static_cast<int>(samples.size());
  best.support = n;
  if (n < 3) return best;
  if (rng_state == 0) rng_state = 0x9e3779b9u;
  double mx = 0, my = 0;
  for (const cv::Point3f& s : samples) {
    mx += s.x;
    my += s.y;
  }
  mx /= n;
  my /= n;

  const double thr = config.inlier_threshold_px;
  int best_count = -1;
  double best_a = 0, best_b = 0, best_c = 0;
  int max_iters = config.ransac_iterations;
  for (int it = 0; it < max_iters; ++it) {
    const int i0 = static_cast<int>(next_random(rng_state) % static_cast<uint32_t>(n));
    const int i1 = static_cast<int>(next_random(rng_state) % static_cast<uint32_t>(n));
    const int i2 = static_cast<int>(next_random(rng_state) % static_cast<uint32_t>(n));
    if (i0 == i1 || i0 == i2 || i1 == i2) continue;
    const cv::Point3f& p0 = samples[static_cast<std::size_t>(i0)];
    const cv::Point3f& p1 = samples[static_cast<std::size_t>(i1)];
    const cv::Point3f& p2 = samples[static_cast<std::size_t>(i2)];
    // Solve [x y 1] [a b c]^T = d for the three points (relative coordinates).
    const double x0 = p0.x - mx, y0 = p0.y - my, x1 = p1.x - mx, y1 = p1.y - my, x2 = p2.x - mx, y2 = p2.y - my;
    const double det = x0 * (y1 - y2) - y0 * (x1 - x2) + (x1 * y2 - x2 * y1);
    if (std::abs(det) < 1e-6) continue;  // collinear sample
    const double d0 = p0.z, d1 = p1.z, d2 = p2.z;
    const double a = (d0 * (y1 - y2) - y0 * (d1 - d2) + (d1 * y2 - d2 * y1)) / det;
    const double b = (x0 * (d1 - d2) - d0 * (x1 - x2) + (x1 * d2 - x2 * d1)) / det;
    const double c = d0 - a * x0 - b * y0;
    int count = 0;
    for (const cv::Point3f& s : samples) {
      count += std::abs(a * (s.x - mx) + b * (s.y - my) + c - s.z) <= thr;
    }
    if (count > best_count) {
      best_count = count;
      best_a = a;
      best_b = b;
      best_c = c;
      // Adaptive number of iterations for the requested confidence.
      const double w = static_cast<double>(count) / n;
      const double p_fail = 1.0 - w * w * w;
      if (p_fail <= 1e-12) {
        max_iters = it + 1;
      } else {
        const double needed = std::log(1.0 - config.confidence) / std::log(p_fail);
        if (needed < max_iters) max_iters = std::max(it + 1, static_cast<int>(std::ceil(needed)));
      }
    }
  }
  if (best_count < 3) return best;

  // Least-squares refit on the inliers (twice: the refit can change the inlier set a little).
  std::vector<int> inliers;
  inliers.reserve(static_cast<std::size_t>(n));
  DisparityPlane plane;
  plane.a = best_a;
  plane.b = best_b;
  plane.c = best_c - best_a * mx - best_b * my;
  for (int pass = 0; pass < 2; ++pass) {
    inliers.clear();
    for (int i = 0; i < n; ++i) {
      const cv::Point3f& s = samples[static_cast<std::size_t>(i)];
      if (std::abs(plane.disparity_at(s.x, s.y) - s.z) <= thr) inliers.push_back(i);
    }
    if (inliers.size() < 3) return best;
    DisparityPlane refit;
    if (!least_squares(samples, inliers, mx, my, refit)) break;
    plane.a = refit.a;
    plane.b = refit.b;
    plane.c = refit.c;
  }
  inliers.clear();
  double sq = 0;
  for (int i = 0; i < n; ++i) {
    const cv::Point3f& s = samples[static_cast<std::size_t>(i)];
    const double r = plane.disparity_at(s.x, s.y) - s.z;
    if (std::abs(r) <= thr) {
      inliers.push_back(i);
      sq += r * r;
    }
  }
  plane.support = n;
  plane.inliers = static_cast<int>(inliers.size());
  plane.rms_px = plane.inliers > 0 ? std::sqrt(sq / plane.inliers) : 0.0;
  plane.valid = static_cast<double>(plane.inliers) >= config.min_inlier_fraction * n && plane.inliers >= 3;
  return plane;
}

void fit_superpixel_planes(const cv::Mat& labels, int count, const cv::Mat& disparity_px, cv::Point origin,
                           const PlaneFitConfig& config, std::vector<DisparityPlane>& planes, int sample_step) {
  CV_Assert(labels.type() == CV_32SC1 && disparity_px.type() == CV_32FC1 && labels.size() == disparity_px.size());
  CV_Assert(sample_step >= 1);
  planes.assign(static_cast<std::size_t>(std::max(count, 0)), DisparityPlane{});
  if (count <= 0) return;
  std::vector<int> sizes(static_cast<std::size_t>(count), 0);
  std::vector<std::vector<cv::Point3f>> samples(static_cast<std::size_t>(count));
  for (int y = 0; y < labels.rows; y += sample_step) {
    const int32_t* l = labels.ptr<int32_t>(y);
    const float* d = disparity_px.ptr<float>(y);
    for (int x = 0; x < labels.cols; x += sample_step) {
      const int k = l[x];
      if (k < 0 || k >= count) continue;
      ++sizes[static_cast<std::size_t>(k)];
      if (d[x] > 0) {
        samples[static_cast<std::size_t>(k)].emplace_back(static_cast<float>(x + origin.x),
                                                          static_cast<float>(y + origin.y), d[x]);
      }
    }
  }
  for (int k = 0; k < count; ++k) {
    std::vector<cv::Point3f>& s = samples[static_cast<std::size_t>(k)];
    const int valid = static_cast<int>(s.size());
    // min_valid_pixels counts full-resolution pixels: each sample stands for sample_step^2 of them.
    if (valid * sample_step * sample_step < config.min_valid_pixels ||
        valid < config.min_valid_fraction * sizes[static_cast<std::size_t>(k)] || valid < 3) {
      planes[static_cast<std::size_t>(k)].support = valid;
      continue;
    }
    if (valid > config.max_samples) {  // regular subsampling keeps the spatial spread
      const double stride = static_cast<double>(valid) / config.max_samples;
      std::vector<cv::Point3f> sub;
      sub.reserve(static_cast<std::size_t>(config.max_samples));
      for (int i = 0; i < config.max_samples; ++i) sub.push_back(s[static_cast<std::size_t>(i * stride)]);
      s.swap(sub);
    }
    uint32_t rng = config.seed * 2654435761u + static_cast<uint32_t>(k) * 40503u + 1u;
    planes[static_cast<std::size_t>(k)] = fit_disparity_plane(s, config, rng);
  }
}

}  // namespace agvslam::dynamic
