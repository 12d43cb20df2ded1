// Simulator benchmarks: one 752x480 stereo frame (both cameras ray cast and shaded, sensor model, ground
// truth) of scenes with people, and building a scenario (warehouse layout + actor planning).
#include <benchmark/benchmark.h>

#include <memory>

#include "agvslam/sim/simulator.h"

namespace {

using agvslam::sim::ScenarioOptions;
using agvslam::sim::SimConfig;
using agvslam::sim::SimFrame;
using agvslam::sim::Simulator;

std::unique_ptr<Simulator> make_simulator(const std::string& name, uint64_t seed) {
  ScenarioOptions o;
  o.name = name;
  o.seed = seed;
  return std::make_unique<Simulator>(SimConfig{}, o);
}

// scene3 frame 150: three people and the forklift in view, looking down the racked aisle.
void BM_SimStereoFrameAisleWithPeople(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = make_simulator("scene3", 2);
  SimFrame frame;
  for (auto _ : state) {
    sim->render_frame(150, frame, 1);
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(2.0 * 752 * 480, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SimStereoFrameAisleWithPeople)->Unit(benchmark::kMillisecond);

// scene5 frame 300: on the loop, the leading person close ahead.
void BM_SimStereoFrameLoopWithLeader(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = make_simulator("scene5", 3);
  SimFrame frame;
  for (auto _ : state) {
    sim->render_frame(300, frame, 1);
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(2.0 * 752 * 480, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SimStereoFrameLoopWithLeader)->Unit(benchmark::kMillisecond);

void BM_SimBuildScenario(benchmark::State& state) {
  uint64_t seed = 1;
  for (auto _ : state) {
    const auto sim = make_simulator("scene5", seed++);
    benchmark::DoNotOptimize(sim->warehouse().boxes.data());
  }
}
BENCHMARK(BM_SimBuildScenario)->Unit(benchmark::kMillisecond);

}  // namespace
