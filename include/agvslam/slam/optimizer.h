#pragma once
// Ceres optimisers of the SLAM back end (ORB-SLAM2's Optimizer, stereo):
//
//   motion-only BA   one pose against fixed map points; Huber loss (delta^2 = the chi-square threshold); rounds of
//                    optimise + chi-square classification, outliers left out of the next round but re-tested
//                    after it (ORB-SLAM2: 4 rounds x 10 iterations, robust in the first two).
//   bundle adjustment   poses and points; points are eliminated by the Schur complement (DENSE_SCHUR or
//                    SPARSE_SCHUR); a robust pass, then outliers (chi-square, negative depth) are removed and the
//                    rest optimised without the robust loss.
//
// Residuals are reprojection errors in pixels, weighted by the keypoint's level (information = 1 / sigma^2 with
// sigma = scale_factor^level): monocular (u, v), stereo (u, v, u_right). Their Jacobians are analytic. A pose is
// T_c_w as 7 numbers [qx qy qz qw tx ty tz] with a 6-dof manifold: R <- Exp(phi) R, t <- t + rho.

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <vector>

#include "agvslam/core/se3.h"
#include "agvslam/slam/slam_config.h"

namespace agvslam::slam {

struct StereoIntrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double bf = 0;  // fx * baseline_m
};

// One observation of a fixed world point by the pose being optimised.
struct PoseObservation {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
  double u_right_px = -1;  // < 0: monocular observation
  double inv_sigma2 = 1;   // 1 / sigma^2 of the keypoint's level
};

struct MotionOnlyStats {
  int inliers = 0;
  int outliers = 0;
  int rounds = 0;
  int iterations = 0;
};

// Optimises T_c_w (initial value in, result out). outlier[i] (resized to observations.size()) says which
// observations failed the chi-square test in the last round. Returns the statistics; inliers < 3 leaves the pose
// at the best estimate found but callers treat the result as failed.
MotionOnlyStats optimize_pose(const StereoIntrinsics& camera, const OptimizerConfig& config,
                              const std::vector<PoseObservation>& observations, std::vector<uint8_t>& outlier,
                              SE3d& T_c_w);

// A bundle-adjustment problem in plain data (filled from the map by the local mapper, or by tests).
struct BaProblem {
  struct Pose {
    SE3d T_c_w = SE3d::Identity();
    bool fixed = false;
  };
  struct Observation {
    int pose = -1;
    int point = -1;
    Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();
    double u_right_px = -1;  // < 0: monocular
    double inv_sigma2 = 1;
    bool outlier = false;  // output: rejected (chi-square or behind the camera)
  };
  std::vector<Pose> poses;
  std::vector<Eigen::Vector3d> points_w;
  std::vector<Observation> observations;
};

struct BaStats {
  double initial_cost = 0;  // 0.5 * sum of squared weighted residuals (no robust loss), before
  double final_cost = 0;    // ... and after (over the observations that stayed inliers)
  int iterations = 0;
  int outliers = 0;
  bool aborted = false;
};

// Runs iterations_robust iterations with the Huber loss, marks outliers, then iterations_plain without it, and
// marks outliers again. abort (optional) stops the solver between iterations (the local mapper sets it when a
// new keyframe arrives); the estimate so far is kept.
BaStats solve_bundle_adjustment(BaProblem& problem, const StereoIntrinsics& camera, const OptimizerConfig& config,
                                int iterations_robust, int iterations_plain, const std::atomic<bool>* abort = nullptr);

// Squared weighted reprojection error (chi-square value) of a point in the camera frame; also false when the
// point is behind the camera.
double reprojection_chi2(const StereoIntrinsics& camera, const Eigen::Vector3d& p_c, const Eigen::Vector2d& uv_px,
                         double u_right_px, double inv_sigma2, bool* in_front = nullptr);

}  // namespace agvslam::slam
