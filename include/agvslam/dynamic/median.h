#pragma once
// The upper median of a sample, by selection (the vector is reordered): shared by the detector's stages.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace agvslam::dynamic {

// v[n / 2] of the sorted values (reorders v); `empty_value` for an empty vector.
inline float median_in_place(std::vector<float>& v, float empty_value) {
  if (v.empty()) return empty_value;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace agvslam::dynamic
