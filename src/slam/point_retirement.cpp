#include "agvslam/slam/point_retirement.h"

#include <algorithm>
#include <cmath>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

const char* to_string(RetirementReason reason) {
  switch (reason) {
    case RetirementReason::kMask: return "mask";
    case RetirementReason::kMotion: return "motion";
    case RetirementReason::kAbsent: return "absent";
  }
  return "?";
}

const char* to_string(SurfaceAt surface) {
  switch (surface) {
    case SurfaceAt::kUnknown: return "unknown";
    case SurfaceAt::kAtDepth: return "at depth";
    case SurfaceAt::kBehind: return "behind";
    case SurfaceAt::kInFront: return "in front";
  }
  return "?";
}

SurfaceAt probe_stereo(const cv::Mat& left, const cv::Mat& right, double u_px, double v_px,
                       double expected_disparity_px, double tolerance_px, const RetirementConfig& config) {
  if (left.empty() || right.empty() || left.type() != CV_8UC1 || right.type() != CV_8UC1) return SurfaceAt::kUnknown;
  const int h = config.probe_half_size_px;
  const int u = static_cast<int>(std::lround(u_px)), v = static_cast<int>(std::lround(v_px));
  if (u - h < 0 || v - h < 0 || u + h >= left.cols || v + h >= left.rows || v + h >= right.rows) {
    return SurfaceAt::kUnknown;
  }
  const int side = 2 * h + 1;
  const double n = side * side;
  double left_patch[31 * 31];
  double sum = 0, sum2 = 0;
  for (int y = 0; y < side; ++y) {
    const uint8_t* row = left.ptr<uint8_t>(v - h + y) + (u - h);
    for (int x = 0; x < side; ++x) {
      const double g = row[x];
      left_patch[y * side + x] = g;
      sum += g;
      sum2 += g * g;
    }
  }
  const double mean = sum / n;
  const double var = std::max(0.0, sum2 / n - mean * mean);
  if (std::sqrt(var) < config.probe_min_contrast) return SurfaceAt::kUnknown;
  for (int k = 0; k < side * side; ++k) left_patch[k] -= mean;

  const int d_max = std::min(static_cast<int>(std::floor(2.0 * expected_disparity_px + tolerance_px)), u - h);
  if (d_max < 0) return SurfaceAt::kUnknown;
  std::vector<double> zncc(static_cast<std::size_t>(d_max) + 1, -1.0);
  for (int d = 0; d <= d_max; ++d) {
    double rs = 0, rs2 = 0, cross = 0;
    for (int y = 0; y < side; ++y) {
      const uint8_t* row = right.ptr<uint8_t>(v - h + y) + (u - d - h);
      for (int x = 0; x < side; ++x) {
        const double g = row[x];
        rs += g;
        rs2 += g * g;
        cross += left_patch[y * side + x] * g;
      }
    }
    const double r_var = rs2 / n - (rs / n) * (rs / n);
    if (r_var <= 1e-9) continue;
    zncc[static_cast<std::size_t>(d)] = cross / (n * std::sqrt(var * r_var));
  }
  // A surface at the expected depth when any disparity within the tolerance correlates (a repeated texture may
  // correlate better elsewhere: that is no evidence against the point); otherwise the best disparity says where
  // the surface is.
  const int lo = std::max(0, static_cast<int>(std::ceil(expected_disparity_px - tolerance_px)));
  const int hi = std::min(d_max, static_cast<int>(std::floor(expected_disparity_px + tolerance_px)));
  for (int d = lo; d <= hi; ++d) {
    if (zncc[static_cast<std::size_t>(d)] >= config.probe_min_zncc) return SurfaceAt::kAtDepth;
  }
  const auto best_it = std::max_element(zncc.begin(), zncc.end());
  if (*best_it < config.probe_min_zncc) return SurfaceAt::kUnknown;
  const int best = static_cast<int>(best_it - zncc.begin());
  double d_best = best;
  if (best > 0 && best < d_max) {
    const double a = zncc[static_cast<std::size_t>(best - 1)], b = *best_it, c = zncc[static_cast<std::size_t>(best + 1)];
    const double denom = a - 2 * b + c;
    if (denom < 0) d_best += std::clamp(0.5 * (a - c) / denom, -0.5, 0.5);
  }
  if (d_best < expected_disparity_px - tolerance_px) return SurfaceAt::kBehind;
  if (d_best > expected_disparity_px + tolerance_px) return SurfaceAt::kInFront;
  return SurfaceAt::kAtDepth;
}

PointRetirement::PointRetirement(const RetirementConfig& config, const StereoIntrinsics& intrinsics)
    : config_(config),
      intrinsics_(intrinsics),
      window_bits_(static_cast<uint16_t>((1u << config.window_frames) - 1u)) {}

bool PointRetirement::record(MapPoint& point, uint64_t frame_id, Outcome outcome, RetirementReason& reason) const {
  MapPoint::RetirementWindow& w = point.retirement;
  if (w.last_frame == frame_id) return false;
  w.last_frame = frame_id;
  w.frames = static_cast<uint16_t>(((w.frames << 1) | 1u) & window_bits_);
  w.mask = static_cast<uint16_t>(((w.mask << 1) | (outcome == Outcome::kMask ? 1u : 0u)) & window_bits_);
  w.motion = static_cast<uint16_t>(((w.motion << 1) | (outcome == Outcome::kMotion ? 1u : 0u)) & window_bits_);
  w.absent = static_cast<uint16_t>(((w.absent << 1) | (outcome == Outcome::kAbsent ? 1u : 0u)) & window_bits_);
  if (outcome == Outcome::kNoEvidence) return false;
  const int mask = __builtin_popcount(w.mask), motion = __builtin_popcount(w.motion),
            absent = __builtin_popcount(w.absent);
  if (mask + motion + absent < config_.min_frames) return false;
  reason = mask >= motion && mask >= absent ? RetirementReason::kMask
           : motion >= absent               ? RetirementReason::kMotion
                                            : RetirementReason::kAbsent;
  return true;
}

void PointRetirement::retire(MapPoint& point, Map& map) {
  if (point.bad()) return;
  const MapPointPtr keep = point.shared_from_this();
  point.mark_retired();
  const std::vector<Observation> observations = point.observations();
  for (const Observation& o : observations) o.keyframe->retire_keypoint(static_cast<std::size_t>(o.index));
  point.set_bad(map);
}

RetirementCounts PointRetirement::update(const Frame& frame, const std::vector<Match>& matches,
                                         const std::vector<MapPoint*>& local_points, const FrameImages& images,
                                         Map& map) {
  RetirementCounts counts;
  if (!config_.enabled || !frame.has_pose()) return counts;
  const FrameGeometry& g = *frame.geometry;
  const SE3d& T_c_w = frame.T_c_w();
  const Eigen::Vector3d center = frame.center_w();
  std::vector<std::pair<MapPoint*, RetirementReason>> to_retire;

  for (const Match& m : matches) {
    MapPoint& p = *m.point;
    if (p.bad()) continue;
    const std::size_t i = static_cast<std::size_t>(m.keypoint);
    const cv::KeyPoint& kp = frame.keypoints[i];
    bool in_front = false;
    const double chi2 = reprojection_chi2(intrinsics_, T_c_w * p.p_w, {kp.pt.x, kp.pt.y}, frame.u_right[i],
                                          g.inv_level_sigma2[static_cast<std::size_t>(kp.octave)], &in_front);
    const double bound = frame.u_right[i] >= 0 ? config_.chi2_stereo : config_.chi2_mono;
    const Outcome outcome = !in_front || chi2 > bound ? Outcome::kMotion : Outcome::kNoEvidence;
    RetirementReason reason;
    if (record(p, frame.id, outcome, reason)) to_retire.emplace_back(&p, reason);
  }

  const bool has_mask = !images.dynamic_mask.empty();
  for (MapPoint* point : local_points) {
    MapPoint& p = *point;
    if (p.bad() || p.retirement.last_frame == frame.id) continue;
    const Eigen::Vector3d p_c = T_c_w * p.p_w;
    if (p_c.z() <= 0) continue;
    const double u = intrinsics_.fx * p_c.x() / p_c.z() + intrinsics_.cx;
    const double v = intrinsics_.fy * p_c.y() / p_c.z() + intrinsics_.cy;
    if (!g.in_image(u, v)) continue;
    const Eigen::Vector3d ray = p.p_w - center;
    const double dist = ray.norm();
    if (dist < p.min_invariance_distance() || dist > p.max_invariance_distance()) continue;
    // Seen from within 60 degrees of its mean viewing direction (ORB-SLAM2's frustum test): beyond that the
    // tracker would not expect to match it either.
    if (ray.dot(p.normal_w) < 0.5 * dist) continue;
    const int level = p.predict_scale_level(dist, g);
    const double sigma_level = g.scale_factors[static_cast<std::size_t>(level)];
    const double tolerance = std::sqrt(config_.depth_chi2 * (sigma_level * sigma_level +
                                                             config_.probe_sigma_px * config_.probe_sigma_px));
    const double disparity = intrinsics_.bf / p_c.z();
    const SurfaceAt surface = probe_stereo(images.left, images.right, u, v, disparity, tolerance, config_);
    const bool in_mask = has_mask && images.dynamic_mask.at<uint8_t>(static_cast<int>(v), static_cast<int>(u)) != 0;
    Outcome outcome;
    if (in_mask) {
      // Masked: either the object it lies on moves (a surface at its depth) or a mover hides it (no outcome).
      if (surface != SurfaceAt::kAtDepth) continue;
      outcome = Outcome::kMask;
    } else if (surface == SurfaceAt::kBehind) {
      outcome = Outcome::kAbsent;
    } else if (surface == SurfaceAt::kAtDepth) {
      outcome = Outcome::kNoEvidence;
    } else {
      continue;  // occluded or nothing to see: the point keeps its window
    }
    RetirementReason reason;
    if (record(p, frame.id, outcome, reason)) to_retire.emplace_back(&p, reason);
  }

  for (const auto& [point, reason] : to_retire) {
    if (point->bad()) continue;
    retire(*point, map);
    switch (reason) {
      case RetirementReason::kMask: ++counts.mask; break;
      case RetirementReason::kMotion: ++counts.motion; break;
      case RetirementReason::kAbsent: ++counts.absent; break;
    }
  }
  return counts;
}

}  // namespace agvslam::slam
