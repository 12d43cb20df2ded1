#pragma once
// Errors raised at I/O boundaries (files, devices, command-line values).
//
// Every message names the source (a file path, a device, an option), where in it the problem is (a line,
// a field, a key) and what was expected, e.g.
//   "data/calib.txt: line 2: expected 12 numbers after 'P1:', found 11"

#include <stdexcept>
#include <string>

namespace agvslam {

class InputError : public std::runtime_error {
 public:
  InputError(std::string source, std::string where, std::string expected);

  const std::string& source() const noexcept { return source_; }
  const std::string& where() const noexcept { return where_; }
  const std::string& expected() const noexcept { return expected_; }

 private:
  std::string source_;
  std::string where_;
  std::string expected_;
};

}  // namespace agvslam
