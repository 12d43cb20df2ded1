#include "agvslam/eval/object_motion.h"

#include <cmath>
#include <stdexcept>

namespace agvslam::eval {

ObjectImageMotion ground_truth_image_motion(const cv::Mat& instances_then, const cv::Mat& disparity_then_px,
                                            const cv::Mat& instances_now, const cv::Mat& disparity_now_px, int object_id,
                                            const PinholeCamera& camera, double bf_px_m, const SE3d& T_now_then,
                                            const ObjectMotionConfig& config) {
  if (instances_then.type() != CV_8UC1 || instances_now.type() != CV_8UC1 || disparity_then_px.type() != CV_32FC1 ||
      disparity_now_px.type() != CV_32FC1 || instances_then.size() != disparity_then_px.size() ||
      instances_now.size() != disparity_now_px.size()) {
    throw std::invalid_argument("ground_truth_image_motion: expected CV_8UC1 instances and CV_32FC1 disparities of one size");
  }
  ObjectImageMotion m;
  if (!(bf_px_m > 0) || !camera.valid()) return m;
  // Where the earlier pixels would be now if the object stood still.
  double sum_x = 0, sum_y = 0;
  int predicted = 0;
  for (int y = 0; y < instances_then.rows; ++y) {
    const uint8_t* id = instances_then.ptr<uint8_t>(y);
    const float* d = disparity_then_px.ptr<float>(y);
    for (int x = 0; x < instances_then.cols; ++x) {
      if (id[x] != object_id || !(d[x] > 0)) continue;
      ++m.pixels_then;
      const Eigen::Vector3d p_now = T_now_then * camera.unproject(Eigen::Vector2d(x, y), bf_px_m / d[x]);
      if (p_now.z() <= 1e-3) continue;
      const Eigen::Vector2d uv = camera.project(p_now);
      sum_x += uv.x();
      sum_y += uv.y();
      ++predicted;
    }
  }
  double now_x = 0, now_y = 0;
  for (int y = 0; y < instances_now.rows; ++y) {
    const uint8_t* id = instances_now.ptr<uint8_t>(y);
    const float* d = disparity_now_px.ptr<float>(y);
    for (int x = 0; x < instances_now.cols; ++x) {
      if (id[x] != object_id || !(d[x] > 0)) continue;
      ++m.pixels_now;
      now_x += x;
      now_y += y;
    }
  }
  if (m.pixels_then < config.min_pixels || m.pixels_now < config.min_pixels || predicted < config.min_pixels) return m;
  m.visible_ratio = static_cast<double>(m.pixels_now) / m.pixels_then;
  m.offset_px = std::hypot(now_x / m.pixels_now - sum_x / predicted, now_y / m.pixels_now - sum_y / predicted);
  const double c = config.max_visible_change;
  m.valid = m.visible_ratio <= 1 + c && m.visible_ratio >= 1 / (1 + c);
  return m;
}

}  // namespace agvslam::eval
