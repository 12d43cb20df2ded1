#pragma once
// A simulator of a named scenario for the sim tests, at `scale` times the default image size.
#include <cstdint>
#include <string>

#include "agvslam/sim/simulator.h"

namespace agvslam::sim::test {

inline Simulator make_sim(const std::string& name, uint64_t seed, double scale, double start_offset_m = 0) {
  ScenarioOptions o;
  o.name = name;
  o.seed = seed;
  o.start_offset_m = start_offset_m;
  return Simulator(SimConfig{}.scaled(scale), o);
}

}  // namespace agvslam::sim::test
