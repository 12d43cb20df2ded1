#pragma once
// The live odometry check: the SLAM's poses against the vehicle's wheel odometry over a sliding window, so an
// integrator sees a diverging pose before the vehicle does. No I/O and no clock: it is fed pose samples and
// odometry samples with their time stamps (both CLOCK_REALTIME ns), whatever the odometry's source (CAN today; a
// DDS/ROS 2 odometry subscriber feeds add_odometry() the same way).
//
// Each tracking pose ends a window of window_s seconds; over it, with the arithmetic of the offline check
// (eval::check_against_odometry, the figures `agvslam-eval --odometry` prints):
//   distance ratio    SLAM path length / integrated |speed|
//   speed RMSE        of the two speeds over 0.5 s steps
//   heading           SLAM heading change - integrated yaw rate (degrees)
// and a state: no odometry (none received yet), stale (none for stale_ms), too little motion (the window is not
// full yet, or neither track moved min_distance_m nor turned faster than min_yaw_rate_degps on average), agrees,
// disagrees (while moving, |ratio - 1| > tolerance; or |heading difference| > tolerance * max(|odometry heading
// change|, min_yaw_rate_degps * window): a straight drive is judged against the floor, not against 0).
// A pose that is not tracking breaks the window (the pose jumps when tracking recovers); it fills again from the
// next tracking pose.

#include <cstdint>
#include <deque>

#include "agvslam/core/se3.h"
#include "agvslam/core/trajectory.h"
#include "agvslam/drivers/pose_sample.h"

namespace agvslam::daemon {

struct OdometryMonitorConfig {
  double window_s = 5.0;
  double min_distance_m = 1.0;
  double tolerance = 0.2;
  double min_yaw_rate_degps = 5.0;
  int stale_ms = 500;
  double warn_every_s = 10.0;  // the daemon's warning when the state turns to disagrees, at most this often
};

class OdometryMonitor {
 public:
  explicit OdometryMonitor(const OdometryMonitorConfig& config);

  // A wheel odometry sample. One older than the newest is dropped (counted): integration needs time order.
  void add_odometry(const OdometryRate& sample);
  // A pose sample of the SLAM (T_map_base, base_link axes); returns the check at its time.
  drivers::OdometryCheck add_pose(int64_t t_ns, const SE3d& T_map_base, bool tracking);
  // The check at t_ns without a new pose (heartbeats): the last figures, with no-odometry / stale judged at t_ns.
  drivers::OdometryCheck status_at(int64_t t_ns) const;

  uint64_t odometry_samples() const { return odometry_samples_; }
  uint64_t odometry_out_of_order() const { return odometry_out_of_order_; }
  const OdometryMonitorConfig& config() const { return config_; }

 private:
  // no odometry / stale at t_ns, or nullopt-like kOff when neither applies.
  drivers::OdometryCheckState odometry_state(int64_t t_ns) const;
  drivers::OdometryCheck evaluate() const;

  OdometryMonitorConfig config_;
  std::deque<StampedPose> poses_;      // tracking poses of the current window (T_w_c holds T_map_base)
  std::deque<OdometryRate> odometry_;  // samples covering the window
  drivers::OdometryCheck last_;
  uint64_t odometry_samples_ = 0, odometry_out_of_order_ = 0;
};

}  // namespace agvslam::daemon
