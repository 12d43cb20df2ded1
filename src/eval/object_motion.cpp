#include "agvslam/eval/object_motion.h"

#include <cmath>
#include <stdexcept>

namespace agvslam::eval {
namespace {

// Calls fn(x, y, disparity) for each pixel of object `id` with a disparity; returns their count.
template <typename Fn>
int for_each_object_pixel(const cv::Mat& instances, const cv::Mat& disparity_px, int id, Fn fn) {
  int count = 0;
  for (int y = 0; y < instances.rows; ++y) {
    const uint8_t* object = instances.ptr<uint8_t>(y);
    const float* d = disparity_px.ptr<float>(y);
    for (int x = 0; x < instances.cols; ++x) {
      if (object[x] != id || !(d[x] > 0)) continue;
      ++count;
      fn(x, y, d[x]);
    }
  }
  return count;
}

}  // namespace

ObjectImageMotion ground_truth_image_motion(const cv::Mat& instances_then, const cv::Mat& disparity_then_px,
                                            const cv::Mat& instances_now, const cv::Mat& disparity_now_px,
                                            int object_id, const PinholeCamera& camera, double bf_px_m,
                                            const SE3d& T_now_then, const ObjectMotionConfig& config) {
  if (instances_then.type() != CV_8UC1 || instances_now.type() != CV_8UC1 || disparity_then_px.type() != CV_32FC1 ||
      disparity_now_px.type() != CV_32FC1 || instances_then.size() != disparity_then_px.size() ||
      instances_now.size() != disparity_now_px.size()) {
    throw std::invalid_argument(
        "ground_truth_image_motion: expected CV_8UC1 instances and CV_32FC1 disparities of one size");
  }
  ObjectImageMotion m;
  if (!(bf_px_m > 0) || !camera.valid()) return m;
  // Where the earlier pixels would be now if the object stood still, and where its pixels are now.
  double sum_x = 0, sum_y = 0;
  int predicted = 0;
  m.pixels_then = for_each_object_pixel(instances_then, disparity_then_px, object_id, [&](int x, int y, float d) {
    const Eigen::Vector3d p_now = T_now_then * camera.unproject(Eigen::Vector2d(x, y), bf_px_m / d);
    if (p_now.z() <= 1e-3) return;
    const Eigen::Vector2d uv = camera.project(p_now);
    sum_x += uv.x();
    sum_y += uv.y();
    ++predicted;
  });
  double now_x = 0, now_y = 0;
  m.pixels_now = for_each_object_pixel(instances_now, disparity_now_px, object_id, [&](int x, int y, float) {
    now_x += x;
    now_y += y;
  });
  if (m.pixels_then < config.min_pixels || m.pixels_now < config.min_pixels || predicted < config.min_pixels) return m;
  m.visible_ratio = static_cast<double>(m.pixels_now) / m.pixels_then;
  m.offset_px = std::hypot(now_x / m.pixels_now - sum_x / predicted, now_y / m.pixels_now - sum_y / predicted);
  const double c = config.max_visible_change;
  m.valid = m.visible_ratio <= 1 + c && m.visible_ratio >= 1 / (1 + c);
  return m;
}

}  // namespace agvslam::eval
