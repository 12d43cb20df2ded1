#include "agvslam/io/odometry_io.h"

#include <cmath>

#include "agvslam/core/error.h"
#include "text_util.h"

namespace agvslam::io {

using detail::LineReader;

std::vector<OdometryRate> read_odometry_csv(const std::string& path) {
  LineReader lines(path, detail::read_text_file(path));
  std::vector<OdometryRate> samples;
  std::string_view line;
  bool first_data_line = true;
  while (lines.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto fields = detail::split_csv(line);
    double probe = 0;
    if (first_data_line && !fields.empty() && !detail::parse_double(fields[0], probe)) {
      first_data_line = false;  // a header of column names
      continue;
    }
    first_data_line = false;
    if (fields.size() != 3) {
      throw InputError(
          path, lines.where(),
          "expected 3 comma-separated fields (t_s, speed_mps, yaw_rate_radps), found " + std::to_string(fields.size()));
    }
    OdometryRate s;
    if (!detail::parse_seconds_to_ns(fields[0], s.t_ns)) {
      throw InputError(path, lines.where(),
                       "expected a time in seconds as field 1, found '" + std::string(fields[0]) + "'");
    }
    const std::vector<double> v =
        detail::parse_numbers({fields[1], fields[2]}, path, lines.where(), "speed and yaw rate");
    detail::require_finite(v.data(), v.size(), path, lines.where(), "speed and yaw rate");
    s.speed_mps = v[0];
    s.yaw_rate_radps = v[1];
    if (!samples.empty() && s.t_ns <= samples.back().t_ns) {
      throw InputError(path, lines.where(),
                       "expected time stamps that increase (" + detail::format_ns_as_seconds(s.t_ns) + " s after " +
                           detail::format_ns_as_seconds(samples.back().t_ns) + " s)");
    }
    samples.push_back(s);
  }
  if (samples.size() < 2)
    throw InputError(path, "", "expected at least 2 odometry samples, found " + std::to_string(samples.size()));
  return samples;
}

bool looks_like_odometry_csv(const std::string& path) {
  LineReader lines(path, detail::read_text_file(path));
  std::string_view line;
  while (lines.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto fields = detail::split_csv(line);
    double probe = 0;
    if (!fields.empty() && !detail::parse_double(fields[0], probe)) continue;  // a header
    return fields.size() == 3;
  }
  return false;
}

}  // namespace agvslam::io
