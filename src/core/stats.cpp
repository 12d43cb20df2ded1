#include "agvslam/core/stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace agvslam {

double quantile_in_place(std::vector<double>& values, double q) {
  if (values.empty()) return 0;
  const double rank = std::floor(std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
  const auto k = std::min(values.size() - 1, static_cast<std::size_t>(rank));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

double Series::quantile(double q) const {
  std::vector<double> copy = values_;
  return quantile_in_place(copy, q);
}

double Series::max() const { return values_.empty() ? 0 : *std::max_element(values_.begin(), values_.end()); }

double Series::mean() const {
  return values_.empty() ? 0
                         : std::accumulate(values_.begin(), values_.end(), 0.0) / static_cast<double>(values_.size());
}

RollingSeries::RollingSeries(std::size_t capacity) : values_(std::max<std::size_t>(capacity, 1), 0.0) {
  scratch_.reserve(values_.size());
}

void RollingSeries::add(double value) {
  values_[next_] = value;
  next_ = (next_ + 1) % values_.size();
  filled_ = std::min(filled_ + 1, values_.size());
  ++total_;
}

double RollingSeries::quantile(double q) const {
  scratch_.assign(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(filled_));
  return quantile_in_place(scratch_, q);
}

double RollingSeries::max() const {
  if (filled_ == 0) return 0;
  return *std::max_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(filled_));
}

}  // namespace agvslam
