#pragma once
// The plain value the daemon hands to every pose output (DDS, CAN, trajectory file) once per processed frame.
//
// Frames follow REP-105: `map` is the fixed world frame of the SLAM map, `base_link` the vehicle body (x forward,
// y left, z up). The SLAM estimates T_map_cam; the daemon turns it into T_map_base with the camera-to-base_link
// extrinsic before it fills this value.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "agvslam/core/se3.h"

namespace agvslam::drivers {

// Tracking state, in the numbering the DDS status topic and the CAN frames carry.
enum class TrackingState : uint8_t {
  kNotInitialized = 0,  // no map yet (start-up, or after a reset)
  kTracking = 1,        // pose from tracking against the map
  kCoasting = 2,        // tracking lost for a few frames; pose predicted by the motion model
  kLost = 3,            // lost; the pose is the last good one and must not be used for control
};

inline const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "not_initialized";
    case TrackingState::kTracking:
      return "tracking";
    case TrackingState::kCoasting:
      return "coasting";
    case TrackingState::kLost:
      return "lost";
  }
  return "unknown";
}

// The live odometry check (agvslamd's `odometry` section: the SLAM's motion against the vehicle's wheel odometry over
// a sliding window), in the numbering the DDS status topic and the CAN frame AGVSLAM_ODOM_CHECK carry.
enum class OdometryCheckState : uint8_t {
  kOff = 0,              // no odometry input configured
  kNoOdometry = 1,       // configured, but no odometry sample received yet
  kStale = 2,            // no odometry sample for longer than odometry.stale_ms
  kTooLittleMotion = 3,  // the window holds too little travel and turning to judge (or is not full yet)
  kAgrees = 4,
  kDisagrees = 5,  // distance ratio or heading difference outside the tolerance
};

inline const char* to_string(OdometryCheckState state) {
  switch (state) {
    case OdometryCheckState::kOff:
      return "off";
    case OdometryCheckState::kNoOdometry:
      return "no_odometry";
    case OdometryCheckState::kStale:
      return "stale";
    case OdometryCheckState::kTooLittleMotion:
      return "too_little_motion";
    case OdometryCheckState::kAgrees:
      return "agrees";
    case OdometryCheckState::kDisagrees:
      return "disagrees";
  }
  return "unknown";
}

struct OdometryCheck {
  OdometryCheckState state = OdometryCheckState::kOff;
  double distance_ratio = std::nan("");  // SLAM / odometry path length over the window; NaN: not available
  double speed_rmse_mps = 0;             // RMS speed difference over the window's 0.5 s steps
  double heading_difference_deg = 0;     // SLAM heading change - integrated odometry yaw rate over the window
  double window_s = 0;                   // the span the figures cover
};

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct PoseSample {
  // Capture time of the frame this pose belongs to, nanoseconds since the UNIX epoch (CLOCK_REALTIME, the clock
  // ROS 2 stamps with). The daemon converts V4L2's CLOCK_MONOTONIC capture stamps to this clock.
  int64_t t_ns = 0;

  SE3d T_map_base = SE3d::Identity();
  // base_link in the odom frame (REP-105) from the vehicle's wheel odometry integrated to t_ns; valid while an
  // odometry input is current. The map -> odom transform is then T_map_base * T_odom_base^-1.
  bool odom_valid = false;
  SE3d T_odom_base = SE3d::Identity();
  // Covariance of the pose, row-major 6x6 about (x, y, z, rotation about X, about Y, about Z), in m^2, rad^2 and
  // m*rad, as geometry_msgs/PoseWithCovariance defines it (the rotation part is a small rotation of base_link
  // expressed in the map frame's axes).
  Matrix6d cov_pose = Matrix6d::Identity() * 1e-4;

  // Velocity of base_link relative to map, expressed in base_link axes (what nav_msgs/Odometry's twist holds).
  Eigen::Vector3d v_base_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d w_base_radps = Eigen::Vector3d::Zero();
  // Covariance of (v, w), same ordering as cov_pose.
  Matrix6d cov_twist = Matrix6d::Identity() * 1e-4;

  TrackingState tracking_state = TrackingState::kNotInitialized;
  // The SLAM map the pose is in: 0 for the first, +1 each time a long loss started a new map, whose origin is the
  // vehicle where it started, so poses of different map ids must not be compared.
  uint32_t map_id = 0;

  uint64_t frame_index = 0;             // index of the frame since the daemon started
  uint64_t frames_processed = 0;        // frames the tracker processed since start
  uint64_t frames_dropped = 0;          // frames captured but never processed (queue full, unpaired stereo)
  float fps = 0.0F;                     // processed frames per second over the last second
  float dynamic_pixel_fraction = 0.0F;  // 0..1, share of the left image masked as dynamic
  // Capture -> pose handed to the outputs, nanoseconds (measured by the daemon when it hands the sample over).
  int64_t latency_ns = 0;
  OdometryCheck odometry_check;  // filled by the daemon's outputs stage when an odometry input is configured
};

// Yaw (rotation about z of map, radians in (-pi, pi]) of T_map_base, the heading the CAN frames carry.
// (ZYX convention: atan2(R10, R00), exact for a vehicle on a level floor and the usual heading otherwise.)
inline double yaw_rad(const SE3d& T_map_base) {
  const Eigen::Matrix3d& R = T_map_base.linear();
  return std::atan2(R(1, 0), R(0, 0));
}

// A deterministic sample for tools and tests (agvslam-pose-replay --synthetic, the driver tests): the vehicle
// drives a circle of 3 m radius around (-2 m, 3 m) with a small vertical vibration, through every tracking
// state, with every field non-trivial (negative coordinates, yaw wrapping through +-180 degrees, growing
// covariance). `i` is the sample index, `t_ns` its capture time.
inline PoseSample synthetic_pose_sample(uint64_t i, int64_t t_ns) {
  PoseSample s;
  const double k = static_cast<double>(i);
  const double radius_m = 3.0;
  const double phi = 0.05 * k;  // 0.05 rad (0.15 m) per sample
  const double yaw = phi + EIGEN_PI / 2.0;
  s.t_ns = t_ns;
  s.T_map_base = make_se3(
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(0.01 * std::sin(0.3 * k), Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(0.02 * std::cos(0.2 * k), Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(-2.0 + radius_m * std::cos(phi), 3.0 + radius_m * std::sin(phi), 0.004 * std::sin(0.7 * k)));
  s.cov_pose = Matrix6d::Zero();
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) s.cov_pose(r, c) = (r == c ? 1.0 : 0.1) * (1e-4 + 1e-6 * k) * (1.0 + 0.1 * (r + c));
  }
  s.v_base_mps = Eigen::Vector3d(0.5 + 0.01 * std::sin(k), -0.02 * std::cos(k), 0.001 * std::sin(2.0 * k));
  s.w_base_radps = Eigen::Vector3d(0.003 * std::cos(k), -0.002, 0.1667 + 0.01 * std::sin(0.5 * k));
  s.cov_twist = Matrix6d::Identity() * (4e-4 + 1e-7 * k);
  s.tracking_state = static_cast<TrackingState>((i / 7) % 4);
  s.map_id = static_cast<uint32_t>(i / 60 + (i >= 180 ? 70000 : 0));  // a new map now and then; one id above 16 bits
  s.frame_index = 3 * i + 1;
  s.frames_processed = 2 * i + 1;
  s.frames_dropped = i / 5;
  s.fps = 19.5F + 0.25F * static_cast<float>(i % 4);
  s.dynamic_pixel_fraction = static_cast<float>(i % 100) / 100.0F;
  s.latency_ns = 12000000 + static_cast<int64_t>(i % 13) * 1000000 + 12345;
  return s;
}

}  // namespace agvslam::drivers
