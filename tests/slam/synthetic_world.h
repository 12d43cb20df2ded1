#pragma once
// Synthetic stereo observations for the slam unit tests: random world points seen by cameras on a path, projected
// into keypoints with a chosen pixel noise, with random (but per-point consistent) descriptors.

#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/slam/frame.h"

namespace agvslam::slam::test {

inline PinholeCamera test_camera() {
  PinholeCamera cam;
  cam.fx = cam.fy = 460;
  cam.cx = 376;
  cam.cy = 240;
  cam.width = 752;
  cam.height = 480;
  return cam;
}

inline FrameGeometryPtr test_geometry() {
  return std::make_shared<const FrameGeometry>(FrameGeometry::make(test_camera(), 0.12, 40, 8, 1.2));
}

struct World {
  std::vector<Eigen::Vector3d> points_w;
  std::vector<Descriptor> descriptors;
};

// Points in a box in front of the origin camera (z forward).
inline World make_world(int n, uint32_t seed, double min_z = 1.5, double max_z = 12.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-6, 6), uy(-2.5, 2.5), uz(min_z, max_z);
  std::uniform_int_distribution<int> ub(0, 255);
  World w;
  for (int i = 0; i < n; ++i) {
    w.points_w.emplace_back(ux(rng), uy(rng), uz(rng));
    Descriptor d;
    for (auto& b : d) b = static_cast<uint8_t>(ub(rng));
    w.descriptors.push_back(d);
  }
  return w;
}

// A frame of `world` seen from T_c_w: every visible point becomes a keypoint (level 0), with stereo when the
// disparity is positive. point_of_keypoint maps keypoint -> world point index.
inline void make_frame(const World& world, const SE3d& T_c_w, const FrameGeometryPtr& g, uint64_t id, double noise_px,
                       uint32_t seed, Frame& frame, std::vector<int>& point_of_keypoint) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<cv::KeyPoint> kps;
  std::vector<float> u_right, depth;
  std::vector<Descriptor> descs;
  point_of_keypoint.clear();
  for (std::size_t i = 0; i < world.points_w.size(); ++i) {
    const Eigen::Vector3d p_c = T_c_w * world.points_w[i];
    if (p_c.z() < 0.5) continue;
    const Eigen::Vector2d uv = g->camera.project(p_c);
    if (!g->in_image(uv.x(), uv.y())) continue;
    const double u = uv.x() + noise(rng), v = uv.y() + noise(rng);
    if (!g->in_image(u, v)) continue;
    cv::KeyPoint kp(static_cast<float>(u), static_cast<float>(v), 31.f, 0.f, 1.f, 0);
    kps.push_back(kp);
    const double ur = uv.x() - g->bf / p_c.z() + noise(rng);
    const bool stereo = ur >= 0 && u - ur > 0.5;
    u_right.push_back(stereo ? static_cast<float>(ur) : -1.f);
    depth.push_back(stereo ? static_cast<float>(g->bf / (u - ur)) : -1.f);
    descs.push_back(world.descriptors[i]);
    point_of_keypoint.push_back(static_cast<int>(i));
  }
  cv::Mat d(static_cast<int>(descs.size()), 32, CV_8UC1);
  for (std::size_t k = 0; k < descs.size(); ++k)
    std::copy(descs[k].begin(), descs[k].end(), d.ptr<uint8_t>(static_cast<int>(k)));
  frame.assign(id, static_cast<int64_t>(id) * 50'000'000, g, kps, d, u_right, depth);
  frame.set_pose(T_c_w);
}

// Camera k of a path moving forward (z) and sideways with a slight yaw: T_c_w.
inline SE3d path_pose(int k, double step_m = 0.15) {
  const double yaw = 0.02 * k;
  const Eigen::Matrix3d R_w_c = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d t_w_c(0.05 * k, 0.0, step_m * k);
  return make_se3(R_w_c, t_w_c).inverse();
}

}  // namespace agvslam::slam::test
