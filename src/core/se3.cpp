#include "agvslam/core/se3.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace agvslam {

double rotation_angle_rad(const SE3d& T) {
  // atan2(|sin|, cos) stays accurate near 0 and pi, where acos of the trace loses half the digits.
  const Eigen::Matrix3d R = T.linear();
  const Eigen::Vector3d axis_sin(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const double c = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  return std::atan2(0.5 * axis_sin.norm(), c);
}

Eigen::Matrix3d orthonormalize(const Eigen::Matrix3d& R) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d out = svd.matrixU() * svd.matrixV().transpose();
  if (out.determinant() < 0) {
    Eigen::Matrix3d U = svd.matrixU();
    U.col(2) *= -1.0;
    out = U * svd.matrixV().transpose();
  }
  return out;
}

namespace {
Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
}  // namespace

SE3d se3_exp(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  const double theta = phi.norm();
  const Eigen::Matrix3d Phi = hat(phi);
  Eigen::Matrix3d R, V;
  if (theta < 1e-9) {
    R = Eigen::Matrix3d::Identity() + Phi;
    V = Eigen::Matrix3d::Identity() + 0.5 * Phi;
  } else {
    R = Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
    const double t2 = theta * theta;
    V = Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * Phi +
        (theta - std::sin(theta)) / (t2 * theta) * Phi * Phi;
  }
  return make_se3(R, V * rho);
}

Vector6d se3_log(const SE3d& T) {
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(T.linear()));
  const double theta = aa.angle();
  const Eigen::Vector3d phi = aa.axis() * theta;
  const Eigen::Matrix3d Phi = hat(phi);
  Eigen::Matrix3d V_inv;
  if (theta < 1e-9) {
    V_inv = Eigen::Matrix3d::Identity() - 0.5 * Phi;
  } else {
    const double half = 0.5 * theta;
    V_inv = Eigen::Matrix3d::Identity() - 0.5 * Phi +
            (1.0 - half * std::cos(half) / std::sin(half)) / (theta * theta) * Phi * Phi;
  }
  Vector6d xi;
  xi.head<3>() = V_inv * T.translation();
  xi.tail<3>() = phi;
  return xi;
}

bool is_valid_pose(const SE3d& T, double tol) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < tol &&
         std::abs(R.determinant() - 1.0) < tol;
}

}  // namespace agvslam
