#pragma once
// Wheel odometry of a differential-drive AGV, simulated from its ground-truth camera trajectory.
//
// Between consecutive frames the vehicle's planar motion (distance travelled along the floor and yaw change
// about the floor normal) is taken from the ground truth and corrupted the way real wheel odometry is:
// a distance scale error (wheel radius), a yaw rate bias per metre (wheel radius mismatch / track width) and
// white noise on both. The corrupted increments are integrated on the floor plane, so the result drifts
// without bound as dead reckoning does. Frames: camera x right, y down, z forward; the floor normal is -y of
// the first camera frame, which is also the odometry's world frame.

#include <cstdint>

#include "agvslam/core/trajectory.h"

namespace agvslam::sim {

struct WheelOdometryConfig {
  double distance_scale_error = 0.01;  // +1 %: the wheels read 1 % too far
  double yaw_bias_rad_per_m = 0.004;   // systematic heading drift
  double distance_noise_m_per_sqrt_m = 0.005;
  double yaw_noise_rad_per_sqrt_m = 0.003;
  double yaw_noise_rad_per_rad = 0.01;  // noise proportional to the turned angle
};

// gt: T_w_c of the camera (one pose per frame); returns the odometry poses at the same time stamps.
Trajectory simulate_wheel_odometry(const Trajectory& gt, const WheelOdometryConfig& config, uint64_t seed);

}  // namespace agvslam::sim
