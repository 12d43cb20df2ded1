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

// One stereo frame of `sim` per iteration, on one thread.
void render_stereo_frame(benchmark::State& state, const Simulator& sim, int frame) {
  SimFrame out;
  for (auto _ : state) {
    sim.render_frame(frame, out, 1);
    benchmark::DoNotOptimize(out.left.data);
  }
  state.counters["rays_per_s"] = benchmark::Counter(2.0 * 752 * 480, benchmark::Counter::kIsIterationInvariantRate);
}

// scene3 frame 150: three people and the forklift in view, looking down the racked aisle.
void BM_SimStereoFrameAisleWithPeople(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = make_simulator("scene3", 2);
  render_stereo_frame(state, *sim, 150);
}
BENCHMARK(BM_SimStereoFrameAisleWithPeople)->Unit(benchmark::kMillisecond);

// scene5 frame 300: on the loop, the leading person close ahead.
void BM_SimStereoFrameLoopWithLeader(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = make_simulator("scene5", 3);
  render_stereo_frame(state, *sim, 300);
}
BENCHMARK(BM_SimStereoFrameLoopWithLeader)->Unit(benchmark::kMillisecond);

// crowd frame 280: six people in textured clothing 1.6-2.4 m ahead cover ~40 % of the view (clothing.cpp's
// albedos on much of the image).
void BM_SimStereoFrameCrowd(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = make_simulator("crowd", 101);
  render_stereo_frame(state, *sim, 280);
}
BENCHMARK(BM_SimStereoFrameCrowd)->Unit(benchmark::kMillisecond);

void BM_SimBuildScenario(benchmark::State& state) {
  uint64_t seed = 1;
  for (auto _ : state) {
    const auto sim = make_simulator("scene5", seed++);
    benchmark::DoNotOptimize(sim->warehouse().boxes.data());
  }
}
BENCHMARK(BM_SimBuildScenario)->Unit(benchmark::kMillisecond);

}  // namespace
