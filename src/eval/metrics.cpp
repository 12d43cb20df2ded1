#include "agvslam/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace agvslam::eval {

ErrorStats compute_stats(std::vector<double> values) {
  ErrorStats s;
  s.count = values.size();
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  double sum = 0, sum_sq = 0;
  for (const double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  s.std = std::sqrt(std::max(0.0, sum_sq / n - s.mean * s.mean));
  std::sort(values.begin(), values.end());
  s.min = values.front();
  s.max = values.back();
  const std::size_t mid = values.size() / 2;
  s.median = values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

AteResult compute_ate(const PosePairs& pairs, AlignMode mode) {
  AteResult r;
  r.mode = mode;
  const Eigen::Index n = static_cast<Eigen::Index>(pairs.size());
  Eigen::Matrix3Xd p_est(3, n), p_gt(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    p_est.col(i) = pairs.T_w_c_est[static_cast<std::size_t>(i)].translation();
    p_gt.col(i) = pairs.T_w_c_gt[static_cast<std::size_t>(i)].translation();
  }
  if (mode != AlignMode::kNone && n > 0) r.alignment = umeyama(p_est, p_gt, mode == AlignMode::kSim3);
  r.errors_m.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d aligned = r.alignment.apply(Eigen::Vector3d(p_est.col(i)));
    r.p_est_aligned.push_back(aligned);
    r.p_gt.push_back(p_gt.col(i));
    r.errors_m.push_back((aligned - p_gt.col(i)).norm());
  }
  r.translation_m = compute_stats(r.errors_m);
  return r;
}

namespace {
SE3d relative(const SE3d& a, const SE3d& b, double scale) {
  SE3d d = a.inverse() * b;
  d.translation() *= scale;
  return d;
}
}  // namespace

RpeResult compute_rpe(const PosePairs& pairs, int delta_frames, double scale) {
  RpeResult r;
  r.delta_frames = delta_frames;
  std::vector<double> t_err, r_err;
  const std::size_t step = static_cast<std::size_t>(std::max(1, delta_frames));
  for (std::size_t i = 0; i + step < pairs.size(); ++i) {
    const SE3d d_gt = relative(pairs.T_w_c_gt[i], pairs.T_w_c_gt[i + step], 1.0);
    const SE3d d_est = relative(pairs.T_w_c_est[i], pairs.T_w_c_est[i + step], scale);
    const SE3d e = d_gt.inverse() * d_est;
    t_err.push_back(e.translation().norm());
    r_err.push_back(rotation_angle_rad(e) * 180.0 / M_PI);
  }
  r.translation_m = compute_stats(std::move(t_err));
  r.rotation_deg = compute_stats(std::move(r_err));
  return r;
}

double path_length_m(const std::vector<SE3d>& poses) {
  double len = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) len += (poses[i].translation() - poses[i - 1].translation()).norm();
  return len;
}

std::optional<KittiResult> compute_kitti_relative(const PosePairs& pairs, double scale,
                                                  const std::vector<double>& lengths_m, int step_frames) {
  const std::size_t n = pairs.size();
  if (n < 2 || lengths_m.empty()) return std::nullopt;
  std::vector<double> dist(n, 0.0);
  for (std::size_t i = 1; i < n; ++i)
    dist[i] = dist[i - 1] + (pairs.T_w_c_gt[i].translation() - pairs.T_w_c_gt[i - 1].translation()).norm();
  if (dist.back() < *std::min_element(lengths_m.begin(), lengths_m.end())) return std::nullopt;

  KittiResult result;
  double t_sum = 0, r_sum = 0;
  for (const double len : lengths_m) {
    KittiSegmentError seg;
    seg.length_m = len;
    double seg_t = 0, seg_r = 0;
    for (std::size_t first = 0; first < n; first += static_cast<std::size_t>(std::max(1, step_frames))) {
      const auto it =
          std::lower_bound(dist.begin() + static_cast<std::ptrdiff_t>(first), dist.end(), dist[first] + len);
      if (it == dist.end()) break;
      const std::size_t last = static_cast<std::size_t>(it - dist.begin());
      const SE3d d_gt = relative(pairs.T_w_c_gt[first], pairs.T_w_c_gt[last], 1.0);
      const SE3d d_est = relative(pairs.T_w_c_est[first], pairs.T_w_c_est[last], scale);
      const SE3d e = d_est.inverse() * d_gt;
      seg_t += e.translation().norm() / len;
      seg_r += rotation_angle_rad(e) / len;
      ++seg.count;
    }
    if (seg.count == 0) continue;
    t_sum += seg_t;
    r_sum += seg_r;
    result.count += seg.count;
    seg.t_rel_pct = 100.0 * seg_t / static_cast<double>(seg.count);
    seg.r_rel_deg_per_100m = 100.0 * (180.0 / M_PI) * seg_r / static_cast<double>(seg.count);
    result.per_length.push_back(seg);
  }
  if (result.count == 0) return std::nullopt;
  result.t_rel_pct = 100.0 * t_sum / static_cast<double>(result.count);
  result.r_rel_deg_per_100m = 100.0 * (180.0 / M_PI) * r_sum / static_cast<double>(result.count);
  return result;
}

}  // namespace agvslam::eval
