#include "common/test_data.h"

#include <sys/wait.h>
#include <unistd.h>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <random>
#include <vector>

namespace agvslam::test {
namespace fs = std::filesystem;

std::string shared_dir() {
  if (const char* env = std::getenv("AGVSLAM_SHARED_DIR"); env && *env) return env;
  return AGVSLAM_SHARED_DIR;
}

std::optional<std::string> shared_path(const std::string& rel) {
  const fs::path p = fs::path(shared_dir()) / rel;
  std::error_code ec;
  if (!fs::exists(p, ec)) return std::nullopt;
  return fs::weakly_canonical(p, ec).string();
}

bool running_in_ci() {
  const char* ci = std::getenv("CI");
  return ci && (std::string(ci) == "true" || std::string(ci) == "1");
}

std::string binary_dir() { return AGVSLAM_BINARY_DIR; }

std::string tool_path(const std::string& name) { return (fs::path(binary_dir()) / "bin" / name).string(); }

namespace {

// The folders make_temp_dir made in this process, removed when it exits unless a test failed (then they stay for
// inspection) or AGVSLAM_KEEP_TEST_DIRS is set. Only the process that made them removes them: a forked child that
// exits normally leaves them alone.
struct TempDirRegistry {
  std::mutex mutex;
  std::vector<fs::path> dirs;
  pid_t owner = 0;
};

TempDirRegistry& temp_dir_registry() {
  static TempDirRegistry* registry = new TempDirRegistry;  // never destroyed: the atexit handler uses it
  return *registry;
}

void remove_temp_dirs_at_exit() {
  TempDirRegistry& reg = temp_dir_registry();
  if (getpid() != reg.owner) return;
  const char* keep = std::getenv("AGVSLAM_KEEP_TEST_DIRS");
  if ((keep && *keep) || ::testing::UnitTest::GetInstance()->Failed()) return;
  std::lock_guard<std::mutex> lock(reg.mutex);
  for (const fs::path& p : reg.dirs) {
    std::error_code ec;
    fs::remove_all(p, ec);
  }
}

void register_temp_dir(const fs::path& p) {
  TempDirRegistry& reg = temp_dir_registry();
  std::lock_guard<std::mutex> lock(reg.mutex);
  if (reg.owner == 0) {
    reg.owner = getpid();
    std::atexit(remove_temp_dirs_at_exit);  // registered after gtest's singleton exists, so it runs before its end
  }
  reg.dirs.push_back(p);
}

}  // namespace

std::string make_temp_dir(const std::string& prefix) {
  std::random_device rd;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path p = fs::temp_directory_path() / (prefix + "-" + std::to_string(rd()));
    std::error_code ec;
    if (fs::create_directory(p, ec)) {
      register_temp_dir(p);
      return p.string();
    }
  }
  throw std::runtime_error("make_temp_dir: could not create a folder under " + fs::temp_directory_path().string());
}

int run_command(const std::string& cmd, std::string* output) {
  const std::string full = cmd + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return -1;
  std::array<char, 4096> buf{};
  std::string out;
  while (fgets(buf.data(), static_cast<int>(buf.size()), pipe)) out += buf.data();
  const int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace agvslam::test
