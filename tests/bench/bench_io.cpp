// io benchmarks: loading (and rectifying) stereo pairs from the real data sets, and reading long trajectory files.
// Data: env AGVSLAM_SHARED_DIR, else the configured shared folder (AGVSLAM_SHARED_DIR_DEFAULT); a case whose data
// is missing reports an error instead of a time.
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "agvslam/core/error.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"

namespace {
namespace fs = std::filesystem;
using agvslam::SE3d;
using agvslam::Trajectory;

std::string shared_data(const std::string& rel) {
  const char* env = std::getenv("AGVSLAM_SHARED_DIR");
  const std::string base = (env && *env) ? env : AGVSLAM_SHARED_DIR_DEFAULT;
  return (fs::path(base) / "data" / rel).string();
}

// Datasets warn about the frames they skip; keep the benchmark output readable.
class QuietLogs {
 public:
  QuietLogs() : previous_(spdlog::get_level()) { spdlog::set_level(spdlog::level::err); }
  ~QuietLogs() { spdlog::set_level(previous_); }
  QuietLogs(const QuietLogs&) = delete;
  QuietLogs& operator=(const QuietLogs&) = delete;

 private:
  spdlog::level::level_enum previous_;
};

template <typename Dataset>
std::unique_ptr<Dataset> open_or_skip(benchmark::State& state, const std::string& rel) {
  const std::string root = shared_data(rel);
  if (!fs::exists(root)) {
    state.SkipWithError(("shared data not found: " + root + " (set AGVSLAM_SHARED_DIR)").c_str());
    return nullptr;
  }
  try {
    return std::make_unique<Dataset>(root);
  } catch (const agvslam::InputError& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

// imread of two 752x480 PNGs + remap of both through the rectification maps.
void BM_EurocLoadAndRectifyPair(benchmark::State& state) {
  QuietLogs quiet;
  const auto dataset = open_or_skip<agvslam::io::EurocDataset>(state, "euroc_v101_f000-094");
  if (!dataset) return;
  std::size_t i = 0;
  for (auto _ : state) {
    agvslam::StereoFrame frame = dataset->frame(i++ % dataset->size());
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EurocLoadAndRectifyPair)->Unit(benchmark::kMillisecond);

// Only the remap part of the above (images already decoded).
void BM_EurocRectifyPair(benchmark::State& state) {
  QuietLogs quiet;
  const auto dataset = open_or_skip<agvslam::io::EurocDataset>(state, "euroc_v101_f000-094");
  if (!dataset) return;
  const cv::Mat left = cv::imread(dataset->left_path(0), cv::IMREAD_GRAYSCALE);
  const cv::Mat right = cv::imread(dataset->right_path(0), cv::IMREAD_GRAYSCALE);
  cv::Mat left_rect, right_rect;
  for (auto _ : state) {
    dataset->calibration().rectify(left, right, left_rect, right_rect);
    benchmark::DoNotOptimize(left_rect.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EurocRectifyPair)->Unit(benchmark::kMillisecond);

// imread of two 1226x370 PNGs (KITTI images are already rectified).
void BM_KittiLoadPair(benchmark::State& state) {
  const auto dataset = open_or_skip<agvslam::io::KittiDataset>(state, "kitti06_f000-050");
  if (!dataset) return;
  std::size_t i = 0;
  for (auto _ : state) {
    agvslam::StereoFrame frame = dataset->frame(i++ % dataset->size());
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KittiLoadPair)->Unit(benchmark::kMillisecond);

// A long trajectory (state.range(0) poses) written once to a temporary file, then read repeatedly.
class TrajectoryFile {
 public:
  TrajectoryFile(std::size_t poses, agvslam::io::TrajectoryFormat format)
      : folder_(fs::temp_directory_path() / ("agvslam-bench-io-" + std::to_string(::getpid()))) {
    fs::create_directories(folder_);
    path_ = (folder_ / ("trajectory." + agvslam::io::to_string(format))).string();
    Trajectory trajectory;
    trajectory.reserve(poses);
    for (std::size_t i = 0; i < poses; ++i) {
      agvslam::Vector6d xi;
      const double s = static_cast<double>(i) * 0.05;
      xi << s, 0.3 * s, 0.01 * s, 0.1 * std::sin(s), 0.02 * s, 0.05;
      trajectory.push_back({static_cast<int64_t>(i) * 50'000'000 + 1403715273262142976, agvslam::se3_exp(xi)});
    }
    agvslam::io::write_trajectory(path_, trajectory, format);
  }
  ~TrajectoryFile() {
    std::error_code ec;
    fs::remove_all(folder_, ec);
  }
  TrajectoryFile(const TrajectoryFile&) = delete;
  TrajectoryFile& operator=(const TrajectoryFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  fs::path folder_;
  std::string path_;
};

void BM_ReadKittiPoses(benchmark::State& state) {
  const TrajectoryFile file(static_cast<std::size_t>(state.range(0)), agvslam::io::TrajectoryFormat::kKitti);
  for (auto _ : state) {
    Trajectory trajectory = agvslam::io::read_kitti_poses(file.path());
    benchmark::DoNotOptimize(trajectory.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(file.path())));
}
BENCHMARK(BM_ReadKittiPoses)->Arg(20000)->Unit(benchmark::kMillisecond);

void BM_ReadTum(benchmark::State& state) {
  const TrajectoryFile file(static_cast<std::size_t>(state.range(0)), agvslam::io::TrajectoryFormat::kTum);
  for (auto _ : state) {
    Trajectory trajectory = agvslam::io::read_tum(file.path());
    benchmark::DoNotOptimize(trajectory.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(fs::file_size(file.path())));
}
BENCHMARK(BM_ReadTum)->Arg(20000)->Unit(benchmark::kMillisecond);

// The real ORB-SLAM3 EuRoC V1_01 ground truth (2871 rows, comma separated).
void BM_ReadEurocGroundTruthCsv(benchmark::State& state) {
  const std::string path = shared_data("euroc_v101_f000-094/gt_orbslam3_left_cam/V101_GT.txt");
  if (!fs::exists(path)) {
    state.SkipWithError(("shared data not found: " + path + " (set AGVSLAM_SHARED_DIR)").c_str());
    return;
  }
  std::size_t rows = 0;
  for (auto _ : state) {
    Trajectory trajectory = agvslam::io::read_euroc_csv(path);
    rows = trajectory.size();
    benchmark::DoNotOptimize(trajectory.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(rows));
}
BENCHMARK(BM_ReadEurocGroundTruthCsv)->Unit(benchmark::kMillisecond);

}  // namespace
