#include "agvslam/slam/optimizer.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>

namespace agvslam::slam {

namespace {

// ---------------------------------------------------------------------------------------------------------------
// Pose parameterisation: x = [qx qy qz qw tx ty tz] (T_c_w), delta = [rho phi]: R <- Exp(phi) R, t <- t + rho.
// The residuals fill the first six columns of their 7-column pose Jacobian with the derivative with respect to
// delta directly (and zero the seventh), so PlusJacobian is [I6; 0].

Eigen::Quaterniond exp_so3(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  if (theta < 1e-10) {
    Eigen::Quaterniond q(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z());
    return q.normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(theta, phi / theta));
}

class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(x);
    const Eigen::Map<const Eigen::Vector3d> t(x + 4);
    const Eigen::Map<const Eigen::Vector3d> rho(delta);
    const Eigen::Map<const Eigen::Vector3d> phi(delta + 3);
    Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta);
    Eigen::Map<Eigen::Vector3d> t_out(x_plus_delta + 4);
    q_out = (exp_so3(phi) * q).normalized();
    t_out = t + rho;
    return true;
  }
  bool PlusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
    J.setZero();
    J.topRows<6>().setIdentity();
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const Eigen::Map<const Eigen::Quaterniond> qy(y), qx(x);
    const Eigen::Map<const Eigen::Vector3d> ty(y + 4), tx(x + 4);
    const Eigen::AngleAxisd aa(qy * qx.conjugate());
    Eigen::Map<Eigen::Vector3d> d_t(y_minus_x), d_r(y_minus_x + 3);
    d_t = ty - tx;
    d_r = aa.angle() * aa.axis();
    return true;
  }
  bool MinusJacobian(const double* /*x*/, double* jacobian) const override {
    Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
    J.setZero();
    J.leftCols<6>().setIdentity();
    return true;
  }
};

void pose_to_params(const SE3d& T, double* x) {
  const Eigen::Quaterniond q(T.linear());
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  x[4] = T.translation().x();
  x[5] = T.translation().y();
  x[6] = T.translation().z();
}

SE3d params_to_pose(const double* x) {
  const Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
  return make_se3(q.normalized(), Eigen::Vector3d(x[4], x[5], x[6]));
}

Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Residual r = sqrt(info) * (observation - projection) and its Jacobian with respect to p_c (kRows x 3).
template <int kRows>
void project_residual(const StereoIntrinsics& cam, const Eigen::Vector3d& p_c, const double* obs, double sqrt_info,
                      double* residual, Eigen::Matrix<double, kRows, 3>* J_pc) {
  // Points at or behind the camera keep a finite (large) residual; the chi-square test then rejects them.
  const double z = std::max(p_c.z(), 1e-3);
  const double inv_z = 1.0 / z;
  const double u = cam.fx * p_c.x() * inv_z + cam.cx;
  const double v = cam.fy * p_c.y() * inv_z + cam.cy;
  residual[0] = sqrt_info * (obs[0] - u);
  residual[1] = sqrt_info * (obs[1] - v);
  if constexpr (kRows == 3) residual[2] = sqrt_info * (obs[2] - (u - cam.bf * inv_z));
  if (J_pc) {
    const double inv_z2 = inv_z * inv_z;
    J_pc->setZero();
    (*J_pc)(0, 0) = -sqrt_info * cam.fx * inv_z;
    (*J_pc)(0, 2) = sqrt_info * cam.fx * p_c.x() * inv_z2;
    (*J_pc)(1, 1) = -sqrt_info * cam.fy * inv_z;
    (*J_pc)(1, 2) = sqrt_info * cam.fy * p_c.y() * inv_z2;
    if constexpr (kRows == 3) {
      (*J_pc)(2, 0) = -sqrt_info * cam.fx * inv_z;
      (*J_pc)(2, 2) = sqrt_info * (cam.fx * p_c.x() - cam.bf) * inv_z2;
    }
  }
}

// Pose-only reprojection residual (the point is a constant).
template <int kRows>
class PoseOnlyCost final : public ceres::SizedCostFunction<kRows, 7> {
 public:
  PoseOnlyCost(const StereoIntrinsics& cam, const PoseObservation& o) : cam_(cam), p_w_(o.p_w) {
    obs_[0] = o.uv_px.x();
    obs_[1] = o.uv_px.y();
    obs_[2] = o.u_right_px;
    sqrt_info_ = std::sqrt(o.inv_sigma2);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* x = parameters[0];
    const Eigen::Map<const Eigen::Quaterniond> q(x);
    const Eigen::Map<const Eigen::Vector3d> t(x + 4);
    const Eigen::Vector3d Rp = q * p_w_;
    const Eigen::Vector3d p_c = Rp + t;
    if (jacobians && jacobians[0]) {
      Eigen::Matrix<double, kRows, 3> J_pc;
      project_residual<kRows>(cam_, p_c, obs_, sqrt_info_, residuals, &J_pc);
      Eigen::Map<Eigen::Matrix<double, kRows, 7, Eigen::RowMajor>> J(jacobians[0]);
      J.template leftCols<3>() = J_pc;
      J.template middleCols<3>(3) = -J_pc * hat(Rp);
      J.col(6).setZero();
    } else {
      project_residual<kRows>(cam_, p_c, obs_, sqrt_info_, residuals, nullptr);
    }
    return true;
  }

 private:
  StereoIntrinsics cam_;
  Eigen::Vector3d p_w_;
  double obs_[3];
  double sqrt_info_ = 1;
};

// Pose and point reprojection residual.
template <int kRows>
class PosePointCost final : public ceres::SizedCostFunction<kRows, 7, 3> {
 public:
  PosePointCost(const StereoIntrinsics& cam, const BaProblem::Observation& o) : cam_(cam) {
    obs_[0] = o.uv_px.x();
    obs_[1] = o.uv_px.y();
    obs_[2] = o.u_right_px;
    sqrt_info_ = std::sqrt(o.inv_sigma2);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* x = parameters[0];
    const Eigen::Map<const Eigen::Quaterniond> q(x);
    const Eigen::Map<const Eigen::Vector3d> t(x + 4);
    const Eigen::Map<const Eigen::Vector3d> p_w(parameters[1]);
    const Eigen::Vector3d Rp = q * p_w;
    const Eigen::Vector3d p_c = Rp + t;
    if (jacobians && (jacobians[0] || jacobians[1])) {
      Eigen::Matrix<double, kRows, 3> J_pc;
      project_residual<kRows>(cam_, p_c, obs_, sqrt_info_, residuals, &J_pc);
      if (jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, kRows, 7, Eigen::RowMajor>> J(jacobians[0]);
        J.template leftCols<3>() = J_pc;
        J.template middleCols<3>(3) = -J_pc * hat(Rp);
        J.col(6).setZero();
      }
      if (jacobians[1]) {
        Eigen::Map<Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>> J(jacobians[1]);
        J = J_pc * q.toRotationMatrix();
      }
    } else {
      project_residual<kRows>(cam_, p_c, obs_, sqrt_info_, residuals, nullptr);
    }
    return true;
  }

 private:
  StereoIntrinsics cam_;
  double obs_[3];
  double sqrt_info_ = 1;
};

class AbortCallback final : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& /*summary*/) override {
    if (flag_ && flag_->load(std::memory_order_relaxed)) {
      aborted_ = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool aborted() const { return aborted_; }

 private:
  const std::atomic<bool>* flag_;
  bool aborted_ = false;
};

ceres::Problem::Options problem_options() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return o;
}

}  // namespace

double reprojection_chi2(const StereoIntrinsics& cam, const Eigen::Vector3d& p_c, const Eigen::Vector2d& uv_px,
                         double u_right_px, double inv_sigma2, bool* in_front) {
  if (in_front) *in_front = p_c.z() > 0;
  const double z = std::max(p_c.z(), 1e-3);
  const double inv_z = 1.0 / z;
  const double u = cam.fx * p_c.x() * inv_z + cam.cx;
  const double v = cam.fy * p_c.y() * inv_z + cam.cy;
  const double eu = uv_px.x() - u, ev = uv_px.y() - v;
  double e2 = eu * eu + ev * ev;
  if (u_right_px >= 0) {
    const double er = u_right_px - (u - cam.bf * inv_z);
    e2 += er * er;
  }
  return e2 * inv_sigma2;
}

MotionOnlyStats optimize_pose(const StereoIntrinsics& camera, const OptimizerConfig& config,
                              const std::vector<PoseObservation>& observations, std::vector<uint8_t>& outlier,
                              SE3d& T_c_w) {
  MotionOnlyStats stats;
  const std::size_t n = observations.size();
  outlier.assign(n, 0);
  if (n < 3) {
    stats.outliers = static_cast<int>(n);
    std::fill(outlier.begin(), outlier.end(), 1);
    return stats;
  }
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  costs.reserve(n);
  for (const PoseObservation& o : observations) {
    if (o.u_right_px >= 0) {
      costs.push_back(std::make_unique<PoseOnlyCost<3>>(camera, o));
    } else {
      costs.push_back(std::make_unique<PoseOnlyCost<2>>(camera, o));
    }
  }
  ceres::HuberLoss huber_mono(std::sqrt(config.chi2_mono));
  ceres::HuberLoss huber_stereo(std::sqrt(config.chi2_stereo));
  PoseManifold manifold;
  double x[7];
  pose_to_params(T_c_w, x);

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = config.motion_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;

  for (int round = 0; round < config.motion_rounds; ++round) {
    const bool robust = round < config.motion_robust_rounds;
    ceres::Problem problem(problem_options());
    int used = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (outlier[i]) continue;
      ceres::LossFunction* loss = nullptr;
      if (robust) loss = observations[i].u_right_px >= 0 ? &huber_stereo : &huber_mono;
      problem.AddResidualBlock(costs[i].get(), loss, x);
      ++used;
    }
    if (used < 3) break;
    problem.SetManifold(x, &manifold);
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    stats.iterations += static_cast<int>(summary.iterations.size());
    ++stats.rounds;

    // Classify every observation (also the ones left out) against the new pose.
    const SE3d T = params_to_pose(x);
    stats.inliers = 0;
    stats.outliers = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const PoseObservation& o = observations[i];
      bool in_front = true;
      const double chi2 = reprojection_chi2(camera, T * o.p_w, o.uv_px, o.u_right_px, o.inv_sigma2, &in_front);
      const double th = o.u_right_px >= 0 ? config.chi2_stereo : config.chi2_mono;
      outlier[i] = (!in_front || chi2 > th) ? 1 : 0;
      if (outlier[i]) {
        ++stats.outliers;
      } else {
        ++stats.inliers;
      }
    }
    if (stats.inliers < 10 && round + 1 < config.motion_rounds) {
      // ORB-SLAM2 stops early when too few edges remain; the pose so far is the answer.
      break;
    }
  }
  T_c_w = params_to_pose(x);
  return stats;
}

BaStats solve_bundle_adjustment(BaProblem& problem, const StereoIntrinsics& camera, const OptimizerConfig& config,
                                int iterations_robust, int iterations_plain, const std::atomic<bool>* abort) {
  BaStats stats;
  const std::size_t n_poses = problem.poses.size();
  const std::size_t n_points = problem.points_w.size();
  std::vector<double> pose_params(7 * n_poses);
  for (std::size_t k = 0; k < n_poses; ++k) pose_to_params(problem.poses[k].T_c_w, &pose_params[7 * k]);
  std::vector<double> point_params(3 * n_points);
  for (std::size_t k = 0; k < n_points; ++k) {
    for (int c = 0; c < 3; ++c) point_params[3 * k + static_cast<std::size_t>(c)] = problem.points_w[k][c];
  }

  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  costs.reserve(problem.observations.size());
  for (const BaProblem::Observation& o : problem.observations) {
    if (o.u_right_px >= 0) {
      costs.push_back(std::make_unique<PosePointCost<3>>(camera, o));
    } else {
      costs.push_back(std::make_unique<PosePointCost<2>>(camera, o));
    }
  }
  ceres::HuberLoss huber_mono(std::sqrt(config.chi2_mono));
  ceres::HuberLoss huber_stereo(std::sqrt(config.chi2_stereo));
  PoseManifold manifold;
  AbortCallback callback(abort);

  auto classify = [&](bool count_cost, double* cost) {
    int outliers = 0;
    double c = 0;
    for (BaProblem::Observation& o : problem.observations) {
      const SE3d T = params_to_pose(&pose_params[7 * static_cast<std::size_t>(o.pose)]);
      const Eigen::Vector3d p_w =
          Eigen::Map<const Eigen::Vector3d>(&point_params[3 * static_cast<std::size_t>(o.point)]);
      bool in_front = true;
      const double chi2 = reprojection_chi2(camera, T * p_w, o.uv_px, o.u_right_px, o.inv_sigma2, &in_front);
      const double th = o.u_right_px >= 0 ? config.chi2_stereo : config.chi2_mono;
      if (count_cost) {
        if (!o.outlier) c += 0.5 * chi2;
        continue;
      }
      o.outlier = !in_front || chi2 > th;
      if (o.outlier) {
        ++outliers;
      } else {
        c += 0.5 * chi2;
      }
    }
    if (cost) *cost = c;
    return outliers;
  };
  classify(true, &stats.initial_cost);

  auto run = [&](int iterations, bool robust) {
    if (iterations <= 0) return;
    ceres::Problem p(problem_options());
    std::vector<uint8_t> pose_used(n_poses, 0);
    for (std::size_t i = 0; i < problem.observations.size(); ++i) {
      const BaProblem::Observation& o = problem.observations[i];
      if (o.outlier) continue;
      ceres::LossFunction* loss = nullptr;
      if (robust) loss = o.u_right_px >= 0 ? &huber_stereo : &huber_mono;
      double* pose = &pose_params[7 * static_cast<std::size_t>(o.pose)];
      double* point = &point_params[3 * static_cast<std::size_t>(o.point)];
      p.AddResidualBlock(costs[i].get(), loss, pose, point);
      if (!pose_used[static_cast<std::size_t>(o.pose)]) {
        pose_used[static_cast<std::size_t>(o.pose)] = 1;
        p.SetManifold(pose, &manifold);
        if (problem.poses[static_cast<std::size_t>(o.pose)].fixed) p.SetParameterBlockConstant(pose);
      }
    }
    if (p.NumResidualBlocks() == 0) return;
    ceres::Solver::Options options;
    options.linear_solver_type = config.local_ba_dense_schur ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
    options.max_num_iterations = iterations;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    if (abort) options.callbacks.push_back(&callback);
    ceres::Solver::Summary summary;
    ceres::Solve(options, &p, &summary);
    stats.iterations += static_cast<int>(summary.iterations.size());
  };

  run(iterations_robust, true);
  if (!callback.aborted()) {
    classify(false, nullptr);
    run(iterations_plain, false);
  }
  stats.outliers = classify(false, &stats.final_cost);
  stats.aborted = callback.aborted();

  for (std::size_t k = 0; k < n_poses; ++k) {
    if (!problem.poses[k].fixed) problem.poses[k].T_c_w = params_to_pose(&pose_params[7 * k]);
  }
  for (std::size_t k = 0; k < n_points; ++k)
    problem.points_w[k] = Eigen::Map<const Eigen::Vector3d>(&point_params[3 * k]);
  return stats;
}

}  // namespace agvslam::slam
