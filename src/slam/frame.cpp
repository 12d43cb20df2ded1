#include "agvslam/slam/frame.h"

#include <algorithm>
#include <cmath>

#include "agvslam/place/vocabulary.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

FrameGeometry FrameGeometry::make(const PinholeCamera& cam, double baseline, double close_depth_baselines, int levels,
                                  double scale) {
  FrameGeometry g;
  g.camera = cam;
  g.baseline_m = baseline;
  g.bf = cam.fx * baseline;
  g.close_depth_m = close_depth_baselines * baseline;
  g.n_levels = levels;
  g.scale_factor = static_cast<float>(scale);
  g.log_scale_factor = static_cast<float>(std::log(scale));
  g.scale_factors.resize(static_cast<std::size_t>(levels));
  g.inv_scale_factors.resize(g.scale_factors.size());
  g.level_sigma2.resize(g.scale_factors.size());
  g.inv_level_sigma2.resize(g.scale_factors.size());
  double s = 1.0;
  for (std::size_t l = 0; l < g.scale_factors.size(); ++l) {
    g.scale_factors[l] = static_cast<float>(s);
    g.inv_scale_factors[l] = static_cast<float>(1.0 / s);
    g.level_sigma2[l] = static_cast<float>(s * s);
    g.inv_level_sigma2[l] = static_cast<float>(1.0 / (s * s));
    s *= scale;
  }
  g.grid_inv_cell_w = static_cast<float>(kGridCols) / static_cast<float>(std::max(1, cam.width));
  g.grid_inv_cell_h = static_cast<float>(kGridRows) / static_cast<float>(std::max(1, cam.height));
  return g;
}

int FrameGeometry::predict_scale_level(double distance_m, double max_distance_m) const {
  if (distance_m <= 0) return n_levels - 1;
  const double ratio = max_distance_m / distance_m;
  int level = static_cast<int>(std::ceil(std::log(ratio) / static_cast<double>(log_scale_factor)));
  return std::clamp(level, 0, n_levels - 1);
}

void FeatureGrid::build(const std::vector<cv::KeyPoint>& keypoints, const FrameGeometry& g) {
  constexpr int kCells = FrameGeometry::kGridCols * FrameGeometry::kGridRows;
  cell_start_.assign(kCells + 1, 0);
  cell_of_.resize(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int cx = std::clamp(static_cast<int>(keypoints[i].pt.x * g.grid_inv_cell_w), 0, FrameGeometry::kGridCols - 1);
    const int cy = std::clamp(static_cast<int>(keypoints[i].pt.y * g.grid_inv_cell_h), 0, FrameGeometry::kGridRows - 1);
    const int c = cy * FrameGeometry::kGridCols + cx;
    cell_of_[i] = c;
    ++cell_start_[static_cast<std::size_t>(c) + 1];
  }
  for (int c = 0; c < kCells; ++c)
    cell_start_[static_cast<std::size_t>(c) + 1] += cell_start_[static_cast<std::size_t>(c)];
  indices_.resize(keypoints.size());
  fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const std::size_t c = static_cast<std::size_t>(cell_of_[i]);
    indices_[static_cast<std::size_t>(fill_[c]++)] = static_cast<int>(i);
  }
}

void FeatureGrid::features_in_area(const std::vector<cv::KeyPoint>& keypoints, const FrameGeometry& g, float x, float y,
                                   float r, int min_level, int max_level, std::vector<int>& out) const {
  out.clear();
  if (cell_start_.empty()) return;
  const int min_cx = std::max(0, static_cast<int>(std::floor((x - r) * g.grid_inv_cell_w)));
  const int max_cx = std::min(FrameGeometry::kGridCols - 1, static_cast<int>(std::ceil((x + r) * g.grid_inv_cell_w)));
  const int min_cy = std::max(0, static_cast<int>(std::floor((y - r) * g.grid_inv_cell_h)));
  const int max_cy = std::min(FrameGeometry::kGridRows - 1, static_cast<int>(std::ceil((y + r) * g.grid_inv_cell_h)));
  if (min_cx > max_cx || min_cy > max_cy) return;
  const bool check_levels = min_level > 0 || max_level >= 0;
  for (int cy = min_cy; cy <= max_cy; ++cy) {
    for (int cx = min_cx; cx <= max_cx; ++cx) {
      const std::size_t c = static_cast<std::size_t>(cy * FrameGeometry::kGridCols + cx);
      for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const int i = indices_[static_cast<std::size_t>(k)];
        const cv::KeyPoint& kp = keypoints[static_cast<std::size_t>(i)];
        if (check_levels) {
          if (kp.octave < min_level) continue;
          if (max_level >= 0 && kp.octave > max_level) continue;
        }
        if (std::fabs(kp.pt.x - x) < r && std::fabs(kp.pt.y - y) < r) out.push_back(i);
      }
    }
  }
}

void Frame::assign(uint64_t frame_id, int64_t time_ns, const FrameGeometryPtr& geom,
                   const std::vector<cv::KeyPoint>& kps, const cv::Mat& descs, const std::vector<float>& u_right_px,
                   const std::vector<float>& depth_m) {
  id = frame_id;
  t_ns = time_ns;
  geometry = geom;
  keypoints.assign(kps.begin(), kps.end());
  descs.copyTo(descriptors);
  u_right.assign(u_right_px.begin(), u_right_px.end());
  depth.assign(depth_m.begin(), depth_m.end());
  u_right.resize(keypoints.size(), -1.f);
  depth.resize(keypoints.size(), -1.f);
  map_points.assign(keypoints.size(), nullptr);
  outlier.assign(keypoints.size(), 0);
  reference_keyframe.reset();
  has_bow = false;
  has_pose_ = false;
  grid.build(keypoints, *geometry);
}

void Frame::compute_bow(const place::Vocabulary& vocabulary, int direct_index_level) {
  if (has_bow && bow_vocabulary_id == vocabulary.identity() && bow_features.level == direct_index_level) return;
  vocabulary.transform(descriptors, bow, bow_features, direct_index_level);
  bow_vocabulary_id = vocabulary.identity();
  has_bow = true;
}

void Frame::set_pose(const SE3d& T_c_w) {
  T_c_w_ = T_c_w;
  T_w_c_ = T_c_w.inverse();
  has_pose_ = true;
}

Eigen::Vector3d Frame::unproject_stereo(std::size_t i) const {
  const cv::Point2f& pt = keypoints[i].pt;
  const Eigen::Vector3d p_c = geometry->camera.unproject({pt.x, pt.y}, depth[i]);
  return T_w_c_ * p_c;
}

bool Frame::is_in_frustum(MapPoint& point, double viewing_cos_limit) const {
  point.track.in_view = false;
  const Eigen::Vector3d p_c = T_c_w_ * point.p_w;
  if (p_c.z() <= 0) return false;
  const PinholeCamera& cam = geometry->camera;
  const double inv_z = 1.0 / p_c.z();
  const double u = cam.fx * p_c.x() * inv_z + cam.cx;
  const double v = cam.fy * p_c.y() * inv_z + cam.cy;
  if (!geometry->in_image(u, v)) return false;
  const Eigen::Vector3d po = point.p_w - center_w();
  const double dist = po.norm();
  if (dist < point.min_invariance_distance() || dist > point.max_invariance_distance()) return false;
  const double view_cos = po.dot(point.normal_w) / dist;
  if (view_cos < viewing_cos_limit) return false;
  point.track.in_view = true;
  point.track.proj_x = static_cast<float>(u);
  point.track.proj_y = static_cast<float>(v);
  point.track.proj_x_right = static_cast<float>(u - geometry->bf * inv_z);
  point.track.scale_level = point.predict_scale_level(dist, *geometry);
  point.track.view_cos = static_cast<float>(view_cos);
  return true;
}

int Frame::tracked_count() const {
  int n = 0;
  for (std::size_t i = 0; i < map_points.size(); ++i) {
    if (map_points[i] && !outlier[i]) ++n;
  }
  return n;
}

}  // namespace agvslam::slam
