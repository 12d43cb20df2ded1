#pragma once
// Helpers shared by the io tests: a temporary folder removed at the end of the test, writing small text files,
// and checking an InputError's message.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>

#include "agvslam/core/error.h"
#include "common/test_data.h"

namespace agvslam::io::testing {

class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "agvslam-io-test") : path_(agvslam::test::make_temp_dir(prefix)) {}
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return (std::filesystem::path(path_) / name).string(); }
  // Writes text to <dir>/name (creating parent folders) and returns the full path.
  std::string write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = std::filesystem::path(path_) / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out << text;
    return p.string();
  }

 private:
  std::string path_;
};

// Runs fn, expects an InputError whose message contains every one of the pieces.
inline void expect_input_error(const std::function<void()>& fn, std::initializer_list<std::string> pieces) {
  try {
    fn();
    ADD_FAILURE() << "expected an InputError containing '" << *pieces.begin() << "', nothing was thrown";
  } catch (const agvslam::InputError& e) {
    const std::string message = e.what();
    for (const std::string& piece : pieces) {
      EXPECT_NE(message.find(piece), std::string::npos) << "message: " << message << "\nmissing: " << piece;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected an InputError, got another exception: " << e.what();
  }
}

}  // namespace agvslam::io::testing
