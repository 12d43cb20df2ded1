#pragma once
// Summary statistics of a sample of timings or other figures, one definition for every tool and the daemon:
// the q-quantile is the sorted sample's element at round(q * (n - 1)) (nearest rank, no interpolation), so a
// median, p95 or p99 is always a value that occurred.

#include <cstddef>
#include <vector>

namespace agvslam {

// The q-quantile (0 <= q <= 1) of `values` as above; 0 for an empty sample. Reorders `values` (selection).
double quantile_in_place(std::vector<double>& values, double q);

// A growing sample (a whole run's per-frame times).
class Series {
 public:
  void add(double value) { values_.push_back(value); }
  std::size_t count() const { return values_.size(); }
  bool empty() const { return values_.empty(); }
  const std::vector<double>& values() const { return values_; }
  double quantile(double q) const;  // 0 when empty
  double median() const { return quantile(0.5); }
  double max() const;   // 0 when empty
  double mean() const;  // 0 when empty

 private:
  std::vector<double> values_;
};

// The last `capacity` values of an endless stream (a daemon's latencies): fixed memory, no allocation per add.
class RollingSeries {
 public:
  explicit RollingSeries(std::size_t capacity = 4096);
  void add(double value);
  std::size_t count() const { return filled_; }  // values held (at most capacity)
  std::size_t total() const { return total_; }   // values ever added
  double quantile(double q) const;               // over the values held; 0 when none
  double max() const;

 private:
  std::vector<double> values_;
  mutable std::vector<double> scratch_;
  std::size_t next_ = 0, filled_ = 0, total_ = 0;
};

}  // namespace agvslam
