#include "agvslam/slam/triangulation.h"

#include <Eigen/SVD>
#include <cmath>

namespace agvslam::slam {

bool triangulate_linear(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, const SE3d& T1_c_w, const SE3d& T2_c_w,
                        Eigen::Vector3d& p_w) {
  const Eigen::Matrix<double, 3, 4> P1 = T1_c_w.matrix().topRows<3>();
  const Eigen::Matrix<double, 3, 4> P2 = T2_c_w.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::fabs(h(3)) < 1e-12) return false;
  p_w = h.head<3>() / h(3);
  return p_w.allFinite();
}

double parallax_cos(const Eigen::Vector3d& p_w, const Eigen::Vector3d& c1, const Eigen::Vector3d& c2) {
  const Eigen::Vector3d r1 = p_w - c1, r2 = p_w - c2;
  const double n = r1.norm() * r2.norm();
  return n > 0 ? r1.dot(r2) / n : 1.0;
}

Eigen::Matrix3d fundamental_from_poses(const SE3d& T1_c_w, const SE3d& T2_c_w, const Eigen::Matrix3d& K) {
  const SE3d T12 = T1_c_w * T2_c_w.inverse();  // camera 2 -> camera 1
  const Eigen::Matrix3d R12 = T12.linear();
  const Eigen::Vector3d t12 = T12.translation();
  Eigen::Matrix3d t_hat;
  t_hat << 0, -t12.z(), t12.y(), t12.z(), 0, -t12.x(), -t12.y(), t12.x(), 0;
  const Eigen::Matrix3d K_inv = K.inverse();
  return K_inv.transpose() * t_hat * R12 * K_inv;
}

}  // namespace agvslam::slam
