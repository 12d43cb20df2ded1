// stereo benchmarks on a real 752x480 EuRoC pair (rectified): whole-frame SGBM (the reference the detector
// avoids), SGBM on a ROI crop, and the sparse block matcher at quadtree FAST corners.
// Data: env AGVSLAM_SHARED_DIR, else the configured shared folder; a case whose data is missing reports an error.
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/features2d.hpp>
#include <string>

#include "agvslam/core/error.h"
#include "agvslam/io/dataset.h"
#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/sparse_stereo.h"

namespace {
namespace fs = std::filesystem;

std::string stereo_bench_data(const std::string& rel) {
  const char* env = std::getenv("AGVSLAM_SHARED_DIR");
  const std::string base = (env && *env) ? env : AGVSLAM_SHARED_DIR_DEFAULT;
  return (fs::path(base) / "data" / rel).string();
}

// Frame 40 of the EuRoC excerpt, loaded once.
const agvslam::StereoFrame* euroc_pair(benchmark::State& state) {
  static std::unique_ptr<agvslam::StereoFrame> frame;
  static std::string error;
  if (!frame && error.empty()) {
    const std::string root = stereo_bench_data("euroc_v101_f000-094");
    if (!fs::exists(root)) {
      error = "shared data not found: " + root + " (set AGVSLAM_SHARED_DIR)";
    } else {
      try {
        const auto level = spdlog::get_level();
        spdlog::set_level(spdlog::level::err);
        const agvslam::io::EurocDataset dataset(root);
        frame = std::make_unique<agvslam::StereoFrame>(dataset.frame(40));
        spdlog::set_level(level);
      } catch (const agvslam::InputError& e) {
        error = e.what();
      }
    }
  }
  if (!frame) state.SkipWithError(error.c_str());
  return frame.get();
}

void BM_StereoSgbmWholeFrame(benchmark::State& state) {
  const agvslam::StereoFrame* f = euroc_pair(state);
  if (!f) return;
  agvslam::stereo::StereoSgbm sgbm;
  cv::Mat disparity_px;
  for (auto _ : state) {
    sgbm.compute(f->left, f->right, disparity_px);
    benchmark::DoNotOptimize(disparity_px.data);
  }
  state.counters["pixels"] = static_cast<double>(f->left.total());
}
BENCHMARK(BM_StereoSgbmWholeFrame)->Unit(benchmark::kMillisecond);

// A person-sized ROI (120x240 px) in the middle of the image, full range and narrowed to 32 disparities.
void BM_StereoSgbmRoi(benchmark::State& state) {
  const agvslam::StereoFrame* f = euroc_pair(state);
  if (!f) return;
  agvslam::stereo::StereoSgbm sgbm;
  const cv::Rect roi(320, 120, 120, 240);
  const int max_disparity = static_cast<int>(state.range(0));
  cv::Mat disparity_px;
  for (auto _ : state) {
    sgbm.compute_roi(f->left, f->right, roi, disparity_px, max_disparity);
    benchmark::DoNotOptimize(disparity_px.data);
  }
  state.counters["crop_px"] =
      static_cast<double>(sgbm.crop_for(roi, f->left.size(), sgbm.roi_num_disparities(max_disparity)).area());
}
BENCHMARK(BM_StereoSgbmRoi)->Arg(0)->Arg(31)->Unit(benchmark::kMillisecond);

// 300 FAST corners (strongest), matched one by one.
void BM_StereoSparsePoints(benchmark::State& state) {
  const agvslam::StereoFrame* f = euroc_pair(state);
  if (!f) return;
  std::vector<cv::KeyPoint> kps;
  cv::FAST(f->left, kps, 20, true);
  cv::KeyPointsFilter::runByImageBorder(kps, f->left.size(), 16);
  cv::KeyPointsFilter::retainBest(kps, 300);
  std::vector<cv::Point2f> pts;
  for (const auto& kp : kps) pts.push_back(kp.pt);
  agvslam::stereo::SparseStereoMatcher matcher;
  std::vector<float> disparity_px;
  int valid = 0;
  for (auto _ : state) {
    matcher.match(f->left, f->right, pts, disparity_px);
    benchmark::DoNotOptimize(disparity_px.data());
  }
  for (float d : disparity_px) valid += d > 0;
  state.counters["points"] = static_cast<double>(pts.size());
  state.counters["valid"] = valid;
}
BENCHMARK(BM_StereoSparsePoints)->Unit(benchmark::kMillisecond);

}  // namespace
