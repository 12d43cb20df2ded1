#include "agvslam/slam/matcher.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <utility>
#include <vector>

#include "agvslam/slam/map.h"

namespace agvslam::slam {

namespace {

float angle_diff_deg(float a, float b) {
  float d = a - b;
  if (d < 0) d += 360.f;
  return d;
}

// The candidate keypoint of `image` (a Frame or KeyFrame) whose descriptor is nearest to `descriptor`, among those
// at pyramid level `level` - 1 or `level` (any level for level < 0) that `skip` does not reject:
// {distance, index}, {256, -1} when there is none.
template <class Image, class Skip>
std::pair<int, int> nearest_candidate(const uint8_t* descriptor, const Image& image, const std::vector<int>& candidates,
                                      int level, const Skip& skip) {
  int best = 256, best_j = -1;
  for (const int j : candidates) {
    const std::size_t sj = static_cast<std::size_t>(j);
    if (skip(sj)) continue;
    if (level >= 0) {
      const int kp_level = image.keypoints[sj].octave;
      if (kp_level < level - 1 || kp_level > level) continue;
    }
    const int d = hamming_distance(descriptor, image.descriptor(sj));
    if (d < best) {
      best = d;
      best_j = j;
    }
  }
  return {best, best_j};
}
constexpr auto kSkipNone = [](std::size_t) { return false; };

}  // namespace

void Matcher::reset_rotation_histogram() {
  for (auto& bin : histogram_) bin.clear();
}

void Matcher::add_to_histogram(float diff_deg, int index) {
  int bin = static_cast<int>(std::round(diff_deg * (1.0f / 360.f) * kHistogramBins));
  if (bin >= kHistogramBins) bin = 0;
  if (bin < 0) bin = 0;
  histogram_[bin].push_back(index);
}

int Matcher::drop_rotation_outliers(std::vector<MapPointPtr>& matches) {
  rotation_outliers(rejected_);
  for (const int j : rejected_) matches[static_cast<std::size_t>(j)].reset();
  return static_cast<int>(rejected_.size());
}

void Matcher::rotation_outliers(std::vector<int>& out) const {
  out.clear();
  int m1 = 0, m2 = 0, m3 = 0;
  int i1 = -1, i2 = -1, i3 = -1;
  for (int i = 0; i < kHistogramBins; ++i) {
    const int s = static_cast<int>(histogram_[i].size());
    if (s > m1) {
      m3 = m2;
      i3 = i2;
      m2 = m1;
      i2 = i1;
      m1 = s;
      i1 = i;
    } else if (s > m2) {
      m3 = m2;
      i3 = i2;
      m2 = s;
      i2 = i;
    } else if (s > m3) {
      m3 = s;
      i3 = i;
    }
  }
  // ORB-SLAM2: the second and third bins count only with at least 10 % of the first.
  if (m2 < 0.1 * m1) {
    i2 = -1;
    i3 = -1;
  } else if (m3 < 0.1 * m1) {
    i3 = -1;
  }
  for (int i = 0; i < kHistogramBins; ++i) {
    if (i == i1 || i == i2 || i == i3) continue;
    out.insert(out.end(), histogram_[i].begin(), histogram_[i].end());
  }
}

int Matcher::search_last_frame(Frame& current, const Frame& last, float radius_px, bool check_orientation,
                               float ratio) {
  const FrameGeometry& g = *current.geometry;
  const SE3d& T_c_w = current.T_c_w();
  // The current camera centre in the last camera's frame: moving forward, points appear at coarser levels.
  const Eigen::Vector3d t_lc = last.T_c_w() * current.center_w();
  const bool forward = t_lc.z() > g.baseline_m;
  const bool backward = -t_lc.z() > g.baseline_m;
  reset_rotation_histogram();
  int matches = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    const MapPointPtr& point = last.map_points[i];
    if (!point || last.outlier[i] || point->bad()) continue;
    const Eigen::Vector3d p_c = T_c_w * point->p_w;
    if (p_c.z() <= 0) continue;
    const double inv_z = 1.0 / p_c.z();
    const double u = g.camera.fx * p_c.x() * inv_z + g.camera.cx;
    const double v = g.camera.fy * p_c.y() * inv_z + g.camera.cy;
    if (!g.in_image(u, v)) continue;
    const int last_level = last.keypoints[i].octave;
    const float radius = radius_px * g.scale_factors[static_cast<std::size_t>(last_level)];
    if (forward) {
      current.grid.features_in_area(current.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius,
                                    last_level, -1, candidates_);
    } else if (backward) {
      current.grid.features_in_area(current.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius, 0,
                                    last_level, candidates_);
    } else {
      current.grid.features_in_area(current.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius,
                                    std::max(0, last_level - 1), last_level + 1, candidates_);
    }
    if (candidates_.empty()) continue;
    const double u_right = u - g.bf * inv_z;
    int best_dist = 256, second_dist = 256, best = -1;
    for (const int j : candidates_) {
      const std::size_t sj = static_cast<std::size_t>(j);
      if (current.map_points[sj]) continue;
      if (current.u_right[sj] > 0 && std::fabs(u_right - current.u_right[sj]) > radius) continue;
      const int d = hamming_distance(point->descriptor.data(), current.descriptor(sj));
      if (d < best_dist) {
        second_dist = best_dist;
        best_dist = d;
        best = j;
      } else if (d < second_dist) {
        second_dist = d;
      }
    }
    if (ratio < 1.0f && static_cast<float>(best_dist) > ratio * static_cast<float>(second_dist)) continue;
    if (best >= 0 && best_dist <= kMatchThresholdHigh) {
      current.map_points[static_cast<std::size_t>(best)] = point;
      ++matches;
      if (check_orientation) {
        add_to_histogram(
            angle_diff_deg(last.keypoints[i].angle, current.keypoints[static_cast<std::size_t>(best)].angle), best);
      }
    }
  }
  if (check_orientation) {
    matches -= drop_rotation_outliers(current.map_points);
  }
  return matches;
}

int Matcher::search_local_points(Frame& frame, const std::vector<MapPoint*>& points, float radius_factor) {
  const FrameGeometry& g = *frame.geometry;
  constexpr float kRatio = 0.8f;
  int matches = 0;
  for (MapPoint* point : points) {
    if (!point->track.in_view || point->bad()) continue;
    const int level = point->track.scale_level;
    float r = radius_by_viewing_cos(point->track.view_cos) * radius_factor;
    r *= g.scale_factors[static_cast<std::size_t>(level)];
    frame.grid.features_in_area(frame.keypoints, g, point->track.proj_x, point->track.proj_y, r, std::max(0, level - 1),
                                level, candidates_);
    if (candidates_.empty()) continue;
    int best_dist = 256, best_level = -1, best_dist2 = 256, best_level2 = -1, best = -1;
    for (const int j : candidates_) {
      const std::size_t sj = static_cast<std::size_t>(j);
      if (frame.map_points[sj]) continue;
      if (frame.u_right[sj] > 0 && std::fabs(point->track.proj_x_right - frame.u_right[sj]) > r) continue;
      const int d = hamming_distance(point->descriptor.data(), frame.descriptor(sj));
      if (d < best_dist) {
        best_dist2 = best_dist;
        best_level2 = best_level;
        best_dist = d;
        best_level = frame.keypoints[sj].octave;
        best = j;
      } else if (d < best_dist2) {
        best_level2 = frame.keypoints[sj].octave;
        best_dist2 = d;
      }
    }
    if (best < 0 || best_dist > kMatchThresholdHigh) continue;
    if (best_level == best_level2 && best_dist > kRatio * best_dist2) continue;
    frame.map_points[static_cast<std::size_t>(best)] = point->shared_from_this();
    ++matches;
  }
  return matches;
}

int Matcher::search_keyframe_brute_force(const KeyFrame& kf, const Frame& frame, float ratio,
                                         std::vector<MapPointPtr>& matches) {
  matches.assign(frame.size(), nullptr);
  best_dist_.assign(frame.size(), 256);
  best_index_.assign(frame.size(), -1);
  reset_rotation_histogram();
  for (std::size_t i = 0; i < kf.size(); ++i) {
    const MapPointPtr& point = kf.map_point(i);
    if (!point || point->bad()) continue;
    const uint8_t* d1 = kf.descriptor(i);
    int best = 256, second = 256, best_j = -1;
    for (std::size_t j = 0; j < frame.size(); ++j) {
      const int d = hamming_distance(d1, frame.descriptor(j));
      if (d < best) {
        second = best;
        best = d;
        best_j = static_cast<int>(j);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j < 0 || best > kMatchThresholdLow || static_cast<float>(best) >= ratio * static_cast<float>(second))
      continue;
    const std::size_t sj = static_cast<std::size_t>(best_j);
    if (best < best_dist_[sj]) {  // keep the better of two keyframe points claiming one keypoint
      best_dist_[sj] = best;
      best_index_[sj] = static_cast<int>(i);
    }
  }
  int n = 0;
  for (std::size_t j = 0; j < frame.size(); ++j) {
    if (best_index_[j] < 0) continue;
    const std::size_t i = static_cast<std::size_t>(best_index_[j]);
    matches[j] = kf.map_point(i);
    add_to_histogram(angle_diff_deg(kf.keypoints[i].angle, frame.keypoints[j].angle), static_cast<int>(j));
    ++n;
  }
  n -= drop_rotation_outliers(matches);
  return n;
}

int Matcher::search_for_triangulation(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F12,
                                      std::vector<std::pair<int, int>>& out) {
  out.clear();
  const FrameGeometry& g = *kf1.geometry;
  const PinholeCamera& cam = g.camera;
  const SE3d T_c2_c1 = kf2.T_c_w() * kf1.T_w_c();
  // Epipole: kf1's centre in kf2's image (a monocular match right next to it is ill-conditioned).
  const Eigen::Vector3d c1_in_2 = T_c2_c1.translation();
  const bool epipole_valid = c1_in_2.z() > 1e-6;
  const double ex = epipole_valid ? cam.fx * c1_in_2.x() / c1_in_2.z() + cam.cx : 0;
  const double ey = epipole_valid ? cam.fy * c1_in_2.y() / c1_in_2.z() + cam.cy : 0;

  best_dist_.assign(kf2.size(), 256);
  best_index_.assign(kf2.size(), -1);
  stamp_.assign(kf2.size(), -1);
  constexpr double kMinDepth = 0.2;  // m
  const double max_depth = 2000.0 * g.baseline_m;

  for (std::size_t i1 = 0; i1 < kf1.size(); ++i1) {
    if (kf1.map_point(i1)) continue;
    const cv::KeyPoint& kp1 = kf1.keypoints[i1];
    const bool stereo1 = kf1.u_right[i1] >= 0;
    const float s1 = g.scale_factors[static_cast<std::size_t>(kp1.octave)];
    double z_near = kMinDepth, z_far = max_depth;
    if (stereo1) {
      const double disparity = kp1.pt.x - kf1.u_right[i1];
      z_near = g.bf / (disparity + 2.0 * s1);
      z_far = disparity - 2.0 * s1 > 0.5 ? g.bf / (disparity - 2.0 * s1) : max_depth;
    }
    // The ray's ends in camera 2, clipped to positive depth.
    const Eigen::Vector3d ray1 = cam.unproject({kp1.pt.x, kp1.pt.y}, 1.0);
    Eigen::Vector3d a = T_c2_c1 * (ray1 * z_near), b = T_c2_c1 * (ray1 * z_far);
    constexpr double kMinZ = 0.1;
    if (a.z() < kMinZ && b.z() < kMinZ) continue;
    if (a.z() < kMinZ) a = a + (b - a) * ((kMinZ - a.z()) / (b.z() - a.z()));
    if (b.z() < kMinZ) b = b + (a - b) * ((kMinZ - b.z()) / (a.z() - b.z()));
    Eigen::Vector2d ua(cam.fx * a.x() / a.z() + cam.cx, cam.fy * a.y() / a.z() + cam.cy);
    Eigen::Vector2d ub(cam.fx * b.x() / b.z() + cam.cx, cam.fy * b.y() / b.z() + cam.cy);
    // Clip the segment to the image (Liang-Barsky).
    {
      double t0 = 0, t1 = 1;
      const Eigen::Vector2d d = ub - ua;
      const double lo[2] = {0, 0}, hi[2] = {static_cast<double>(cam.width - 1), static_cast<double>(cam.height - 1)};
      bool visible = true;
      for (int k = 0; k < 2 && visible; ++k) {
        if (std::fabs(d[k]) < 1e-12) {
          if (ua[k] < lo[k] || ua[k] > hi[k]) visible = false;
          continue;
        }
        double ta = (lo[k] - ua[k]) / d[k], tb = (hi[k] - ua[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) visible = false;
      }
      if (!visible) continue;
      const Eigen::Vector2d a2 = ua + t0 * d, b2 = ua + t1 * d;
      ua = a2;
      ub = b2;
    }
    // Line in image 2 (from F12) for the distance test.
    const double la = kp1.pt.x * F12(0, 0) + kp1.pt.y * F12(1, 0) + F12(2, 0);
    const double lb = kp1.pt.x * F12(0, 1) + kp1.pt.y * F12(1, 1) + F12(2, 1);
    const double lc = kp1.pt.x * F12(0, 2) + kp1.pt.y * F12(1, 2) + F12(2, 2);
    const double line_den = la * la + lb * lb;
    if (line_den < 1e-20) continue;

    // Walk the segment in steps of the band radius.
    const float band = 4.0f * s1;
    const double len = (ub - ua).norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(len / band)));
    const uint8_t* d1 = kf1.descriptor(i1);
    int best = 256, best_i2 = -1;
    for (int s = 0; s <= steps; ++s) {
      const Eigen::Vector2d p = ua + (ub - ua) * (static_cast<double>(s) / steps);
      kf2.grid.features_in_area(kf2.keypoints, g, static_cast<float>(p.x()), static_cast<float>(p.y()), band,
                                std::max(0, kp1.octave - 2), kp1.octave + 2, candidates_);
      for (const int j : candidates_) {
        const std::size_t sj = static_cast<std::size_t>(j);
        if (stamp_[sj] == static_cast<int>(i1)) continue;
        stamp_[sj] = static_cast<int>(i1);
        if (kf2.map_point(sj)) continue;
        const cv::KeyPoint& kp2 = kf2.keypoints[sj];
        const int d = hamming_distance(d1, kf2.descriptor(sj));
        if (d > kMatchThresholdLow || d >= best) continue;
        const bool stereo2 = kf2.u_right[sj] >= 0;
        const float sigma2 = g.level_sigma2[static_cast<std::size_t>(kp2.octave)];
        if (!stereo1 && !stereo2 && epipole_valid) {
          const double dx = ex - kp2.pt.x, dy = ey - kp2.pt.y;
          if (dx * dx + dy * dy < 100.0 * g.scale_factors[static_cast<std::size_t>(kp2.octave)]) continue;
        }
        const double num = la * kp2.pt.x + lb * kp2.pt.y + lc;
        if (num * num / line_den >= 3.84 * sigma2) continue;
        best = d;
        best_i2 = j;
      }
    }
    if (best_i2 < 0) continue;
    const std::size_t s2 = static_cast<std::size_t>(best_i2);
    if (best < best_dist_[s2]) {
      best_dist_[s2] = best;
      best_index_[s2] = static_cast<int>(i1);
    }
  }
  reset_rotation_histogram();
  std::vector<int>& pair_of_2 = best_index_;
  for (std::size_t i2 = 0; i2 < kf2.size(); ++i2) {
    if (pair_of_2[i2] < 0) continue;
    add_to_histogram(
        angle_diff_deg(kf1.keypoints[static_cast<std::size_t>(pair_of_2[i2])].angle, kf2.keypoints[i2].angle),
        static_cast<int>(i2));
  }
  rotation_outliers(rejected_);
  for (const int i2 : rejected_) pair_of_2[static_cast<std::size_t>(i2)] = -1;
  for (std::size_t i2 = 0; i2 < kf2.size(); ++i2) {
    if (pair_of_2[i2] >= 0) out.emplace_back(pair_of_2[i2], static_cast<int>(i2));
  }
  return static_cast<int>(out.size());
}

int Matcher::fuse(KeyFrame& kf, const std::vector<MapPointPtr>& points, float radius_factor, Map& map) {
  const FrameGeometry& g = *kf.geometry;
  const SE3d& T_c_w = kf.T_c_w();
  const Eigen::Vector3d center = kf.center_w();
  constexpr double kChi2Mono = 5.99, kChi2Stereo = 7.8;
  int fused = 0;
  for (const MapPointPtr& point : points) {
    if (!point || point->bad() || point->is_in(&kf)) continue;
    const Eigen::Vector3d p_c = T_c_w * point->p_w;
    if (p_c.z() <= 0) continue;
    const double inv_z = 1.0 / p_c.z();
    const double u = g.camera.fx * p_c.x() * inv_z + g.camera.cx;
    const double v = g.camera.fy * p_c.y() * inv_z + g.camera.cy;
    if (!g.in_image(u, v)) continue;
    const double ur = u - g.bf * inv_z;
    const Eigen::Vector3d po = point->p_w - center;
    const double dist = po.norm();
    if (dist < point->min_invariance_distance() || dist > point->max_invariance_distance()) continue;
    if (po.dot(point->normal_w) < 0.5 * dist) continue;
    const int level = point->predict_scale_level(dist, g);
    const float radius = radius_factor * g.scale_factors[static_cast<std::size_t>(level)];
    kf.grid.features_in_area(kf.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius, 0, -1, candidates_);
    int best_dist = 256, best = -1;
    for (const int j : candidates_) {
      const std::size_t sj = static_cast<std::size_t>(j);
      const cv::KeyPoint& kp = kf.keypoints[sj];
      if (kp.octave < level - 1 || kp.octave > level) continue;
      const double ex = u - kp.pt.x, ey = v - kp.pt.y;
      const float inv_sigma2 = g.inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
      if (kf.u_right[sj] >= 0) {
        const double er = ur - kf.u_right[sj];
        if ((ex * ex + ey * ey + er * er) * inv_sigma2 > kChi2Stereo) continue;
      } else if ((ex * ex + ey * ey) * inv_sigma2 > kChi2Mono) {
        continue;
      }
      const int d = hamming_distance(point->descriptor.data(), kf.descriptor(sj));
      if (d < best_dist) {
        best_dist = d;
        best = j;
      }
    }
    if (best < 0 || best_dist > kMatchThresholdLow) continue;
    const std::size_t sb = static_cast<std::size_t>(best);
    const MapPointPtr existing = kf.map_point(sb);
    if (existing) {
      if (!existing->bad()) {
        if (existing->observation_count() > point->observation_count()) {
          point->replace(existing, map);
        } else {
          existing->replace(point, map);
        }
      }
    } else if (!kf.keypoint_retired(sb)) {  // a retired keypoint saw an object that has moved
      point->add_observation(&kf, best);
      kf.add_map_point(point, sb);
    } else {
      continue;
    }
    ++fused;
  }
  return fused;
}

int Matcher::search_by_bow(const KeyFrame& kf, const Frame& frame, float ratio, std::vector<MapPointPtr>& matches) {
  matches.assign(frame.size(), nullptr);
  reset_rotation_histogram();
  int n = 0;
  place::for_each_common_node(
      kf.bow.features, frame.bow_features,
      [&](place::NodeId, const uint32_t* a0, const uint32_t* a1, const uint32_t* b0, const uint32_t* b1) {
        for (const uint32_t* ia = a0; ia != a1; ++ia) {
          const std::size_t i = *ia;
          const MapPointPtr& point = kf.map_point(i);
          if (!point || point->bad()) continue;
          const uint8_t* d1 = kf.descriptor(i);
          int best = 256, second = 256, best_j = -1;
          for (const uint32_t* ib = b0; ib != b1; ++ib) {
            if (matches[*ib]) continue;
            const int d = hamming_distance(d1, frame.descriptor(*ib));
            if (d < best) {
              second = best;
              best = d;
              best_j = static_cast<int>(*ib);
            } else if (d < second) {
              second = d;
            }
          }
          if (best_j < 0 || best > kMatchThresholdLow ||
              static_cast<float>(best) >= ratio * static_cast<float>(second)) {
            continue;
          }
          matches[static_cast<std::size_t>(best_j)] = point;
          add_to_histogram(
              angle_diff_deg(kf.keypoints[i].angle, frame.keypoints[static_cast<std::size_t>(best_j)].angle), best_j);
          ++n;
        }
      });
  n -= drop_rotation_outliers(matches);
  return n;
}

int Matcher::search_by_bow(const KeyFrame& kf1, const KeyFrame& kf2, float ratio, std::vector<MapPointPtr>& matches12) {
  matches12.assign(kf1.size(), nullptr);
  taken_.assign(kf2.size(), 0);
  reset_rotation_histogram();
  int n = 0;
  place::for_each_common_node(
      kf1.bow.features, kf2.bow.features,
      [&](place::NodeId, const uint32_t* a0, const uint32_t* a1, const uint32_t* b0, const uint32_t* b1) {
        for (const uint32_t* ia = a0; ia != a1; ++ia) {
          const std::size_t i1 = *ia;
          const MapPointPtr& p1 = kf1.map_point(i1);
          if (!p1 || p1->bad()) continue;
          const uint8_t* d1 = kf1.descriptor(i1);
          int best = 256, second = 256, best_i2 = -1;
          for (const uint32_t* ib = b0; ib != b1; ++ib) {
            const std::size_t i2 = *ib;
            const MapPointPtr& p2 = kf2.map_point(i2);
            if (taken_[i2] || !p2 || p2->bad()) continue;
            const int d = hamming_distance(d1, kf2.descriptor(i2));
            if (d < best) {
              second = best;
              best = d;
              best_i2 = static_cast<int>(i2);
            } else if (d < second) {
              second = d;
            }
          }
          if (best_i2 < 0 || best > kMatchThresholdLow ||
              static_cast<float>(best) >= ratio * static_cast<float>(second)) {
            continue;
          }
          const std::size_t s2 = static_cast<std::size_t>(best_i2);
          matches12[i1] = kf2.map_point(s2);
          taken_[s2] = 1;
          add_to_histogram(angle_diff_deg(kf1.keypoints[i1].angle, kf2.keypoints[s2].angle), static_cast<int>(i1));
          ++n;
        }
      });
  n -= drop_rotation_outliers(matches12);
  return n;
}

int Matcher::search_keyframe_projection(Frame& frame, const KeyFrame& kf, float radius_px, int max_distance) {
  const FrameGeometry& g = *frame.geometry;
  const SE3d& T_c_w = frame.T_c_w();
  const Eigen::Vector3d center = frame.center_w();
  std::unordered_set<const MapPoint*> found;
  for (const MapPointPtr& p : frame.map_points) {
    if (p) found.insert(p.get());
  }
  reset_rotation_histogram();
  int n = 0;
  for (std::size_t i = 0; i < kf.size(); ++i) {
    const MapPointPtr& point = kf.map_point(i);
    if (!point || point->bad() || found.count(point.get())) continue;
    const Eigen::Vector3d p_c = T_c_w * point->p_w;
    if (p_c.z() <= 0) continue;
    const double inv_z = 1.0 / p_c.z();
    const double u = g.camera.fx * p_c.x() * inv_z + g.camera.cx;
    const double v = g.camera.fy * p_c.y() * inv_z + g.camera.cy;
    if (!g.in_image(u, v)) continue;
    const double dist = (point->p_w - center).norm();
    if (dist < point->min_invariance_distance() || dist > point->max_invariance_distance()) continue;
    const int level = point->predict_scale_level(dist, g);
    const float radius = radius_px * g.scale_factors[static_cast<std::size_t>(level)];
    frame.grid.features_in_area(frame.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius,
                                std::max(0, level - 1), level + 1, candidates_);
    const auto [best, best_j] = nearest_candidate(point->descriptor.data(), frame, candidates_, -1,
                                                  [&](std::size_t j) { return frame.map_points[j] != nullptr; });
    if (best_j < 0 || best > max_distance) continue;
    frame.map_points[static_cast<std::size_t>(best_j)] = point;
    found.insert(point.get());
    add_to_histogram(angle_diff_deg(kf.keypoints[i].angle, frame.keypoints[static_cast<std::size_t>(best_j)].angle),
                     best_j);
    ++n;
  }
  n -= drop_rotation_outliers(frame.map_points);
  return n;
}

namespace {

// Projection of a world point into a keyframe-sized image with pose T_c_w, with ORB-SLAM2's distance-range and
// viewing-angle checks; false when it does not qualify.
bool project_checked(const FrameGeometry& g, const SE3d& T_c_w, const Eigen::Vector3d& center_w, const MapPoint& point,
                     double& u, double& v, int& level) {
  const Eigen::Vector3d p_c = T_c_w * point.p_w;
  if (p_c.z() <= 0) return false;
  const double inv_z = 1.0 / p_c.z();
  u = g.camera.fx * p_c.x() * inv_z + g.camera.cx;
  v = g.camera.fy * p_c.y() * inv_z + g.camera.cy;
  if (!g.in_image(u, v)) return false;
  const Eigen::Vector3d po = point.p_w - center_w;
  const double dist = po.norm();
  if (dist < point.min_invariance_distance() || dist > point.max_invariance_distance()) return false;
  if (po.dot(point.normal_w) < 0.5 * dist) return false;
  level = point.predict_scale_level(dist, g);
  return true;
}

}  // namespace

int Matcher::search_loop_projection(const KeyFrame& kf, const SE3d& T_c_w, const std::vector<MapPointPtr>& points,
                                    float radius_px, std::vector<MapPointPtr>& matched) {
  const FrameGeometry& g = *kf.geometry;
  const Eigen::Vector3d center = T_c_w.inverse().translation();
  std::unordered_set<const MapPoint*> already;
  for (const MapPointPtr& p : matched) {
    if (p) already.insert(p.get());
  }
  int n = 0;
  for (const MapPointPtr& point : points) {
    if (!point || point->bad() || already.count(point.get())) continue;
    double u = 0, v = 0;
    int level = 0;
    if (!project_checked(g, T_c_w, center, *point, u, v, level)) continue;
    const float radius = radius_px * g.scale_factors[static_cast<std::size_t>(level)];
    kf.grid.features_in_area(kf.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius, 0, -1, candidates_);
    const auto [best, best_j] = nearest_candidate(point->descriptor.data(), kf, candidates_, level,
                                                  [&](std::size_t j) { return matched[j] != nullptr; });
    if (best_j < 0 || best > kMatchThresholdLow) continue;
    matched[static_cast<std::size_t>(best_j)] = point;
    already.insert(point.get());
    ++n;
  }
  return n;
}

int Matcher::search_by_se3(const KeyFrame& kf1, const KeyFrame& kf2, const SE3d& T_c1_c2, float radius_px,
                           std::vector<MapPointPtr>& matches12) {
  const FrameGeometry& g = *kf1.geometry;
  const SE3d T_c2_c1 = T_c1_c2.inverse();
  const std::size_t n1 = kf1.size(), n2 = kf2.size();
  std::vector<uint8_t> matched2(n2, 0);
  for (std::size_t i1 = 0; i1 < n1; ++i1) {
    const MapPointPtr& p = matches12[i1];
    if (!p) continue;
    const int i2 = p->index_in(&kf2);
    if (i2 >= 0) matched2[static_cast<std::size_t>(i2)] = 1;
  }
  // One direction: points of `from` (camera-frame positions through T_from_w), projected into `to` with T_to_from.
  auto search = [&](const KeyFrame& from, const KeyFrame& to, const SE3d& T_to_from, const auto& skip,
                    std::vector<int>& match) {
    match.assign(from.size(), -1);
    const SE3d T_from_w = from.T_c_w();
    for (std::size_t i = 0; i < from.size(); ++i) {
      const MapPointPtr& point = from.map_point(i);
      if (!point || point->bad() || skip(i)) continue;
      const Eigen::Vector3d p_to = T_to_from * (T_from_w * point->p_w);
      if (p_to.z() <= 0) continue;
      const double u = g.camera.fx * p_to.x() / p_to.z() + g.camera.cx;
      const double v = g.camera.fy * p_to.y() / p_to.z() + g.camera.cy;
      if (!g.in_image(u, v)) continue;
      const double dist = p_to.norm();
      if (dist < point->min_invariance_distance() || dist > point->max_invariance_distance()) continue;
      const int level = point->predict_scale_level(dist, g);
      const float radius = radius_px * g.scale_factors[static_cast<std::size_t>(level)];
      to.grid.features_in_area(to.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius, 0, -1,
                               candidates_);
      const auto [best, best_j] = nearest_candidate(point->descriptor.data(), to, candidates_, level, kSkipNone);
      if (best_j >= 0 && best <= kMatchThresholdHigh) match[i] = best_j;
    }
  };
  std::vector<int> match1, match2;
  search(
      kf1, kf2, T_c2_c1, [&](std::size_t i1) { return matches12[i1] != nullptr; }, match1);
  search(
      kf2, kf1, T_c1_c2, [&](std::size_t i2) { return matched2[i2] != 0; }, match2);
  int n = 0;
  for (std::size_t i1 = 0; i1 < n1; ++i1) {
    const int i2 = match1[i1];
    if (i2 < 0 || match2[static_cast<std::size_t>(i2)] != static_cast<int>(i1)) continue;
    const MapPointPtr& p2 = kf2.map_point(static_cast<std::size_t>(i2));
    if (!p2 || p2->bad()) continue;
    matches12[i1] = p2;
    ++n;
  }
  return n;
}

int Matcher::fuse_with_pose(KeyFrame& kf, const SE3d& T_c_w, const std::vector<MapPointPtr>& points, float radius_px,
                            std::vector<MapPointPtr>& replace) {
  const FrameGeometry& g = *kf.geometry;
  const Eigen::Vector3d center = T_c_w.inverse().translation();
  replace.assign(points.size(), nullptr);
  int fused = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const MapPointPtr& point = points[k];
    if (!point || point->bad() || point->is_in(&kf)) continue;
    double u = 0, v = 0;
    int level = 0;
    if (!project_checked(g, T_c_w, center, *point, u, v, level)) continue;
    const float radius = radius_px * g.scale_factors[static_cast<std::size_t>(level)];
    kf.grid.features_in_area(kf.keypoints, g, static_cast<float>(u), static_cast<float>(v), radius, 0, -1, candidates_);
    const auto [best, best_j] = nearest_candidate(point->descriptor.data(), kf, candidates_, level, kSkipNone);
    if (best_j < 0 || best > kMatchThresholdLow) continue;
    const std::size_t sb = static_cast<std::size_t>(best_j);
    const MapPointPtr& existing = kf.map_point(sb);
    if (existing) {
      if (!existing->bad()) replace[k] = existing;
    } else if (kf.keypoint_retired(sb)) {
      continue;
    } else {
      point->add_observation(&kf, best_j);
      kf.add_map_point(point, sb);
    }
    ++fused;
  }
  return fused;
}

int Matcher::search_for_triangulation_bow(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F12,
                                          std::vector<std::pair<int, int>>& out) {
  out.clear();
  const FrameGeometry& g = *kf1.geometry;
  const PinholeCamera& cam = g.camera;
  const Eigen::Vector3d c1_in_2 = kf2.T_c_w() * kf1.center_w();
  const bool epipole_valid = c1_in_2.z() > 1e-6;
  const double ex = epipole_valid ? cam.fx * c1_in_2.x() / c1_in_2.z() + cam.cx : 0;
  const double ey = epipole_valid ? cam.fy * c1_in_2.y() / c1_in_2.z() + cam.cy : 0;
  taken_.assign(kf2.size(), 0);
  best_index_.assign(kf1.size(), -1);
  reset_rotation_histogram();
  place::for_each_common_node(
      kf1.bow.features, kf2.bow.features,
      [&](place::NodeId, const uint32_t* a0, const uint32_t* a1, const uint32_t* b0, const uint32_t* b1) {
        for (const uint32_t* ia = a0; ia != a1; ++ia) {
          const std::size_t i1 = *ia;
          if (kf1.map_point(i1)) continue;
          const cv::KeyPoint& kp1 = kf1.keypoints[i1];
          const bool stereo1 = kf1.u_right[i1] >= 0;
          const double la = kp1.pt.x * F12(0, 0) + kp1.pt.y * F12(1, 0) + F12(2, 0);
          const double lb = kp1.pt.x * F12(0, 1) + kp1.pt.y * F12(1, 1) + F12(2, 1);
          const double lc = kp1.pt.x * F12(0, 2) + kp1.pt.y * F12(1, 2) + F12(2, 2);
          const double line_den = la * la + lb * lb;
          if (line_den < 1e-20) continue;
          const uint8_t* d1 = kf1.descriptor(i1);
          int best = kMatchThresholdLow, best_i2 = -1;
          for (const uint32_t* ib = b0; ib != b1; ++ib) {
            const std::size_t i2 = *ib;
            if (taken_[i2] || kf2.map_point(i2)) continue;
            const int d = hamming_distance(d1, kf2.descriptor(i2));
            if (d > best) continue;
            const cv::KeyPoint& kp2 = kf2.keypoints[i2];
            const bool stereo2 = kf2.u_right[i2] >= 0;
            if (!stereo1 && !stereo2 && epipole_valid) {
              const double dx = ex - kp2.pt.x, dy = ey - kp2.pt.y;
              if (dx * dx + dy * dy < 100.0 * g.scale_factors[static_cast<std::size_t>(kp2.octave)]) continue;
            }
            const double num = la * kp2.pt.x + lb * kp2.pt.y + lc;
            if (num * num / line_den >= 3.84 * g.level_sigma2[static_cast<std::size_t>(kp2.octave)]) continue;
            best = d;
            best_i2 = static_cast<int>(i2);
          }
          if (best_i2 < 0) continue;
          taken_[static_cast<std::size_t>(best_i2)] = 1;
          best_index_[i1] = best_i2;
          add_to_histogram(angle_diff_deg(kp1.angle, kf2.keypoints[static_cast<std::size_t>(best_i2)].angle),
                           static_cast<int>(i1));
        }
      });
  rotation_outliers(rejected_);
  for (const int i1 : rejected_) best_index_[static_cast<std::size_t>(i1)] = -1;
  for (std::size_t i1 = 0; i1 < kf1.size(); ++i1) {
    if (best_index_[i1] >= 0) out.emplace_back(static_cast<int>(i1), best_index_[i1]);
  }
  return static_cast<int>(out.size());
}

}  // namespace agvslam::slam
