#pragma once
// One tracked stereo frame: the left image's ORB keypoints with stereo depth, a grid for searches by area, and
// the association of keypoints with map points (ORB-SLAM2's Frame, stereo only).
//
// Coordinates: keypoints in level-0 pixels of the rectified left image; T_c_w maps world points into the left
// camera (c); the world frame is the left camera of the first keyframe.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/place/bow_vector.h"

namespace agvslam::place {
class Vocabulary;
}

namespace agvslam::slam {

class MapPoint;
class KeyFrame;
using MapPointPtr = std::shared_ptr<MapPoint>;
using KeyFramePtr = std::shared_ptr<KeyFrame>;

// Camera, baseline and ORB pyramid scales shared by all frames and keyframes of one map.
struct FrameGeometry {
  PinholeCamera camera;  // rectified left camera (the right one shares it, shifted by baseline_m along x)
  double baseline_m = 0;
  double bf = 0;             // fx * baseline_m (px m)
  double close_depth_m = 0;  // close/far threshold (ORB-SLAM2's ThDepth)
  int n_levels = 8;
  float scale_factor = 1.2f;
  float log_scale_factor = 0;
  std::vector<float> scale_factors, inv_scale_factors, level_sigma2, inv_level_sigma2;

  static constexpr int kGridCols = 64;
  static constexpr int kGridRows = 48;
  float grid_inv_cell_w = 0, grid_inv_cell_h = 0;

  // Fills the scale tables from (n_levels, scale_factor) and the grid from the camera size.
  static FrameGeometry make(const PinholeCamera& camera, double baseline_m, double close_depth_baselines, int n_levels,
                            double scale_factor);
  // ORB-SLAM2's PredictScale: the pyramid level at which a point seen at distance_m appears, given the largest
  // distance max_distance_m at which it is still seen at level 0 ... n_levels-1.
  int predict_scale_level(double distance_m, double max_distance_m) const;
  bool in_image(double u, double v) const { return u >= 0 && v >= 0 && u < camera.width && v < camera.height; }
};
using FrameGeometryPtr = std::shared_ptr<const FrameGeometry>;

// Keypoint indices bucketed into FrameGeometry::kGridCols x kGridRows cells (CSR layout, rebuilt in place).
class FeatureGrid {
 public:
  void build(const std::vector<cv::KeyPoint>& keypoints, const FrameGeometry& geometry);
  // Indices of keypoints within the square of half-size radius_px around (x, y) whose level is in
  // [min_level, max_level] (max_level < 0: any level >= min_level). Appends nothing when none; clears out first.
  void features_in_area(const std::vector<cv::KeyPoint>& keypoints, const FrameGeometry& geometry, float x, float y,
                        float radius_px, int min_level, int max_level, std::vector<int>& out) const;

 private:
  std::vector<int> cell_start_;  // (cols * rows + 1)
  std::vector<int> indices_;
  std::vector<int> cell_of_, fill_;  // scratch
};

using Descriptor = std::array<uint8_t, 32>;

// Hamming distance of two 32-byte ORB descriptors.
inline int hamming_distance(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int k = 0; k < 4; ++k) {
    uint64_t x, y;
    __builtin_memcpy(&x, a + 8 * k, 8);
    __builtin_memcpy(&y, b + 8 * k, 8);
    d += __builtin_popcountll(x ^ y);
  }
  return d;
}

class Frame {
 public:
  uint64_t id = 0;
  int64_t t_ns = 0;
  FrameGeometryPtr geometry;

  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;         // N x 32, CV_8UC1
  std::vector<float> u_right;  // x of the right-image match, -1 = none
  std::vector<float> depth;    // m, -1 = none
  FeatureGrid grid;

  std::vector<MapPointPtr> map_points;  // per keypoint, null = none
  std::vector<uint8_t> outlier;         // per keypoint, set by the motion-only BA

  KeyFramePtr reference_keyframe;

  // Bag of words of the descriptors (computed on demand: reference-keyframe matching, relocalisation; a keyframe
  // made from the frame takes them over). has_bow is reset by assign().
  place::BowVector bow;
  place::FeatureVector bow_features;  // direct index (vocabulary nodes -> keypoint indices)
  uint64_t bow_vocabulary_id = 0;     // identity of the vocabulary that computed them
  bool has_bow = false;
  void compute_bow(const place::Vocabulary& vocabulary, int direct_index_level);

  // Copies the features (reusing this frame's buffers), clears associations, builds the grid.
  void assign(uint64_t frame_id, int64_t time_ns, const FrameGeometryPtr& geom, const std::vector<cv::KeyPoint>& kps,
              const cv::Mat& descs, const std::vector<float>& u_right_px, const std::vector<float>& depth_m);

  std::size_t size() const { return keypoints.size(); }
  const uint8_t* descriptor(std::size_t i) const { return descriptors.ptr<uint8_t>(static_cast<int>(i)); }
  bool has_depth(std::size_t i) const { return depth[i] > 0; }
  bool is_close(std::size_t i) const { return depth[i] > 0 && depth[i] < geometry->close_depth_m; }

  void set_pose(const SE3d& T_c_w);
  bool has_pose() const { return has_pose_; }
  const SE3d& T_c_w() const { return T_c_w_; }
  const SE3d& T_w_c() const { return T_w_c_; }
  Eigen::Vector3d center_w() const { return T_w_c_.translation(); }

  // World point of keypoint i from its stereo depth (requires has_depth(i) and a pose).
  Eigen::Vector3d unproject_stereo(std::size_t i) const;

  // ORB-SLAM2's isInFrustum: projects the point, checks depth, image bounds, the scale-invariance distance range
  // and the viewing angle (cos >= viewing_cos_limit); on success fills the point's tracking scratch (projection,
  // predicted level, viewing cosine) and returns true.
  bool is_in_frustum(MapPoint& point, double viewing_cos_limit) const;

  // Number of keypoints with an associated, non-outlier map point.
  int tracked_count() const;

 private:
  SE3d T_c_w_ = SE3d::Identity();
  SE3d T_w_c_ = SE3d::Identity();
  bool has_pose_ = false;
};

}  // namespace agvslam::slam
