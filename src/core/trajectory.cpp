#include "agvslam/core/trajectory.h"

#include <cmath>

namespace agvslam {

int64_t s_to_ns(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e9)); }

}  // namespace agvslam
