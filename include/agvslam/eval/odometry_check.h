#pragma once
// Consistency of a trajectory with the vehicle's wheel odometry, for vehicles without ground truth: a pose that
// drifts or jumps shows as motion the wheels did not make. Both are reduced to planar motion on the floor: the
// distance travelled (path length) and the heading (yaw about the floor normal), each accumulated over time; the
// trajectory is then compared with the odometry over the time both cover:
//   distance ratio     trajectory path length / odometry path length (wheel odometry carries its own scale error,
//                      typically 0.5-2 %, so a ratio is judged against a tolerance, not against 1 exactly)
//   speed RMSE         over windows of window_s seconds
//   heading            total heading change of each over the run, their difference, and the largest difference of
//                      the accumulated headings at any time (m/s and degrees)
//   disagreements      the windows where the distances (or, while turning, the heading changes) differ by more than
//                      disagreement_ratio, as frame ranges of the trajectory

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "agvslam/core/trajectory.h"

namespace agvslam::eval {

// The body axes of a pose: which axis is up (the floor normal) and which is forward.
//   kCamera  the project's camera frame: x right, y down, z forward (up = -y)
//   kBase    REP-103 base_link: x forward, y left, z up
enum class BodyAxes { kCamera, kBase };
// "camera" | "base"; InputError(option, value, ...) otherwise.
BodyAxes parse_body_axes(const std::string& value, const std::string& option);

// Distance travelled and heading, accumulated from the first sample (m, rad; heading counter-clockwise seen from
// above).
struct PlanarTrack {
  std::vector<int64_t> t_ns;
  std::vector<double> distance_m;
  std::vector<double> heading_rad;
};
// From poses: per step, the distance is the translation's length in the floor plane (the plane normal to the first
// pose's up axis), the heading change the rotation's twist about the body's up axis.
PlanarTrack planar_track(const Trajectory& poses, BodyAxes axes);
// From speed and yaw rate, integrated with the trapezoidal rule (|speed|: a reversing vehicle travels too).
PlanarTrack planar_track(const std::vector<OdometryRate>& rates);

struct OdometryCheckConfig {
  double window_s = 0.5;             // speeds and disagreements are judged over windows of this length (s)
  double disagreement_ratio = 0.2;   // a window disagrees when distances differ by more than this fraction
  double min_speed_mps = 0.1;        // below this the vehicle stands: small distances are not compared as ratios
  double min_yaw_rate_degps = 5;     // heading changes are compared as ratios only while turning faster than this
  double distance_tolerance = 0.03;  // |distance ratio - 1| above this is reported as a scale disagreement
};

struct OdometryDisagreement {
  std::size_t first_frame = 0, last_frame = 0;  // trajectory indices (inclusive)
  double t_first_s = 0, t_last_s = 0;           // seconds from the trajectory's first pose
  double trajectory_m = 0, odometry_m = 0;      // distances over the range
  double trajectory_heading_deg = 0, odometry_heading_deg = 0;
};

struct OdometryCheckResult {
  std::size_t frames_compared = 0;  // trajectory poses inside the odometry's time span
  std::size_t windows = 0;
  double duration_s = 0;
  double trajectory_distance_m = 0, odometry_distance_m = 0;
  double distance_ratio = 0;  // trajectory / odometry; NaN when the odometry did not move
  bool distance_within_tolerance = true;
  double speed_rmse_mps = 0;
  double trajectory_heading_change_deg = 0, odometry_heading_change_deg = 0;
  double heading_difference_deg = 0;      // trajectory - odometry over the whole run
  double max_heading_difference_deg = 0;  // largest |accumulated difference| at any compared pose
  std::size_t disagreeing_windows = 0;
  std::vector<OdometryDisagreement> disagreements;  // consecutive disagreeing windows merged
};

// Throws InputError(source, ...) when the trajectory and the odometry share less than two poses in time.
OdometryCheckResult check_against_odometry(const Trajectory& trajectory, BodyAxes trajectory_axes,
                                           const PlanarTrack& odometry, const OdometryCheckConfig& config = {},
                                           const std::string& source = "odometry");

}  // namespace agvslam::eval
