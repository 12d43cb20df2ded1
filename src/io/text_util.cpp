#include "text_util.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/core/se3.h"

namespace agvslam::io::detail {
namespace fs = std::filesystem;

void require_file(const std::string& path) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(path, "", "file not found");
  if (fs::is_directory(status)) throw InputError(path, "", "expected a file, found a folder");
}

std::string read_text_file(const std::string& path) {
  require_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", std::string("cannot be read: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot be read (I/O error)");
  return buffer.str();
}

bool LineReader::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  const std::size_t end = text_.find('\n', pos_);
  const std::size_t stop = end == std::string::npos ? text_.size() : end;
  line = std::string_view(text_).substr(pos_, stop - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = end == std::string::npos ? text_.size() : end + 1;
  ++line_number_;
  return true;
}

std::string_view trim(std::string_view s) {
  const char* blanks = " \t\r\n\f\v";
  const std::size_t first = s.find_first_not_of(blanks);
  if (first == std::string_view::npos) return {};
  const std::size_t last = s.find_last_not_of(blanks);
  return s.substr(first, last - first + 1);
}

bool is_blank_or_comment(std::string_view line) {
  const std::string_view t = trim(line);
  return t.empty() || t.front() == '#';
}

std::vector<std::string_view> split_tokens(std::string_view line, bool commas_too) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  auto is_sep = [commas_too](char c) { return c == ' ' || c == '\t' || c == '\r' || (commas_too && c == ','); };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_sep(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::vector<std::string_view> split_csv(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(trim(line.substr(start)));
      break;
    }
    fields.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
  return fields;
}

bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  const auto result = std::from_chars(first, last, value);
  if (result.ec == std::errc::result_out_of_range) {
    // Denormal-range or huge values: let strtod decide (it returns 0 or inf, which the caller checks).
    const std::string copy(token);
    char* end = nullptr;
    value = std::strtod(copy.c_str(), &end);
    return end == copy.c_str() + copy.size();
  }
  return result.ec == std::errc() && result.ptr == last;
}

bool parse_int64(std::string_view token, int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* last = token.data() + token.size();
  const auto result = std::from_chars(token.data(), last, value);
  return result.ec == std::errc() && result.ptr == last;
}

namespace {

// Exact "[-+]digits[.digits]" -> value * 10^scale_digits, rounded half away from zero. False on any other form
// (including exponents) or on overflow.
bool parse_plain_decimal_scaled(std::string_view token, int scale_digits, int64_t& out) {
  bool negative = false;
  if (!token.empty() && (token.front() == '-' || token.front() == '+')) {
    negative = token.front() == '-';
    token.remove_prefix(1);
  }
  if (token.empty()) return false;
  const std::size_t dot = token.find('.');
  const std::string_view int_part = token.substr(0, dot);
  const std::string_view frac_part = dot == std::string_view::npos ? std::string_view() : token.substr(dot + 1);
  if (int_part.empty() && frac_part.empty()) return false;
  for (char c : int_part)
    if (c < '0' || c > '9') return false;
  for (char c : frac_part)
    if (c < '0' || c > '9') return false;

  int64_t magnitude = 0;
  for (char c : int_part) {
    if (__builtin_mul_overflow(magnitude, int64_t{10}, &magnitude)) return false;
    if (__builtin_add_overflow(magnitude, int64_t{c - '0'}, &magnitude)) return false;
  }
  for (int k = 0; k < scale_digits; ++k) {
    const int digit = static_cast<std::size_t>(k) < frac_part.size() ? frac_part[static_cast<std::size_t>(k)] - '0' : 0;
    if (__builtin_mul_overflow(magnitude, int64_t{10}, &magnitude)) return false;
    if (__builtin_add_overflow(magnitude, int64_t{digit}, &magnitude)) return false;
  }
  const std::size_t round_pos = static_cast<std::size_t>(scale_digits);
  if (round_pos < frac_part.size() && frac_part[round_pos] >= '5') {
    if (__builtin_add_overflow(magnitude, int64_t{1}, &magnitude)) return false;
  }
  out = negative ? -magnitude : magnitude;
  return true;
}

bool parse_via_double(std::string_view token, double scale, int64_t& out) {
  double value = 0;
  if (!parse_double(token, value) || !std::isfinite(value)) return false;
  const double scaled = value * scale;
  if (std::abs(scaled) > 9.2e18) return false;
  out = static_cast<int64_t>(std::llround(scaled));
  return true;
}

}  // namespace

bool parse_seconds_to_ns(std::string_view token, int64_t& t_ns) {
  if (parse_plain_decimal_scaled(token, 9, t_ns)) return true;
  return parse_via_double(token, 1e9, t_ns);
}

bool parse_ns(std::string_view token, int64_t& t_ns) {
  if (parse_plain_decimal_scaled(token, 0, t_ns)) return true;
  return parse_via_double(token, 1.0, t_ns);
}

std::string format_ns_as_seconds(int64_t t_ns) {
  // Work on the magnitude as unsigned so that INT64_MIN does not overflow.
  const bool negative = t_ns < 0;
  const uint64_t magnitude = negative ? uint64_t{0} - static_cast<uint64_t>(t_ns) : static_cast<uint64_t>(t_ns);
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000ULL),
                static_cast<unsigned long long>(magnitude % 1000000000ULL));
  return buf;
}

std::vector<double> parse_numbers(const std::vector<std::string_view>& tokens, const std::string& path,
                                  const std::string& where, const std::string& what) {
  std::vector<double> values(tokens.size());
  for (std::size_t k = 0; k < tokens.size(); ++k) {
    if (!parse_double(tokens[k], values[k])) {
      throw InputError(path, where,
                       "expected a number for " + what + " (token " + std::to_string(k + 1) + "), found '" +
                           std::string(tokens[k]) + "'");
    }
  }
  return values;
}

void require_finite(const double* values, std::size_t count, const std::string& path, const std::string& where,
                    const std::string& what) {
  for (std::size_t k = 0; k < count; ++k) {
    if (std::isnan(values[k])) throw InputError(path, where, "NaN in " + what);
    if (!std::isfinite(values[k])) throw InputError(path, where, "infinite value in " + what);
  }
}

void require_parent_folder(const std::string& path) {
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw InputError(path, "folder '" + parent.string() + "'",
                     "does not exist (create it first; writers do not create folders)");
  }
}

Eigen::Matrix3d checked_rotation(const Eigen::Matrix3d& R, const std::string& path, const std::string& where) {
  const double orthonormality_error = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (orthonormality_error < 1e-10 && std::abs(det - 1.0) < 1e-10) return R;
  // Text files carry 6 to 17 digits; anything beyond a few percent is a broken file, not rounding.
  if (!(std::abs(det - 1.0) < 0.05) || !(orthonormality_error < 0.05)) {
    char buf[160];
    std::snprintf(buf, sizeof(buf),
                  "expected a rotation matrix (orthonormal, det = 1), found det = %.6g, max |R*R^T - I| = %.3g", det,
                  orthonormality_error);
    throw InputError(path, where, buf);
  }
  return orthonormalize(R);
}

Eigen::Quaterniond checked_quaternion(double qw, double qx, double qy, double qz, const std::string& path,
                                      const std::string& where) {
  const Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) < 0.05)) {
    char buf[120];
    std::snprintf(buf, sizeof(buf), "expected a unit quaternion, found norm %.6g", norm);
    throw InputError(path, where, buf);
  }
  return q.normalized();
}

}  // namespace agvslam::io::detail
