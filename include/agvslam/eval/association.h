#pragma once
// Pairs poses of an estimated trajectory with ground truth: by index (KITTI files without time stamps) or
// by nearest time stamp within a tolerance (TUM, EuRoC).

#include <cstdint>
#include <vector>

#include "agvslam/core/trajectory.h"

namespace agvslam::eval {

struct PosePairs {
  std::vector<int64_t> t_ns;    // time of the estimated pose
  std::vector<SE3d> T_w_c_gt;   // ground truth, in the ground-truth world frame
  std::vector<SE3d> T_w_c_est;  // estimate, in the estimator's world frame
  std::size_t size() const { return t_ns.size(); }
};

PosePairs associate_by_index(const Trajectory& gt, const Trajectory& est);
// Each estimate is paired with the ground-truth pose nearest in time if |dt| <= max_dt_ns; a ground-truth pose is
// used at most once. Both inputs need not be sorted.
PosePairs associate_by_timestamp(const Trajectory& gt, const Trajectory& est, int64_t max_dt_ns);

}  // namespace agvslam::eval
