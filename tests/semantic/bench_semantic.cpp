// The shipped segmentation network on one core: the forward pass at the model's input size (288 x 192), and a
// whole segmented 752 x 480 frame (resize, forward, upsampled scores, best class), which is what the worker pays
// per keyframe. Target: <= 60 ms per segmented frame.
#include <benchmark/benchmark.h>

#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/semantic/segmenter.h"

namespace {
using agvslam::semantic::ModelConfig;
using agvslam::semantic::Segmenter;

Segmenter& shipped() {
  static std::unique_ptr<Segmenter> net = [] {
    cv::setNumThreads(1);
    ModelConfig c;
    c.path = std::string(AGVSLAM_SOURCE_DIR) + "/" + c.path;
    return std::make_unique<Segmenter>(c);
  }();
  return *net;
}

// A warehouse-like grey frame: smooth shading with edges and noise (the network's cost does not depend on it).
cv::Mat frame(cv::Size size) {
  cv::Mat grey(size, CV_8UC1);
  cv::randu(grey, 40, 200);
  cv::GaussianBlur(grey, grey, {0, 0}, 3.0);
  cv::rectangle(grey, {100, 80, 200, 300}, cv::Scalar(30), cv::FILLED);
  return grey;
}

void BM_SegmenterForwardAtInputSize(benchmark::State& state) {
  Segmenter& net = shipped();
  const cv::Mat grey = frame({net.config().input_width, net.config().input_height});
  for (auto _ : state) benchmark::DoNotOptimize(net.scores(grey).data);
}
BENCHMARK(BM_SegmenterForwardAtInputSize)->Unit(benchmark::kMillisecond);

void BM_SegmentOneFrame752x480(benchmark::State& state) {
  Segmenter& net = shipped();
  const cv::Mat grey = frame({752, 480});
  for (auto _ : state) benchmark::DoNotOptimize(net.segment(grey).data);
}
BENCHMARK(BM_SegmentOneFrame752x480)->Unit(benchmark::kMillisecond);

}  // namespace
