#pragma once
// Two-view triangulation (ORB-SLAM2's linear method: the null vector of the 4x4 DLT system by SVD) and the checks
// a new map point must pass.

#include <Eigen/Core>

#include "agvslam/core/se3.h"

namespace agvslam::slam {

// x1, x2: normalised image coordinates ((u - cx) / fx, (v - cy) / fy) of the same point in two cameras with poses
// T1_c_w, T2_c_w. Writes the world point and returns false when the solution is at infinity (w ~ 0) or not finite.
bool triangulate_linear(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, const SE3d& T1_c_w, const SE3d& T2_c_w,
                        Eigen::Vector3d& p_w);

// Cosine of the parallax angle between the rays from two camera centres to p_w.
double parallax_cos(const Eigen::Vector3d& p_w, const Eigen::Vector3d& center1_w, const Eigen::Vector3d& center2_w);

// Fundamental matrix F12 with x1^T F12 x2 = 0 for pixel coordinates of camera 1 and 2 (both with intrinsics K).
Eigen::Matrix3d fundamental_from_poses(const SE3d& T1_c_w, const SE3d& T2_c_w, const Eigen::Matrix3d& K);

}  // namespace agvslam::slam
