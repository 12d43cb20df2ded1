#include "agvslam/slam/pose_graph.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

namespace agvslam::slam {

namespace {

// Residual of one edge: T_err = T_j_i_measured^-1 * (T_j_w * T_i_w^-1).
class PoseGraphEdgeCost {
 public:
  PoseGraphEdgeCost(const SE3d& T_j_i, double sqrt_weight)
      : q_meas_inv_(Eigen::Quaterniond(T_j_i.linear()).normalized().conjugate()),
        t_meas_(T_j_i.translation()),
        sqrt_weight_(sqrt_weight) {}

  template <typename T>
  bool operator()(const T* qi_data, const T* ti_data, const T* qj_data, const T* tj_data, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qi(qi_data), qj(qj_data);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ti(ti_data), tj(tj_data);
    const Eigen::Quaternion<T> q_ji = qj * qi.conjugate();
    const Eigen::Matrix<T, 3, 1> t_ji = tj - q_ji * ti;
    const Eigen::Quaternion<T> q_inv = q_meas_inv_.cast<T>();
    Eigen::Quaternion<T> q_err = q_inv * q_ji;
    if (q_err.w() < T(0)) q_err.coeffs() = -q_err.coeffs();
    const Eigen::Matrix<T, 3, 1> t_err = q_inv * (t_ji - t_meas_.cast<T>());
    const T w(sqrt_weight_);
    for (int k = 0; k < 3; ++k) {
      r[k] = w * t_err[k];
      r[3 + k] = w * T(2) * q_err.vec()[k];
    }
    return true;
  }

 private:
  Eigen::Quaterniond q_meas_inv_;
  Eigen::Vector3d t_meas_;
  double sqrt_weight_;
};

template <typename T>
void project(const StereoIntrinsics& cam, const Eigen::Matrix<T, 3, 1>& p, T* uv) {
  const T z = p.z() > T(1e-3) ? p.z() : T(1e-3);
  uv[0] = T(cam.fx) * p.x() / z + T(cam.cx);
  uv[1] = T(cam.fy) * p.y() / z + T(cam.cy);
}

// Relative-pose residuals: p2 (camera 2) into image 1, and p1 (camera 1) into image 2.
class RelativePoseCost {
 public:
  RelativePoseCost(const StereoIntrinsics& cam, const PointMatch3d& m) : cam_(cam), m_(m) {}
  template <typename T>
  bool operator()(const T* q_data, const T* t_data, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_data);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_data);
    const Eigen::Matrix<T, 3, 1> p2_in_1 = q * m_.p2_c.cast<T>() + t;
    const Eigen::Matrix<T, 3, 1> p1_in_2 = q.conjugate() * (m_.p1_c.cast<T>() - t);
    T uv1[2], uv2[2];
    project(cam_, p2_in_1, uv1);
    project(cam_, p1_in_2, uv2);
    const T s1(std::sqrt(m_.inv_sigma2_1)), s2(std::sqrt(m_.inv_sigma2_2));
    r[0] = s1 * (T(m_.uv1_px.x()) - uv1[0]);
    r[1] = s1 * (T(m_.uv1_px.y()) - uv1[1]);
    r[2] = s2 * (T(m_.uv2_px.x()) - uv2[0]);
    r[3] = s2 * (T(m_.uv2_px.y()) - uv2[1]);
    return true;
  }

 private:
  StereoIntrinsics cam_;
  PointMatch3d m_;
};

double chi2_of(const StereoIntrinsics& cam, const Eigen::Vector3d& p_c, const Eigen::Vector2d& uv, double inv_sigma2,
               bool& in_front) {
  in_front = p_c.z() > 0;
  double proj[2];
  project(cam, p_c, proj);
  const double du = uv.x() - proj[0], dv = uv.y() - proj[1];
  return (du * du + dv * dv) * inv_sigma2;
}

}  // namespace

PoseGraphStats optimize_pose_graph(PoseGraph& graph, int iterations) {
  PoseGraphStats stats;
  const std::size_t n = graph.vertices.size();
  std::vector<double> q(4 * n), t(3 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Quaterniond qk(graph.vertices[k].T_c_w.linear());
    Eigen::Map<Eigen::Quaterniond> q_map(&q[4 * k]);
    Eigen::Map<Eigen::Vector3d> t_map(&t[3 * k]);
    q_map = qk.normalized();
    t_map = graph.vertices[k].T_c_w.translation();
  }
  ceres::Problem problem;
  std::vector<uint8_t> used(n, 0);
  for (const PoseGraph::Edge& e : graph.edges) {
    if (e.i < 0 || e.j < 0 || e.i == e.j || static_cast<std::size_t>(e.i) >= n || static_cast<std::size_t>(e.j) >= n) {
      continue;
    }
    auto* cost = new ceres::AutoDiffCostFunction<PoseGraphEdgeCost, 6, 4, 3, 4, 3>(
        new PoseGraphEdgeCost(e.T_j_i, std::sqrt(std::max(0.0, e.weight))));
    const std::size_t i = static_cast<std::size_t>(e.i), j = static_cast<std::size_t>(e.j);
    problem.AddResidualBlock(cost, nullptr, &q[4 * i], &t[3 * i], &q[4 * j], &t[3 * j]);
    used[i] = used[j] = 1;
  }
  if (problem.NumResidualBlocks() == 0) return stats;
  for (std::size_t k = 0; k < n; ++k) {
    if (!used[k]) continue;
    problem.SetManifold(&q[4 * k], new ceres::EigenQuaternionManifold);
    if (graph.vertices[k].fixed) {
      problem.SetParameterBlockConstant(&q[4 * k]);
      problem.SetParameterBlockConstant(&t[3 * k]);
    }
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  stats.iterations = static_cast<int>(summary.iterations.size());
  stats.initial_cost = summary.initial_cost;
  stats.final_cost = summary.final_cost;
  for (std::size_t k = 0; k < n; ++k) {
    if (!used[k] || graph.vertices[k].fixed) continue;
    const Eigen::Quaterniond qk = Eigen::Map<const Eigen::Quaterniond>(&q[4 * k]).normalized();
    graph.vertices[k].T_c_w = make_se3(qk, Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(&t[3 * k])));
  }
  return stats;
}

bool match_chi2(const StereoIntrinsics& camera, const PointMatch3d& m, const SE3d& T_c1_c2, double& chi2_1,
                double& chi2_2) {
  bool front1 = true, front2 = true;
  chi2_1 = chi2_of(camera, T_c1_c2 * m.p2_c, m.uv1_px, m.inv_sigma2_1, front1);
  chi2_2 = chi2_of(camera, T_c1_c2.inverse() * m.p1_c, m.uv2_px, m.inv_sigma2_2, front2);
  return front1 && front2;
}

namespace {

// Least-squares T_c1_c2 (p1 = T p2) over the selected matches (Umeyama without scale).
bool fit_se3(const std::vector<PointMatch3d>& matches, const std::vector<int>& indices, SE3d& T) {
  if (indices.size() < 3) return false;
  Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(indices.size())), dst(3, static_cast<Eigen::Index>(indices.size()));
  for (std::size_t k = 0; k < indices.size(); ++k) {
    src.col(static_cast<Eigen::Index>(k)) = matches[static_cast<std::size_t>(indices[k])].p2_c;
    dst.col(static_cast<Eigen::Index>(k)) = matches[static_cast<std::size_t>(indices[k])].p1_c;
  }
  const Eigen::Matrix4d M = Eigen::umeyama(src, dst, false);
  if (!M.allFinite()) return false;
  T = make_se3(Eigen::Matrix3d(M.topLeftCorner<3, 3>()), Eigen::Vector3d(M.topRightCorner<3, 1>()));
  return is_valid_pose(T);
}

int count_inliers(const StereoIntrinsics& camera, const std::vector<PointMatch3d>& matches, const SE3d& T, double chi2,
                  std::vector<uint8_t>* inlier) {
  int n = 0;
  if (inlier) inlier->assign(matches.size(), 0);
  for (std::size_t k = 0; k < matches.size(); ++k) {
    double c1 = 0, c2 = 0;
    if (!match_chi2(camera, matches[k], T, c1, c2) || c1 > chi2 || c2 > chi2) continue;
    ++n;
    if (inlier) (*inlier)[k] = 1;
  }
  return n;
}

}  // namespace

Se3RansacResult estimate_se3_ransac(const StereoIntrinsics& camera, const std::vector<PointMatch3d>& matches,
                                    int iterations, double chi2, int min_inliers, uint64_t seed) {
  Se3RansacResult result;
  const int n = static_cast<int>(matches.size());
  if (n < 3) return result;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> sample(3);
  SE3d best_T = SE3d::Identity();
  int best = -1;
  for (int it = 0; it < iterations; ++it) {
    sample[0] = pick(rng);
    do {
      sample[1] = pick(rng);
    } while (sample[1] == sample[0]);
    do {
      sample[2] = pick(rng);
    } while (sample[2] == sample[0] || sample[2] == sample[1]);
    SE3d T;
    if (!fit_se3(matches, sample, T)) continue;
    const int inliers = count_inliers(camera, matches, T, chi2, nullptr);
    ++result.iterations;
    if (inliers > best) {
      best = inliers;
      best_T = T;
      if (best == n) break;
    }
  }
  if (best < std::max(3, min_inliers)) return result;
  // Refit on every inlier; keep whichever explains more matches.
  std::vector<uint8_t> inlier;
  count_inliers(camera, matches, best_T, chi2, &inlier);
  std::vector<int> all;
  for (int k = 0; k < n; ++k) {
    if (inlier[static_cast<std::size_t>(k)]) all.push_back(k);
  }
  SE3d refit;
  if (fit_se3(matches, all, refit)) {
    const int refit_inliers = count_inliers(camera, matches, refit, chi2, nullptr);
    if (refit_inliers >= best) {
      best = refit_inliers;
      best_T = refit;
    }
  }
  result.found = true;
  result.T_c1_c2 = best_T;
  result.inliers = count_inliers(camera, matches, best_T, chi2, &result.inlier);
  return result;
}

int optimize_relative_pose(const StereoIntrinsics& camera, const std::vector<PointMatch3d>& matches, double chi2,
                           std::vector<uint8_t>& outlier, SE3d& T_c1_c2) {
  outlier.resize(matches.size(), 0);
  double q[4], t[3];
  {
    Eigen::Map<Eigen::Quaterniond> q_map(q);
    Eigen::Map<Eigen::Vector3d> t_map(t);
    q_map = Eigen::Quaterniond(T_c1_c2.linear()).normalized();
    t_map = T_c1_c2.translation();
  }
  ceres::HuberLoss huber(std::sqrt(chi2));
  auto solve = [&](bool robust, int iterations) {
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    for (std::size_t k = 0; k < matches.size(); ++k) {
      if (outlier[k]) continue;
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<RelativePoseCost, 4, 4, 3>(new RelativePoseCost(camera, matches[k])),
          robust ? &huber : nullptr, q, t);
    }
    if (problem.NumResidualBlocks() < 3) return;
    problem.SetManifold(q, new ceres::EigenQuaternionManifold);
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.max_num_iterations = iterations;
    options.num_threads = 1;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
  };
  auto classify = [&]() {
    const SE3d T = make_se3(Eigen::Map<const Eigen::Quaterniond>(q).normalized(), Eigen::Vector3d(t[0], t[1], t[2]));
    int inliers = 0;
    for (std::size_t k = 0; k < matches.size(); ++k) {
      double c1 = 0, c2 = 0;
      const bool ok = match_chi2(camera, matches[k], T, c1, c2) && c1 <= chi2 && c2 <= chi2;
      outlier[k] = ok ? 0 : 1;
      inliers += ok ? 1 : 0;
    }
    return inliers;
  };
  solve(true, 5);
  classify();
  solve(false, 10);
  const int inliers = classify();
  T_c1_c2 = make_se3(Eigen::Map<const Eigen::Quaterniond>(q).normalized(), Eigen::Vector3d(t[0], t[1], t[2]));
  return inliers;
}

}  // namespace agvslam::slam
