#pragma once
// Private helpers of the io module: reading text files line by line with line numbers, strict number parsing
// and exact decimal time stamps. Every failure is an InputError naming the file, the line and what was expected.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace agvslam::io::detail {

// Whole file as text. Throws InputError(path, "", "file not found") / "cannot be read".
std::string read_text_file(const std::string& path);

// Throws InputError(path, "", "file not found") when path is not an existing regular file.
void require_file(const std::string& path);

// Walks a text buffer line by line; line numbers start at 1, a trailing '\r' is dropped.
class LineReader {
 public:
  LineReader(std::string path, std::string text) : path_(std::move(path)), text_(std::move(text)) {}
  // Next line (true), or false at the end of the text.
  bool next(std::string_view& line);
  int line_number() const { return line_number_; }
  const std::string& path() const { return path_; }
  std::string where() const { return "line " + std::to_string(line_number_); }

 private:
  std::string path_;
  std::string text_;
  std::size_t pos_ = 0;
  int line_number_ = 0;
};

std::string_view trim(std::string_view s);
// True for an empty (after trimming) line or one whose first non-blank character is '#'.
bool is_blank_or_comment(std::string_view line);
// Splits on blanks (spaces, tabs) and, when commas_too, on commas as well. Empty tokens are dropped.
std::vector<std::string_view> split_tokens(std::string_view line, bool commas_too);
// Splits on commas only, keeping empty fields (trimmed).
std::vector<std::string_view> split_csv(std::string_view line);

// Parses a whole token as a double (locale-independent). Returns false when the token is not a number.
// "nan" and "inf" parse (the caller checks finiteness to give a precise message).
bool parse_double(std::string_view token, double& value);
bool parse_int64(std::string_view token, int64_t& value);

// Exact conversion of a decimal number of seconds ("1403715273.262142976", "0.1", "1.044989e-01") or
// nanoseconds ("1403715273262142976", "1403715273262142976.000") into integer nanoseconds. Plain decimals are
// converted digit by digit (no double rounding); exponent forms go through double.
bool parse_seconds_to_ns(std::string_view token, int64_t& t_ns);
bool parse_ns(std::string_view token, int64_t& t_ns);

// Formats t_ns as seconds with all nine decimals ("1403715273.262142976", "-0.000000001").
std::string format_ns_as_seconds(int64_t t_ns);

// Parses all tokens as finite-or-not doubles; on a non-numeric token throws
// InputError(path, where, "expected a number for <what> (token k), found 'x'").
std::vector<double> parse_numbers(const std::vector<std::string_view>& tokens, const std::string& path,
                                  const std::string& where, const std::string& what);

// Throws InputError(path, where, "NaN in <what>" / "infinite value in <what>") when any value is not finite.
void require_finite(const double* values, std::size_t count, const std::string& path, const std::string& where,
                    const std::string& what);

// Ensures the folder that will hold `path` exists; else InputError naming the folder.
void require_parent_folder(const std::string& path);

// A rotation read from text: returned as is when orthonormal within 1e-10, projected onto SO(3) when slightly
// off (text precision), InputError(path, where, ...) when clearly invalid (det far from 1, not orthonormal).
Eigen::Matrix3d checked_rotation(const Eigen::Matrix3d& R, const std::string& path, const std::string& where);
// A quaternion read from text, normalised; InputError when its norm is far from 1.
Eigen::Quaterniond checked_quaternion(double qw, double qx, double qy, double qz, const std::string& path,
                                      const std::string& where);

}  // namespace agvslam::io::detail
