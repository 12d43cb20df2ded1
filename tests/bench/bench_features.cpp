// Feature-stage benchmarks (one thread, see bench_main.cpp): ORB extraction of 1200 features at 752x480 on a
// simulator frame and on the real EuRoC / KITTI images, cv::ORB (1200 features) on the same images as the
// reference line, stereo depth at the keypoints (block matching and ORB-SLAM2's descriptor method), and the
// whole feature stage of the tracking thread (extraction + stereo).
// Data: the simulator frame is rendered here; the real images come from env AGVSLAM_SHARED_DIR, else the
// configured shared folder (a case whose data is missing reports an error).
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "agvslam/core/error.h"
#include "agvslam/features/orb_extractor.h"
#include "agvslam/features/stereo_matcher.h"
#include "agvslam/io/dataset.h"
#include "agvslam/sim/simulator.h"

namespace {
namespace fs = std::filesystem;
using agvslam::features::KeypointSet;
using agvslam::features::OrbExtractor;
using agvslam::features::StereoDepth;
using agvslam::features::StereoMatcher;
using agvslam::features::StereoMatcherConfig;
using agvslam::features::StereoMethod;

struct BenchPair {
  cv::Mat left, right;
  agvslam::StereoCalibration calibration;
};

std::string features_bench_data(const std::string& rel) {
  const char* env = std::getenv("AGVSLAM_SHARED_DIR");
  const std::string base = (env && *env) ? env : AGVSLAM_SHARED_DIR_DEFAULT;
  return (fs::path(base) / "data" / rel).string();
}

// 0: simulator scene4 frame 60; 1: EuRoC V1_01 frame 40 (rectified); 2: KITTI 06 frame 10 (1226x370).
const BenchPair* bench_pair(benchmark::State& state, int which) {
  static std::map<int, std::unique_ptr<BenchPair>> pairs;
  static std::map<int, std::string> errors;
  if (!pairs.count(which) && !errors.count(which)) {
    try {
      auto p = std::make_unique<BenchPair>();
      const auto level = spdlog::get_level();
      spdlog::set_level(spdlog::level::err);
      if (which == 0) {
        agvslam::sim::ScenarioOptions options;
        options.name = "scene4";
        const agvslam::sim::Simulator simulator(agvslam::sim::SimConfig{}, options);
        agvslam::sim::SimFrame frame;
        simulator.render_frame(60, frame, 1);
        p->left = frame.left.clone();
        p->right = frame.right.clone();
        p->calibration = simulator.calibration();
      } else {
        const std::string root = features_bench_data(which == 1 ? "euroc_v101_f000-094" : "kitti06_f000-050");
        if (!fs::exists(root)) throw agvslam::InputError(root, "", "shared data not found (set AGVSLAM_SHARED_DIR)");
        std::unique_ptr<agvslam::io::StereoDataset> dataset;
        if (which == 1) {
          dataset = std::make_unique<agvslam::io::EurocDataset>(root);
        } else {
          dataset = std::make_unique<agvslam::io::KittiDataset>(root);
        }
        const agvslam::StereoFrame f = dataset->frame(which == 1 ? 40 : 10);
        p->left = f.left;
        p->right = f.right;
        p->calibration = dataset->calibration();
      }
      spdlog::set_level(level);
      pairs[which] = std::move(p);
    } catch (const agvslam::InputError& e) {
      errors[which] = e.what();
    }
  }
  if (!pairs.count(which)) {
    state.SkipWithError(errors[which].c_str());
    return nullptr;
  }
  return pairs[which].get();
}

const char* pair_name(int which) { return which == 0 ? "sim" : which == 1 ? "euroc" : "kitti"; }

void BM_FeaturesOrbExtract(benchmark::State& state) {
  const BenchPair* p = bench_pair(state, static_cast<int>(state.range(0)));
  if (!p) return;
  OrbExtractor extractor;
  KeypointSet set;
  extractor.extract(p->left, cv::Mat(), set);  // warm-up: buffers reach their size
  double pyramid = 0, fast = 0, distribute = 0, orientation = 0, blur = 0, descriptors = 0;
  for (auto _ : state) {
    extractor.extract(p->left, cv::Mat(), set);
    benchmark::DoNotOptimize(set.descriptors.data);
    const auto& s = extractor.stats();
    pyramid += s.t_pyramid_ms;
    fast += s.t_fast_ms;
    distribute += s.t_distribute_ms;
    orientation += s.t_orientation_ms;
    blur += s.t_blur_ms;
    descriptors += s.t_descriptor_ms;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["keypoints"] = static_cast<double>(set.keypoints.size());
  state.counters["pyramid_ms"] = pyramid / n;
  state.counters["fast_ms"] = fast / n;
  state.counters["quadtree_ms"] = distribute / n;
  state.counters["angle_ms"] = orientation / n;
  state.counters["blur_ms"] = blur / n;
  state.counters["brief_ms"] = descriptors / n;
  state.SetLabel(pair_name(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_FeaturesOrbExtract)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The same with a dynamic mask over 13 % of the image (a person-sized block and a disc), dilated by the default
// mask_dilation_px (8 px) per level.
void BM_FeaturesOrbExtractMasked(benchmark::State& state) {
  const BenchPair* p = bench_pair(state, 0);
  if (!p) return;
  cv::Mat mask = cv::Mat::zeros(p->left.size(), CV_8UC1);
  cv::rectangle(mask, cv::Rect(300, 60, 120, 330), cv::Scalar(255), cv::FILLED);
  cv::circle(mask, cv::Point(620, 300), 45, cv::Scalar(255), cv::FILLED);
  OrbExtractor extractor;
  KeypointSet set;
  extractor.extract(p->left, mask, set);
  for (auto _ : state) {
    extractor.extract(p->left, mask, set);
    benchmark::DoNotOptimize(set.descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(set.keypoints.size());
  state.counters["mask_ms"] = extractor.stats().t_mask_ms;
}
BENCHMARK(BM_FeaturesOrbExtractMasked)->Unit(benchmark::kMillisecond);

// The reference: OpenCV's ORB with ORB-SLAM2's pyramid, 1200 features (no quadtree, no retry).
void BM_FeaturesCvOrbReference(benchmark::State& state) {
  const BenchPair* p = bench_pair(state, static_cast<int>(state.range(0)));
  if (!p) return;
  auto orb = cv::ORB::create(1200, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) {
    orb->detectAndCompute(p->left, cv::noArray(), keypoints, descriptors);
    benchmark::DoNotOptimize(descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
  state.SetLabel(pair_name(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_FeaturesCvOrbReference)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// Stereo depth of the 1200 left keypoints: range(0) = image, range(1) = 0 block matching, 1 descriptor method.
void BM_FeaturesStereoMatch(benchmark::State& state) {
  const BenchPair* p = bench_pair(state, static_cast<int>(state.range(0)));
  if (!p) return;
  OrbExtractor extractor;
  KeypointSet set;
  extractor.extract(p->left, cv::Mat(), set);
  StereoMatcherConfig config;
  config.method = state.range(1) == 0 ? StereoMethod::kBlockMatching : StereoMethod::kDescriptor;
  StereoMatcher matcher(config, p->calibration);
  StereoDepth depth;
  matcher.match(extractor, set, p->right, depth);
  double right = 0, match = 0;
  for (auto _ : state) {
    matcher.match(extractor, set, p->right, depth);
    benchmark::DoNotOptimize(depth.depth_m.data());
    right += matcher.t_right_ms();
    match += matcher.t_match_ms();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["matched"] = depth.matched;
  state.counters["right_ms"] = right / n;
  state.counters["match_ms"] = match / n;
  state.SetLabel(std::string(pair_name(static_cast<int>(state.range(0)))) + " " + to_string(config.method));
}
BENCHMARK(BM_FeaturesStereoMatch)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({0, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond);

// The tracking thread's feature stage per frame: extraction + stereo depth (block matching).
void BM_FeaturesExtractAndStereo(benchmark::State& state) {
  const BenchPair* p = bench_pair(state, static_cast<int>(state.range(0)));
  if (!p) return;
  OrbExtractor extractor;
  KeypointSet set;
  StereoMatcher matcher(StereoMatcherConfig{}, p->calibration);
  StereoDepth depth;
  extractor.extract(p->left, cv::Mat(), set);
  matcher.match(extractor, set, p->right, depth);
  for (auto _ : state) {
    extractor.extract(p->left, cv::Mat(), set);
    matcher.match(extractor, set, p->right, depth);
    benchmark::DoNotOptimize(depth.depth_m.data());
  }
  state.counters["keypoints"] = static_cast<double>(set.keypoints.size());
  state.counters["matched"] = depth.matched;
  state.SetLabel(pair_name(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_FeaturesExtractAndStereo)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
