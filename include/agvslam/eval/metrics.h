#pragma once
// Trajectory error metrics.
//   ATE: absolute trajectory error, the translation difference of associated positions after alignment.
//   RPE: relative pose error over a fixed frame step (default 1: per-frame delta), translation and rotation.
//   KITTI: the odometry benchmark's t_rel (%) and r_rel (deg/100 m), averaged over all sub-sequences of
//          100, 200, ..., 800 m of ground-truth path length, starting every 10th frame.

#include <optional>
#include <vector>

#include "agvslam/eval/alignment.h"
#include "agvslam/eval/association.h"

namespace agvslam::eval {

struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
};
ErrorStats compute_stats(std::vector<double> values);

struct AteResult {
  AlignMode mode = AlignMode::kSE3;
  Alignment alignment;  // maps the estimate's world frame into the ground truth's
  ErrorStats translation_m;
  std::vector<double> errors_m;  // per associated pose
  std::vector<Eigen::Vector3d> p_gt, p_est_aligned;
};
AteResult compute_ate(const PosePairs& pairs, AlignMode mode);

struct RpeResult {
  int delta_frames = 1;
  ErrorStats translation_m;
  ErrorStats rotation_deg;
};
// scale: applied to the estimate's relative translations (use AteResult's alignment scale for sim3).
RpeResult compute_rpe(const PosePairs& pairs, int delta_frames = 1, double scale = 1.0);

struct KittiSegmentError {
  double length_m = 0;
  std::size_t count = 0;
  double t_rel_pct = 0;
  double r_rel_deg_per_100m = 0;
};
struct KittiResult {
  std::vector<KittiSegmentError> per_length;  // only lengths with at least one sub-sequence
  std::size_t count = 0;
  double t_rel_pct = 0;
  double r_rel_deg_per_100m = 0;
};
// nullopt when the ground-truth path is shorter than the shortest segment length.
std::optional<KittiResult> compute_kitti_relative(const PosePairs& pairs, double scale = 1.0,
                                                  const std::vector<double>& lengths_m = {100, 200, 300, 400, 500, 600,
                                                                                          700, 800},
                                                  int step_frames = 10);

double path_length_m(const std::vector<SE3d>& poses);

}  // namespace agvslam::eval
