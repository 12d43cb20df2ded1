#pragma once
// Rigid transforms. Naming: T_a_b maps a point expressed in frame b into frame a (p_a = T_a_b * p_b).

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace agvslam {

using SE3d = Eigen::Isometry3d;
using Vector6d = Eigen::Matrix<double, 6, 1>;

inline SE3d make_se3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  SE3d T = SE3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

inline SE3d make_se3(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  SE3d T = SE3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

// Angle of the rotation part, in radians, in [0, pi].
double rotation_angle_rad(const SE3d& T);

// Nearest rotation matrix (SVD projection); used after reading 3x4 text poses that are not exactly orthonormal.
Eigen::Matrix3d orthonormalize(const Eigen::Matrix3d& R);

// Tangent-space maps with the translation first: xi = [rho; phi].
SE3d se3_exp(const Vector6d& xi);
Vector6d se3_log(const SE3d& T);

// True when every element is finite and the rotation part is orthonormal within tol.
bool is_valid_pose(const SE3d& T, double tol = 1e-3);

}  // namespace agvslam
