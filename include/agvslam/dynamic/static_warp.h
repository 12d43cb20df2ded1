#pragma once
// Where a static point was in an earlier image: the ego-motion warp shared by the stages that compare the current
// left image with an earlier one (the photometric check, the left-band segmenter, the two-motion carving).
//
// The point seen at pixel (u, v) of the current left image with disparity d lies at depth bf / d on the pixel's ray
// ((u - cx) / fx, (v - cy) / fy, 1). With T_earlier_cur = (R, t) it is seen in the earlier image at
// pi(R ray + (d / bf) t) (the ray scaled by bf / d, moved, then projected: the scale cancels), so d = 0 is the
// point at infinity and the warp needs no division by d.
#include <Eigen/Core>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"

namespace agvslam::dynamic {

class StaticWarp {
 public:
  // T_cur_earlier: the ego-motion from the earlier camera to the current one; bf_px_m: baseline * fx.
  StaticWarp(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_earlier)
      : camera_(&camera), bf_px_m_(bf_px_m) {
    const SE3d T_earlier_cur = T_cur_earlier.inverse();
    R_ = T_earlier_cur.linear();
    t_over_bf_ = T_earlier_cur.translation() / bf_px_m;
  }
  // (pu, pv): the point's position in the earlier image. False when it lies less than min_depth_m in front of the
  // earlier camera (behind it, at d = 0).
  bool at(double u, double v, double d, double& pu, double& pv, double min_depth_m = 0) const {
    const Eigen::Vector3d ray((u - camera_->cx) / camera_->fx, (v - camera_->cy) / camera_->fy, 1.0);
    const Eigen::Vector3d q = R_ * ray + d * t_over_bf_;
    // q is the earlier camera's view of the point divided by its current depth bf / d.
    if (q.z() <= 1e-6 || q.z() * bf_px_m_ < min_depth_m * d) return false;
    pu = camera_->fx * q.x() / q.z() + camera_->cx;
    pv = camera_->fy * q.y() / q.z() + camera_->cy;
    return true;
  }

 private:
  const PinholeCamera* camera_;
  double bf_px_m_;
  Eigen::Matrix3d R_;
  Eigen::Vector3d t_over_bf_;
};

}  // namespace agvslam::dynamic
