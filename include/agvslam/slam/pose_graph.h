#pragma once
// Geometry of loop closing (stereo: the scale is known, so ORB-SLAM2's Sim(3) becomes SE(3)):
//
//   optimize_pose_graph   SE(3) pose graph (the essential graph: spanning tree, strong covisibility and loop
//                         edges) with Ceres: vertices T_c_w (quaternion on Ceres' EigenQuaternionManifold +
//                         translation), edges measure T_j_i = T_j_w * T_w_i, residual = [translation error (m);
//                         2 x vector part of the rotation error quaternion (rad)] of T_j_i_measured^-1 * T_j_i,
//                         weighted by sqrt(edge.weight) (ORB-SLAM2: identity information). Sparse Cholesky.
//   estimate_se3_ransac   3-point RANSAC on 3-D point matches (each point in its own camera: p1 in camera 1,
//                         p2 in camera 2) for T_c1_c2 (Umeyama without scale on each sample), inliers by the
//                         reprojection chi-square in both images (ORB-SLAM2's Sim3Solver with the scale fixed),
//                         then a least-squares fit on all inliers.
//   optimize_relative_pose   refines T_c1_c2 on the reprojection errors in both images (ORB-SLAM2's OptimizeSim3,
//                         scale fixed): Huber (delta^2 = chi2), outliers removed, optimised again.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "agvslam/core/se3.h"
#include "agvslam/slam/optimizer.h"

namespace agvslam::slam {

struct PoseGraph {
  struct Vertex {
    SE3d T_c_w = SE3d::Identity();
    bool fixed = false;
  };
  struct Edge {
    int i = -1, j = -1;
    SE3d T_j_i = SE3d::Identity();  // measured T_j_w * T_w_i
    double weight = 1.0;
  };
  std::vector<Vertex> vertices;
  std::vector<Edge> edges;
};

struct PoseGraphStats {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
};

// Optimises the vertices in place (fixed ones stay). Vertices without edges are left as they are.
PoseGraphStats optimize_pose_graph(PoseGraph& graph, int iterations);

// One 3-D match: the point in camera 1 (p1_c) and in camera 2 (p2_c), and its keypoints in each image with the
// information of their pyramid levels.
struct PointMatch3d {
  Eigen::Vector3d p1_c = Eigen::Vector3d::Zero(), p2_c = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv1_px = Eigen::Vector2d::Zero(), uv2_px = Eigen::Vector2d::Zero();
  double inv_sigma2_1 = 1, inv_sigma2_2 = 1;
};

struct Se3RansacResult {
  bool found = false;
  SE3d T_c1_c2 = SE3d::Identity();
  std::vector<uint8_t> inlier;  // per match
  int inliers = 0;
  int iterations = 0;
};

// RANSAC over `iterations` 3-point samples (deterministic for a seed); found when >= min_inliers.
Se3RansacResult estimate_se3_ransac(const StereoIntrinsics& camera, const std::vector<PointMatch3d>& matches,
                                    int iterations, double chi2, int min_inliers, uint64_t seed = 1);

// Reprojection chi-square values of a match under T_c1_c2 (p2 into image 1, p1 into image 2); false when a point
// falls behind a camera.
bool match_chi2(const StereoIntrinsics& camera, const PointMatch3d& m, const SE3d& T_c1_c2, double& chi2_1,
                double& chi2_2);

// Refines T_c1_c2 (in/out) on the matches not marked in `outlier` (in/out: resized to matches.size(), outliers of
// the final pass). Returns the inlier count.
int optimize_relative_pose(const StereoIntrinsics& camera, const std::vector<PointMatch3d>& matches, double chi2,
                           std::vector<uint8_t>& outlier, SE3d& T_c1_c2);

}  // namespace agvslam::slam
