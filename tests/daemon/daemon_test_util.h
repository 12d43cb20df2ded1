#pragma once
// Helpers for the daemon's tests: a short simulator sequence rendered once per build folder, YAML files, child
// processes with signals, JSON-lines files, and the private network namespace the DDS tests run in.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/test_data.h"

extern char** environ;

namespace agvslam::test {

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::vector<nlohmann::json> read_json_lines(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '{') out.push_back(nlohmann::json::parse(line));
  }
  return out;
}

inline std::size_t count_data_lines(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') ++n;
  }
  return n;
}

// scene2 of the simulator (the straight aisle, a person crossing), seed 11, 80 frames at 20 Hz, 752x480: rendered
// once into <build>/test-data/daemon_scene2 and reused (the first test that needs it pays ~10 s).
// A KITTI-layout folder of n 64x48 frames at 20 Hz; left image i is filled with 10 * i, the right with 10 * i + 1.
// With masks, mask_0/ marks column i of frame i as moving.
inline std::string tiny_dataset(int n, bool with_masks = false) {
  const std::string dir = make_temp_dir("agvslamd-source");
  for (const char* sub : {"/image_0", "/image_1", "/mask_0"}) {
    if (with_masks || std::string(sub) != "/mask_0") std::filesystem::create_directories(dir + sub);
  }
  std::string times;
  for (int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/%06d.png", i);
    cv::imwrite(dir + "/image_0" + name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(10 * i)));
    cv::imwrite(dir + "/image_1" + name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(10 * i + 1)));
    if (with_masks) {
      cv::Mat mask(48, 64, CV_8UC1, cv::Scalar(0));
      mask.col(i).setTo(255);
      cv::imwrite(dir + "/mask_0" + name, mask);
    }
    times += std::to_string(0.05 * i) + "\n";
  }
  write_text(dir + "/times.txt", times);
  write_text(dir + "/calib.txt", "P0: 50 0 32 0 0 50 24 0 0 0 1 0\nP1: 50 0 32 -5 0 50 24 0 0 0 1 0\n");
  return dir;
}

inline std::string daemon_sim_sequence() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(binary_dir()) / "test-data" / "daemon_scene2_s11_80";
  if (fs::exists(dir / ".complete")) return dir.string();
  fs::create_directories(dir.parent_path());
  const std::string tmp = make_temp_dir("agvslamd-sim");
  std::string out;
  const int rc = run_command(
      tool_path("agvslam-sim") + " --scenario scene2 --seed 11 --squeeze-to 80 --threads 2 --out " + tmp + "/seq",
      &out);
  if (rc != 0) throw std::runtime_error("agvslam-sim failed: " + out);
  write_text(tmp + "/seq/.complete", "scene2 seed 11 80 frames\n");
  std::error_code ec;
  fs::rename(tmp + "/seq", dir, ec);  // another test process may have won the race: use its copy
  fs::remove_all(tmp, ec);
  if (!fs::exists(dir / ".complete")) throw std::runtime_error("could not place the sequence at " + dir.string());
  return dir.string();
}

// A child process with stdout and stderr in files.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& args, const std::string& stdout_path, const std::string& stderr_path,
               const std::map<std::string, std::string>& env = {}) {
    std::vector<std::string> env_strings;
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string kv = *e;
      const std::string key = kv.substr(0, kv.find('='));
      if (env.count(key) == 0) env_strings.push_back(kv);
    }
    for (const auto& [k, v] : env) env_strings.push_back(k + "=" + v);
    std::vector<char*> argv, envp;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    for (const auto& e : env_strings) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) pid_ = -1;
  }
  ~ChildProcess() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }
  void signal(int sig) const {
    if (pid_ > 0 && !exited_) ::kill(pid_, sig);
  }
  // Exit status, -1 when still running after `timeout` (or killed by a signal: -2).
  int wait(std::chrono::milliseconds timeout) {
    if (exited_) return exit_code_;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      int status = 0;
      const pid_t r = waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        exited_ = true;
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -2;
        return exit_code_;
      }
      if (std::chrono::steady_clock::now() >= deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
};

// Waits until `pred` holds (polling), at most `timeout`.
template <typename Pred>
bool wait_until(Pred pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!pred()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

// The command prefix for a private network namespace ("unshare -n" as root, "unshare -rn" with user namespaces),
// or "" when neither is allowed here.
inline std::string netns_prefix() {
  if (run_command("unshare -n true") == 0) return "unshare -n";
  if (run_command("unshare -rn true") == 0) return "unshare -rn";
  return "";
}

}  // namespace agvslam::test

#define AGVSLAM_REQUIRE_NETNS(var)                                                                          \
  const std::string var = ::agvslam::test::netns_prefix();                                                  \
  if (var.empty()) {                                                                                        \
    if (::agvslam::test::running_in_ci()) FAIL() << "unshare -n is not permitted here and CI=true";         \
    GTEST_SKIP() << "unshare -n (a private network namespace) is not permitted here; run as root or where " \
                    "unprivileged user namespaces are enabled";                                             \
  }
