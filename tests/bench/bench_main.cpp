// Entry point of agvslam-bench. Benchmarks run single-threaded (OpenCV's own thread pool is limited to one
// thread) so that figures are comparable with the one-core budgets in the README.
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
