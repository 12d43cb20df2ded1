#pragma once
// Trajectory files.
//   TUM:   one pose a line, "t tx ty tz qx qy qz qw" (t in seconds, '#' comments allowed).
//   KITTI: one pose a line, 12 numbers: the first three rows of T_w_cam0, row-major. No time stamps;
//          times come from a separate times.txt (seconds, one a line) or are the line index.
//   EuRoC: CSV "t_ns, x, y, z, qw, qx, qy, qz" (header line starting with '#').
// Readers throw InputError naming the file, the line and what was expected (count of numbers, NaN, ...).
// Writers write to "<path>.tmp" and rename, so a reader never sees a half-written file.

#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/trajectory.h"

namespace agvslam::io {

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

// "tum" | "kitti" | "euroc"; throws InputError(option_name, value, "expected tum, kitti or euroc").
TrajectoryFormat parse_trajectory_format(const std::string& value, const std::string& option_name = "format");
std::string to_string(TrajectoryFormat format);
// Guess from the first data line: 8 numbers -> TUM, 12 -> KITTI, comma separated -> EuRoC.
TrajectoryFormat guess_trajectory_format(const std::string& path);

Trajectory read_tum(const std::string& path);
// With times_ns, its size must equal the number of poses (else InputError); without, t_ns = index * 1e9 / 10.
Trajectory read_kitti_poses(const std::string& path, const std::vector<int64_t>* times_ns = nullptr);
Trajectory read_euroc_csv(const std::string& path);
Trajectory read_trajectory(const std::string& path, TrajectoryFormat format,
                           const std::optional<std::string>& times_path = std::nullopt);

void write_tum(const std::string& path, const Trajectory& trajectory);
void write_kitti_poses(const std::string& path, const Trajectory& trajectory);
void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format);

// KITTI times.txt: seconds, one a line.
std::vector<int64_t> read_kitti_times(const std::string& path);
void write_kitti_times(const std::string& path, const std::vector<int64_t>& times_ns);

// Writes `contents` to path atomically (temporary file in the same folder, fsync, rename).
void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace agvslam::io
