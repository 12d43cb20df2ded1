#pragma once
// Access to the real data in ../shared/data and to the built tools, for tests.
//
// AGVSLAM_REQUIRE_SHARED(rel): resolves rel under the shared folder (env AGVSLAM_SHARED_DIR overrides the
// configured one). When it is missing the test is skipped with a message saying so, except under CI=true,
// where a missing data set is a failure.

#include <gtest/gtest.h>

#include <optional>
#include <string>

namespace agvslam::test {

std::string shared_dir();
// Path of rel under the shared folder, or nullopt if it does not exist.
std::optional<std::string> shared_path(const std::string& rel);
bool running_in_ci();
// The build folder (tools live in <build>/bin).
std::string binary_dir();
std::string tool_path(const std::string& name);
// A new empty temporary folder; removed when the test process exits, unless a test failed (left for inspection)
// or AGVSLAM_KEEP_TEST_DIRS is set.
std::string make_temp_dir(const std::string& prefix);
// Runs a shell command, returns its exit status; stdout+stderr go to `output` when given.
int run_command(const std::string& cmd, std::string* output = nullptr);

}  // namespace agvslam::test

#define AGVSLAM_REQUIRE_SHARED(var, rel)                                                                \
  std::string var;                                                                                      \
  {                                                                                                     \
    auto agvslam_p_ = ::agvslam::test::shared_path(rel);                                                \
    if (!agvslam_p_) {                                                                                  \
      if (::agvslam::test::running_in_ci()) {                                                           \
        FAIL() << "shared data " << (rel) << " is missing under " << ::agvslam::test::shared_dir()      \
               << " and CI=true: CI must have ../shared beside the checkout";                           \
      } else {                                                                                          \
        GTEST_SKIP() << "shared data " << (rel) << " not found under " << ::agvslam::test::shared_dir() \
                     << " (set AGVSLAM_SHARED_DIR to the shared/ folder to run this test)";             \
      }                                                                                                 \
    }                                                                                                   \
    var = *agvslam_p_;                                                                                  \
  }
