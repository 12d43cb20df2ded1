#pragma once
// A small ray-cast stereo renderer for end-to-end tests of the dynamic detector: textured rectangles in a
// world frame, a rectified pinhole pair (right camera at +baseline along x), exact depth and object ids.
// World frame = the left camera at frame 0 (x right, y down, z forward).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/core/stereo_frame.h"

namespace agvslam::dynamic::testing {

// Smooth random texture with a given mean and contrast: octaves of cubic-upsampled uniform noise.
inline cv::Mat make_texture(int size, double mean, double contrast, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat acc(size, size, CV_32F, cv::Scalar(0));
  double weight = 1.0, total = 0;
  for (int cell : {32, 8, 3}) {
    cv::Mat coarse(size / cell + 1, size / cell + 1, CV_32F);
    rng.fill(coarse, cv::RNG::UNIFORM, -1.0, 1.0);
    cv::Mat up;
    cv::resize(coarse, up, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
    acc += weight * up;
    total += weight;
    weight *= 0.8;
  }
  cv::Mat out;
  acc.convertTo(out, CV_8U, contrast / total, mean);
  return out;
}

// A textured rectangle: origin + a * u_axis + b * v_axis for a in [0, width_m], b in [0, height_m].
struct TexturedRect {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d u_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d v_axis = Eigen::Vector3d::UnitY();
  double width_m = 1, height_m = 1;
  cv::Mat texture;  // CV_8UC1, repeated
  double metres_per_texel = 0.01;
  int id = 0;  // written to the id image (0 = static background)
};

struct RenderOutput {
  cv::Mat grey;     // CV_8UC1
  cv::Mat depth_m;  // CV_32FC1, 0 = nothing
  cv::Mat id;       // CV_32SC1, -1 = nothing
};

// The CV_8UC1 mask's value at the pixel nearest p: a point tracked to within half a pixel of the right or bottom
// edge rounds onto the next column or row, which is clamped back into the image.
inline uint8_t mask_at(const cv::Mat& mask, const cv::Point2f& p) {
  return mask.at<uint8_t>(std::clamp(cvRound(p.y), 0, mask.rows - 1), std::clamp(cvRound(p.x), 0, mask.cols - 1));
}

inline double sample_bilinear(const cv::Mat& tex, double x, double y) {
  const int w = tex.cols, h = tex.rows;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  auto at = [&](long long xi, long long yi) {
    const int xx = static_cast<int>(((xi % w) + w) % w), yy = static_cast<int>(((yi % h) + h) % h);
    return static_cast<double>(tex.at<uint8_t>(yy, xx));
  };
  const long long x0 = static_cast<long long>(fx), y0 = static_cast<long long>(fy);
  return (1 - ax) * (1 - ay) * at(x0, y0) + ax * (1 - ay) * at(x0 + 1, y0) + (1 - ax) * ay * at(x0, y0 + 1) +
         ax * ay * at(x0 + 1, y0 + 1);
}

inline void render(const std::vector<TexturedRect>& rects, const PinholeCamera& cam, const SE3d& T_w_c,
                   RenderOutput& out) {
  out.grey.create(cam.height, cam.width, CV_8UC1);
  out.depth_m.create(cam.height, cam.width, CV_32FC1);
  out.id.create(cam.height, cam.width, CV_32SC1);
  const Eigen::Matrix3d R = T_w_c.linear();
  const Eigen::Vector3d o = T_w_c.translation();
  std::vector<Eigen::Vector3d> normals;
  for (const auto& r : rects) normals.push_back(r.u_axis.cross(r.v_axis));
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d_c((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d d = R * d_c;
      double best_t = 1e30;
      int best = -1;
      double best_a = 0, best_b = 0;
      for (std::size_t k = 0; k < rects.size(); ++k) {
        const double denom = normals[k].dot(d);
        if (std::abs(denom) < 1e-12) continue;
        const double t = normals[k].dot(rects[k].origin - o) / denom;
        if (t <= 0.05 || t >= best_t) continue;
        const Eigen::Vector3d rel = o + t * d - rects[k].origin;
        const double a = rel.dot(rects[k].u_axis), b = rel.dot(rects[k].v_axis);
        if (a < 0 || b < 0 || a > rects[k].width_m || b > rects[k].height_m) continue;
        best_t = t;
        best = static_cast<int>(k);
        best_a = a;
        best_b = b;
      }
      if (best < 0) {
        out.grey.at<uint8_t>(v, u) = 0;
        out.depth_m.at<float>(v, u) = 0;
        out.id.at<int32_t>(v, u) = -1;
        continue;
      }
      const TexturedRect& r = rects[static_cast<std::size_t>(best)];
      const double g = sample_bilinear(r.texture, best_a / r.metres_per_texel, best_b / r.metres_per_texel);
      out.grey.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(g);
      out.depth_m.at<float>(v, u) = static_cast<float>(best_t);  // t along d with d_c.z = 1 is the depth
      out.id.at<int32_t>(v, u) = r.id;
    }
  }
}

inline void add_noise(cv::Mat& grey, double sigma, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat noise(grey.size(), CV_32F);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat f;
  grey.convertTo(f, CV_32F);
  f += noise;
  f.convertTo(grey, CV_8U);
}

// A static corridor-like scene (back wall, floor, left wall, a pillar) plus one movable box.
struct CorridorScene {
  PinholeCamera camera;
  double baseline_m = 0.12;
  std::vector<TexturedRect> statics;
  TexturedRect box;  // id 1

  CorridorScene() {
    camera.fx = camera.fy = 460.0;
    camera.cx = 375.5;
    camera.cy = 239.5;
    camera.width = 752;
    camera.height = 480;
    const double mpt = 0.01;
    TexturedRect wall;  // z = 8, facing the camera
    wall.origin = {-12, -7, 8};
    wall.u_axis = Eigen::Vector3d::UnitX();
    wall.v_axis = Eigen::Vector3d::UnitY();
    wall.width_m = 24;
    wall.height_m = 7.5;
    wall.texture = make_texture(512, 95, 120, 11);
    wall.metres_per_texel = 2.5 * mpt;
    TexturedRect floor;  // y = 0.5
    floor.origin = {-12, 0.5, 0.2};
    floor.u_axis = Eigen::Vector3d::UnitX();
    floor.v_axis = Eigen::Vector3d::UnitZ();
    floor.width_m = 24;
    floor.height_m = 7.8;
    floor.texture = make_texture(512, 120, 120, 12);
    floor.metres_per_texel = mpt;
    TexturedRect left;  // x = -2.5
    left.origin = {-2.5, -7, 0.2};
    left.u_axis = Eigen::Vector3d::UnitZ();
    left.v_axis = Eigen::Vector3d::UnitY();
    left.width_m = 7.8;
    left.height_m = 7.5;
    left.texture = make_texture(512, 80, 110, 13);
    left.metres_per_texel = 1.5 * mpt;
    TexturedRect pillar;  // z = 5, x in [1.6, 2.4]
    pillar.origin = {1.6, -3, 5};
    pillar.width_m = 0.8;
    pillar.height_m = 3.5;
    pillar.texture = make_texture(256, 60, 100, 14);
    pillar.metres_per_texel = mpt;
    statics = {wall, floor, left, pillar};
    box.origin = {-0.2, -1.1, 3.0};
    box.width_m = 1.0;
    box.height_m = 1.6;
    box.texture = make_texture(256, 175, 110, 15);
    box.metres_per_texel = 0.6 * mpt;
    box.id = 1;
  }

  StereoCalibration calibration() const {
    StereoCalibration c;
    c.left = camera;
    c.baseline_m = baseline_m;
    return c;
  }

  // Renders the pair with the camera at T_w_c and the box moved by box_offset_m; gt_mask: 255 on the box.
  StereoFrame render_frame(const SE3d& T_w_c, const Eigen::Vector3d& box_offset_m, bool include_box, std::size_t index,
                           cv::Mat* gt_mask = nullptr, cv::Mat* gt_disparity_px = nullptr) const {
    std::vector<TexturedRect> rects = statics;
    if (include_box) {
      TexturedRect b = box;
      b.origin += box_offset_m;
      rects.push_back(b);
    }
    RenderOutput left, right;
    render(rects, camera, T_w_c, left);
    SE3d T_c_r = SE3d::Identity();
    T_c_r.translation() = Eigen::Vector3d(baseline_m, 0, 0);
    render(rects, camera, T_w_c * T_c_r, right);
    add_noise(left.grey, 1.5, 100 + 2 * index);
    add_noise(right.grey, 1.5, 101 + 2 * index);
    StereoFrame f;
    f.index = index;
    f.t_ns = static_cast<int64_t>(index) * 50'000'000;
    f.left = left.grey;
    f.right = right.grey;
    if (gt_mask) *gt_mask = (left.id == 1);
    if (gt_disparity_px) {
      gt_disparity_px->create(left.depth_m.size(), CV_32FC1);
      for (int y = 0; y < left.depth_m.rows; ++y) {
        for (int x = 0; x < left.depth_m.cols; ++x) {
          const float z = left.depth_m.at<float>(y, x);
          gt_disparity_px->at<float>(y, x) = z > 0 ? static_cast<float>(camera.fx * baseline_m / z) : 0.0f;
        }
      }
    }
    return f;
  }
};

// A 0.5 x 0.9 m box 5 m away (~46 x 83 px): with 120 quadtree tracks (~55 px apart) two or three fall on it.
inline CorridorScene small_far_box_scene() {
  CorridorScene scene;
  scene.box.origin = {-0.4, -0.4, 5.0};
  scene.box.width_m = 0.5;
  scene.box.height_m = 0.9;
  return scene;
}

inline SE3d camera_pose(double x, double y, double z, double yaw_deg = 0) {
  SE3d T = SE3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

inline double iou(const cv::Mat& a, const cv::Mat& b) {
  const int inter = cv::countNonZero(a & b);
  const int uni = cv::countNonZero(a | b);
  return uni > 0 ? static_cast<double>(inter) / uni : 1.0;
}

}  // namespace agvslam::dynamic::testing
