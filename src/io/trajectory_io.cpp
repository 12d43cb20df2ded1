#include "agvslam/io/trajectory_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "agvslam/core/error.h"
#include "text_util.h"

namespace agvslam::io {
namespace fs = std::filesystem;
using detail::LineReader;

TrajectoryFormat parse_trajectory_format(const std::string& value, const std::string& option_name) {
  if (value == "tum") return TrajectoryFormat::kTum;
  if (value == "kitti") return TrajectoryFormat::kKitti;
  if (value == "euroc") return TrajectoryFormat::kEuroc;
  throw InputError(option_name, value, "expected tum, kitti or euroc");
}

std::string to_string(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "unknown";
}

TrajectoryFormat guess_trajectory_format(const std::string& path) {
  LineReader reader(path, detail::read_text_file(path));
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    if (line.find(',') != std::string_view::npos) return TrajectoryFormat::kEuroc;
    const std::size_t count = detail::split_tokens(line, false).size();
    if (count == 8) return TrajectoryFormat::kTum;
    if (count == 12) return TrajectoryFormat::kKitti;
    throw InputError(path, reader.where(),
                     "expected 8 numbers (TUM), 12 numbers (KITTI) or a comma-separated EuRoC row, found " +
                         std::to_string(count) + " fields");
  }
  throw InputError(path, "", "expected at least one pose line, found none");
}

Trajectory read_tum(const std::string& path) {
  LineReader reader(path, detail::read_text_file(path));
  Trajectory trajectory;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::string where = reader.where();
    const auto tokens = detail::split_tokens(line, false);
    if (tokens.size() != 8) {
      throw InputError(path, where,
                       "expected 8 numbers 't tx ty tz qx qy qz qw', found " + std::to_string(tokens.size()));
    }
    const std::vector<double> v = detail::parse_numbers(tokens, path, where, "pose");
    detail::require_finite(v.data(), v.size(), path, where, "pose");
    StampedPose pose;
    if (!detail::parse_seconds_to_ns(tokens[0], pose.t_ns)) {
      throw InputError(path, where, "expected a time stamp in seconds, found '" + std::string(tokens[0]) + "'");
    }
    const Eigen::Quaterniond q = detail::checked_quaternion(v[7], v[4], v[5], v[6], path, where);
    pose.T_w_c = make_se3(q, Eigen::Vector3d(v[1], v[2], v[3]));
    trajectory.push_back(pose);
  }
  return trajectory;
}

namespace {

SE3d pose_from_12(const std::vector<double>& v, const std::string& path, const std::string& where) {
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  const Eigen::Vector3d t(v[3], v[7], v[11]);
  return make_se3(detail::checked_rotation(R, path, where), t);
}

}  // namespace

Trajectory read_kitti_poses(const std::string& path, const std::vector<int64_t>* times_ns) {
  LineReader reader(path, detail::read_text_file(path));
  Trajectory trajectory;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::string where = reader.where();
    const auto tokens = detail::split_tokens(line, false);
    if (tokens.size() != 12) {
      throw InputError(path, where,
                       "expected 12 numbers (3x4 pose, row-major), found " + std::to_string(tokens.size()));
    }
    const std::vector<double> v = detail::parse_numbers(tokens, path, where, "pose");
    detail::require_finite(v.data(), v.size(), path, where, "pose");
    StampedPose pose;
    // 10 Hz when no times are given (KITTI odometry's nominal rate).
    pose.t_ns = static_cast<int64_t>(trajectory.size()) * 100'000'000;
    pose.T_w_c = pose_from_12(v, path, where);
    trajectory.push_back(pose);
  }
  if (times_ns) {
    if (times_ns->size() != trajectory.size()) {
      throw InputError(path, "line count",
                       "expected " + std::to_string(times_ns->size()) + " poses (one per time stamp), found " +
                           std::to_string(trajectory.size()));
    }
    for (std::size_t i = 0; i < trajectory.size(); ++i) trajectory[i].t_ns = (*times_ns)[i];
  }
  return trajectory;
}

Trajectory read_euroc_csv(const std::string& path) {
  LineReader reader(path, detail::read_text_file(path));
  Trajectory trajectory;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::string where = reader.where();
    const auto fields = detail::split_csv(line);
    // The EuRoC ground-truth CSV has 17 columns (pose, velocity, biases); only the first 8 are the pose.
    if (fields.size() < 8) {
      throw InputError(path, where,
                       "expected at least 8 comma-separated numbers 't_ns, x, y, z, qw, qx, qy, qz', found " +
                           std::to_string(fields.size()));
    }
    const std::vector<std::string_view> pose_fields(fields.begin(), fields.begin() + 8);
    const std::vector<double> v = detail::parse_numbers(pose_fields, path, where, "pose");
    detail::require_finite(v.data(), v.size(), path, where, "pose");
    StampedPose pose;
    if (!detail::parse_ns(fields[0], pose.t_ns)) {
      throw InputError(path, where, "expected a time stamp in nanoseconds, found '" + std::string(fields[0]) + "'");
    }
    const Eigen::Quaterniond q = detail::checked_quaternion(v[4], v[5], v[6], v[7], path, where);
    pose.T_w_c = make_se3(q, Eigen::Vector3d(v[1], v[2], v[3]));
    trajectory.push_back(pose);
  }
  return trajectory;
}

Trajectory read_trajectory(const std::string& path, TrajectoryFormat format,
                           const std::optional<std::string>& times_path) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return read_tum(path);
    case TrajectoryFormat::kEuroc:
      return read_euroc_csv(path);
    case TrajectoryFormat::kKitti:
      if (times_path) {
        const std::vector<int64_t> times_ns = read_kitti_times(*times_path);
        return read_kitti_poses(path, &times_ns);
      }
      return read_kitti_poses(path);
  }
  throw InputError(path, "format", "expected tum, kitti or euroc");
}

std::vector<int64_t> read_kitti_times(const std::string& path) {
  LineReader reader(path, detail::read_text_file(path));
  std::vector<int64_t> times_ns;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto tokens = detail::split_tokens(line, false);
    if (tokens.size() != 1) {
      throw InputError(path, reader.where(),
                       "expected 1 number (time in seconds), found " + std::to_string(tokens.size()));
    }
    double value = 0;
    if (!detail::parse_double(tokens[0], value)) {
      throw InputError(path, reader.where(), "expected a time in seconds, found '" + std::string(tokens[0]) + "'");
    }
    detail::require_finite(&value, 1, path, reader.where(), "time stamp");
    int64_t t_ns = 0;
    if (!detail::parse_seconds_to_ns(tokens[0], t_ns)) {
      throw InputError(path, reader.where(),
                       "expected a time in seconds within +-292 years, found '" + std::string(tokens[0]) + "'");
    }
    times_ns.push_back(t_ns);
  }
  return times_ns;
}

namespace {

void append_line(std::string& out, const char* text) {
  out += text;
  out += '\n';
}

}  // namespace

void write_tum(const std::string& path, const Trajectory& trajectory) {
  std::string out;
  out.reserve(96 * trajectory.size() + 64);
  out += "# t tx ty tz qx qy qz qw\n";
  char buf[320];
  for (const StampedPose& pose : trajectory) {
    Eigen::Quaterniond q(pose.T_w_c.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1.0;
    const Eigen::Vector3d t = pose.T_w_c.translation();
    std::snprintf(buf, sizeof(buf), "%s %.10f %.10f %.10f %.12f %.12f %.12f %.12f",
                  detail::format_ns_as_seconds(pose.t_ns).c_str(), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    append_line(out, buf);
  }
  write_file_atomically(path, out);
}

void write_kitti_poses(const std::string& path, const Trajectory& trajectory) {
  std::string out;
  out.reserve(240 * trajectory.size());
  char buf[400];
  for (const StampedPose& pose : trajectory) {
    const Eigen::Matrix4d M = pose.T_w_c.matrix();
    int len = 0;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        len += std::snprintf(buf + len, sizeof(buf) - static_cast<std::size_t>(len), "%s%.12e",
                             (r == 0 && c == 0) ? "" : " ", M(r, c));
      }
    }
    append_line(out, buf);
  }
  write_file_atomically(path, out);
}

void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      write_tum(path, trajectory);
      return;
    case TrajectoryFormat::kKitti:
      write_kitti_poses(path, trajectory);
      return;
    case TrajectoryFormat::kEuroc: {
      std::string out =
          "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n";
      char buf[320];
      for (const StampedPose& pose : trajectory) {
        Eigen::Quaterniond q(pose.T_w_c.linear());
        q.normalize();
        if (q.w() < 0) q.coeffs() *= -1.0;
        const Eigen::Vector3d t = pose.T_w_c.translation();
        std::snprintf(buf, sizeof(buf), "%lld,%.10f,%.10f,%.10f,%.12f,%.12f,%.12f,%.12f",
                      static_cast<long long>(pose.t_ns), t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z());
        append_line(out, buf);
      }
      write_file_atomically(path, out);
      return;
    }
  }
}

void write_kitti_times(const std::string& path, const std::vector<int64_t>& times_ns) {
  std::string out;
  out.reserve(24 * times_ns.size());
  for (const int64_t t_ns : times_ns) {
    out += detail::format_ns_as_seconds(t_ns);
    out += '\n';
  }
  write_file_atomically(path, out);
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  detail::require_parent_folder(path);
  const std::string tmp_path = path + ".tmp";
  auto fail = [&](const std::string& what) {
    const std::string reason = what + ": " + std::strerror(errno);
    ::unlink(tmp_path.c_str());
    throw InputError(path, "", "cannot write (" + reason + ")");
  };
  const int fd = ::open(tmp_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("open " + tmp_path);
  std::size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int saved = errno;
      ::close(fd);
      errno = saved;
      fail("write");
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int saved = errno;
    ::close(fd);
    errno = saved;
    fail("fsync");
  }
  if (::close(fd) != 0) fail("close");
  if (::rename(tmp_path.c_str(), path.c_str()) != 0) fail("rename " + tmp_path);
  // Make the rename itself durable; failure here leaves a complete file, so it is not an error.
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) parent = ".";
  const int dir_fd = ::open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

}  // namespace agvslam::io
