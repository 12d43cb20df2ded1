#pragma once
// A trajectory is a time-ordered list of camera poses T_w_c (camera c = rectified left camera).

#include <cstdint>
#include <vector>

#include "agvslam/core/se3.h"

namespace agvslam {

struct StampedPose {
  int64_t t_ns = 0;
  SE3d T_w_c = SE3d::Identity();
};

using Trajectory = std::vector<StampedPose>;

// Wheel odometry as a vehicle controller reports it: speed along the floor (m/s, negative when reversing) and yaw
// rate about the floor normal (rad/s, counter-clockwise seen from above, REP-103's z-up yaw).
struct OdometryRate {
  int64_t t_ns = 0;
  double speed_mps = 0;
  double yaw_rate_radps = 0;
};

inline double ns_to_s(int64_t t_ns) { return static_cast<double>(t_ns) * 1e-9; }
int64_t s_to_ns(double t_s);

}  // namespace agvslam
