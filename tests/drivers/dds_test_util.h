#pragma once
// Shared by the DDS tests: a private network namespace for the two-process cases, and the tools' JSON lines.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/test_data.h"

namespace agvslam::test {

// The command prefix that runs a shell in a fresh network namespace with lo up, or "" when not permitted.
inline std::string netns_prefix() {
  if (run_command("unshare -n true") == 0) return "unshare -n";
  if (run_command("unshare -rn true") == 0) return "unshare -rn";
  return "";
}

// One JSON object per non-empty line of `path`.
inline std::vector<nlohmann::json> read_json_lines(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) out.push_back(nlohmann::json::parse(line));
  }
  return out;
}

}  // namespace agvslam::test

// Declares `prefix` (the netns command prefix); skips the test where unshare -n is not permitted (fails under
// CI=true).
#define REQUIRE_NETNS(prefix)                                                                               \
  const std::string prefix = agvslam::test::netns_prefix();                                                 \
  if (prefix.empty()) {                                                                                     \
    if (agvslam::test::running_in_ci()) FAIL() << "unshare -n is not permitted here and CI=true";           \
    GTEST_SKIP() << "unshare -n (a private network namespace) is not permitted here; run as root or where " \
                    "unprivileged user namespaces are enabled";                                             \
  }
