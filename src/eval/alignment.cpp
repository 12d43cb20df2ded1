#include "agvslam/eval/alignment.h"

#include <Eigen/SVD>

#include "agvslam/core/error.h"

namespace agvslam::eval {

AlignMode parse_align_mode(const std::string& value, const std::string& option_name) {
  if (value == "none") return AlignMode::kNone;
  if (value == "se3") return AlignMode::kSE3;
  if (value == "sim3") return AlignMode::kSim3;
  throw InputError(option_name, "value '" + value + "'", "expected se3, sim3 or none");
}

std::string to_string(AlignMode mode) {
  switch (mode) {
    case AlignMode::kNone:
      return "none";
    case AlignMode::kSE3:
      return "se3";
    case AlignMode::kSim3:
      return "sim3";
  }
  return "?";
}

SE3d Alignment::apply(const SE3d& T_src_x) const {
  SE3d out = SE3d::Identity();
  out.linear() = T_dst_src.linear() * T_src_x.linear();
  out.translation() = apply(Eigen::Vector3d(T_src_x.translation()));
  return out;
}

Alignment umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  const Eigen::Index n = src.cols();
  Alignment a;
  if (n == 0 || dst.cols() != n) return a;
  const Eigen::Vector3d mu_src = src.rowwise().mean();
  const Eigen::Vector3d mu_dst = dst.rowwise().mean();
  const Eigen::Matrix3Xd src_c = src.colwise() - mu_src;
  const Eigen::Matrix3Xd dst_c = dst.colwise() - mu_dst;
  const double var_src = src_c.squaredNorm() / static_cast<double>(n);
  const Eigen::Matrix3d cov = dst_c * src_c.transpose() / static_cast<double>(n);

  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1.0;
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();
  double scale = 1.0;
  if (with_scale && var_src > 0) scale = (svd.singularValues().asDiagonal() * S).trace() / var_src;
  a.scale = scale;
  a.T_dst_src = make_se3(R, mu_dst - scale * R * mu_src);
  return a;
}

}  // namespace agvslam::eval
