#pragma once
// Timing of the stages (per-stage timings in the tools' --json output and the daemon's status).

#include <chrono>

namespace agvslam {

using SteadyClock = std::chrono::steady_clock;

// Wall time since t0 (ms).
inline double ms_since(SteadyClock::time_point t0) {
  return std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
}

// CPU time of the calling thread (ms): what a stage costs, unaffected by other load on the machine.
double thread_cpu_ms();

}  // namespace agvslam
