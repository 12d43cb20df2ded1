#pragma once
// OpenCV's ORB test pattern (see orb_pattern.cpp for its origin and licence). Private to the features module.
#include <cstdint>

namespace agvslam::features::detail {

extern const int8_t kOrbBitPattern31[1024];

}  // namespace agvslam::features::detail
