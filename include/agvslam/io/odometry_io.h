#pragma once
// Wheel odometry as a vehicle controller reports it: CSV "t_s, speed_mps, yaw_rate_radps", one sample a line
// (t in seconds; speed along the floor, m/s, negative when reversing; yaw rate about the floor normal, rad/s,
// counter-clockwise seen from above, as REP-103's z-up yaw). Lines starting with '#' and a first line of column
// names are skipped. Time stamps must increase. The pose form of wheel odometry is a TUM trajectory
// (trajectory_io.h).

#include <string>
#include <vector>

#include "agvslam/core/trajectory.h"

namespace agvslam::io {

// Throws InputError naming the file, the line and what was expected (three numbers, finite, increasing time).
std::vector<OdometryRate> read_odometry_csv(const std::string& path);

// True when the file's first data line has three comma-separated fields (the rate CSV) rather than a pose.
bool looks_like_odometry_csv(const std::string& path);

}  // namespace agvslam::io
