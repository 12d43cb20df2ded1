#include "agvslam/slam/point_retirement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

const char* to_string(RetirementReason reason) {
  switch (reason) {
    case RetirementReason::kMask:
      return "mask";
    case RetirementReason::kAbsent:
      return "absent";
  }
  return "?";
}

const char* to_string(SurfaceAt surface) {
  switch (surface) {
    case SurfaceAt::kUnknown:
      return "unknown";
    case SurfaceAt::kNoMatch:
      return "no match";
    case SurfaceAt::kAtDepth:
      return "at depth";
    case SurfaceAt::kBehind:
      return "behind";
    case SurfaceAt::kInFront:
      return "in front";
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
  const auto correlate = [&](int d) {
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
    if (r_var > 1e-9) zncc[static_cast<std::size_t>(d)] = cross / (n * std::sqrt(var * r_var));
  };
  for (int d = 0; d <= d_max; ++d) correlate(d);
  const auto best_it = std::max_element(zncc.begin(), zncc.end());
  if (*best_it < config.probe_min_zncc) return SurfaceAt::kNoMatch;
  const int best = static_cast<int>(best_it - zncc.begin());
  // The surface is where the correlation peaks: the probe runs only where the image no longer looks like the
  // point's reference, so a better correlation elsewhere on the row is no longer the point's own surface.
  double d_best = best;
  if (best > 0 && best < d_max) {
    const double a = zncc[static_cast<std::size_t>(best - 1)], b = *best_it,
                 c = zncc[static_cast<std::size_t>(best + 1)];
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
  w.absent = static_cast<uint16_t>(((w.absent << 1) | (outcome == Outcome::kAbsent ? 1u : 0u)) & window_bits_);
  w.no_match = static_cast<uint16_t>(((w.no_match << 1) | (outcome == Outcome::kNoMatch ? 1u : 0u)) & window_bits_);
  if (outcome == Outcome::kNoEvidence) return false;
  const int mask = __builtin_popcount(w.mask), absent = __builtin_popcount(w.absent);
  const int no_match = __builtin_popcount(w.no_match);
  if (absent == 0 || mask + absent + no_match < config_.min_frames) return false;
  reason = mask > absent + no_match ? RetirementReason::kMask : RetirementReason::kAbsent;
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

namespace {

// The left image's (2 h + 1)^2 patch around (u_px, v_px) into `patch`; false when it does not fit in the image.
bool read_patch(const cv::Mat& left, double u_px, double v_px, int h, std::array<uint8_t, 49>& patch) {
  if (left.empty() || left.type() != CV_8UC1) return false;
  const int u = static_cast<int>(std::lround(u_px)), v = static_cast<int>(std::lround(v_px));
  if (u - h < 0 || v - h < 0 || u + h >= left.cols || v + h >= left.rows) return false;
  const int side = 2 * h + 1;
  for (int y = 0; y < side; ++y) {
    const uint8_t* row = left.ptr<uint8_t>(v - h + y) + (u - h);
    std::copy(row, row + side, patch.begin() + y * side);
  }
  return true;
}

// Zero-mean normalised correlation of two patches of `count` grey levels; nullopt when either is flatter than
// min_contrast (standard deviation, grey levels), which says nothing about the surface.
std::optional<double> patch_zncc(const std::array<uint8_t, 49>& a, const std::array<uint8_t, 49>& b, int count,
                                 double min_contrast) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (int k = 0; k < count; ++k) {
    const double x = a[static_cast<std::size_t>(k)], y = b[static_cast<std::size_t>(k)];
    sa += x;
    sb += y;
    saa += x * x;
    sbb += y * y;
    sab += x * y;
  }
  const double n = count;
  const double var_a = saa / n - (sa / n) * (sa / n), var_b = sbb / n - (sb / n) * (sb / n);
  if (var_a < min_contrast * min_contrast || var_b < min_contrast * min_contrast) return std::nullopt;
  return (sab / n - (sa / n) * (sb / n)) / std::sqrt(var_a * var_b);
}

}  // namespace

std::optional<bool> PointRetirement::looks_as_before(MapPoint& point, const cv::Mat& left, double u_px,
                                                     double v_px) const {
  if (!point.retirement.has_reference) return std::nullopt;
  std::array<uint8_t, 49> now{};
  if (!read_patch(left, u_px, v_px, config_.probe_half_size_px, now)) return std::nullopt;
  const int side = 2 * config_.probe_half_size_px + 1;
  const std::optional<double> zncc =
      patch_zncc(point.retirement.reference_patch, now, side * side, config_.probe_min_contrast);
  if (!zncc) return std::nullopt;
  if (*zncc < config_.probe_min_zncc) return false;
  // Follow the slow change of a static surface's appearance as the camera moves (scale, perspective); a change
  // between two frames is kept as it is, so an object that left is seen to differ on every later frame.
  point.retirement.reference_patch = now;
  return true;
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
  const auto project = [&](const Eigen::Vector3d& p_c) {
    return Eigen::Vector2d(intrinsics_.fx * p_c.x() / p_c.z() + intrinsics_.cx,
                           intrinsics_.fy * p_c.y() / p_c.z() + intrinsics_.cy);
  };

  for (const Match& m : matches) {
    MapPoint& p = *m.point;
    if (p.bad()) continue;
    const std::size_t i = static_cast<std::size_t>(m.keypoint);
    const cv::KeyPoint& kp = frame.keypoints[i];
    const Eigen::Vector3d p_c = T_c_w * p.p_w;
    bool in_front = false;
    const double chi2 = reprojection_chi2(intrinsics_, p_c, {kp.pt.x, kp.pt.y}, frame.u_right[i],
                                          g.inv_level_sigma2[static_cast<std::size_t>(kp.octave)], &in_front);
    const double bound = frame.u_right[i] >= 0 ? config_.chi2_stereo : config_.chi2_mono;
    // Matched away from its prediction: a moved point or a mismatch (a repeated texture), no outcome either way.
    // A keypoint without stereo depth confirms the direction only: a surface behind a point that left lies on the
    // same ray, so such a match leaves the point to the appearance test below.
    if (!in_front || chi2 > bound || frame.u_right[i] < 0) continue;
    // Found where the map predicts it: what the image shows there becomes its reference appearance.
    if (!frame.outlier[i]) {
      const Eigen::Vector2d uv = project(p_c);
      p.retirement.has_reference =
          read_patch(images.left, uv.x(), uv.y(), config_.probe_half_size_px, p.retirement.reference_patch);
    }
    RetirementReason unused;
    record(p, frame.id, Outcome::kNoEvidence, unused);
  }

  const bool has_mask = !images.dynamic_mask.empty();
  for (MapPoint* point : local_points) {
    MapPoint& p = *point;
    // Only points with a reference appearance can disagree with it (a point never matched since the map was loaded
    // says nothing).
    if (p.bad() || p.retirement.last_frame == frame.id || !p.retirement.has_reference) continue;
    const Eigen::Vector3d p_c = T_c_w * p.p_w;
    if (p_c.z() <= 0) continue;
    const Eigen::Vector2d uv = project(p_c);
    const double u = uv.x(), v = uv.y();
    if (!g.in_image(u, v)) continue;
    const Eigen::Vector3d ray = p.p_w - center;
    const double dist = ray.norm();
    if (dist < p.min_invariance_distance() || dist > p.max_invariance_distance()) continue;
    // Seen from within 60 degrees of its mean viewing direction (ORB-SLAM2's frustum test): beyond that the
    // tracker would not expect to match it either.
    if (ray.dot(p.normal_w) < 0.5 * dist) continue;
    // The cheap test first: where the image still shows what it showed when the point was last found, its surface
    // is there (a static point in a false mask region, or one the matcher merely missed).
    const std::optional<bool> same = looks_as_before(p, images.left, u, v);
    if (!same) continue;
    Outcome outcome = Outcome::kNoEvidence;
    if (!*same) {
      // Something else is seen there: the stereo probe tells an occluder (in front: no outcome, a hidden point keeps
      // its window) from the object having moved on (mask with a surface at its depth) or away (a surface behind).
      const int level = p.predict_scale_level(dist, g);
      const double sigma_level = g.scale_factors[static_cast<std::size_t>(level)];
      const double tolerance =
          std::sqrt(config_.depth_chi2 * (sigma_level * sigma_level + config_.probe_sigma_px * config_.probe_sigma_px));
      const double disparity = intrinsics_.bf / p_c.z();
      const SurfaceAt surface = probe_stereo(images.left, images.right, u, v, disparity, tolerance, config_);
      const bool in_mask = has_mask && images.dynamic_mask.at<uint8_t>(static_cast<int>(v), static_cast<int>(u)) != 0;
      if (surface == SurfaceAt::kBehind) {
        outcome = Outcome::kAbsent;
      } else if (surface == SurfaceAt::kNoMatch) {
        outcome = Outcome::kNoMatch;
      } else if (surface == SurfaceAt::kAtDepth) {
        outcome = in_mask ? Outcome::kMask : Outcome::kNoEvidence;
      } else {
        continue;  // occluded or nothing to see
      }
    }
    RetirementReason reason;
    if (record(p, frame.id, outcome, reason)) to_retire.emplace_back(&p, reason);
  }

  for (const auto& [point, reason] : to_retire) {
    if (point->bad()) continue;
    retire(*point, map);
    switch (reason) {
      case RetirementReason::kMask:
        ++counts.mask;
        break;
      case RetirementReason::kAbsent:
        ++counts.absent;
        break;
    }
  }
  return counts;
}

}  // namespace agvslam::slam
