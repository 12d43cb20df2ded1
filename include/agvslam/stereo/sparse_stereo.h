#pragma once
// Disparity at sparse points: a zero-mean SAD block matcher along the rectified row, with a uniqueness test,
// a texture test, a sub-pixel parabola fit and a left-right consistency check. Used where only a few
// hundred points need a disparity (tracked features), so no dense map is computed.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::stereo {

// params/stereo.yaml, section `sparse`.
struct SparseStereoConfig {
  int half_window = 4;    // matching window is (2 h + 1)^2 pixels
  int min_disparity = 0;  // search range [min, min + num - 1] px
  int num_disparities = 64;
  double uniqueness_margin = 0.10;  // second-best cost (more than 1 px away) must exceed best * (1 + margin)
  double max_mean_cost = 40.0;      // mean |zero-mean difference| per pixel at the best match (grey levels)
  double max_cost_ratio = 0.6;      // ... and at most this fraction of the window's texture (below)
  double min_texture = 3.0;         // mean |I - mean(I)| of the left window (grey levels); below: no match
  int lr_max_diff_px = 1;           // left-right check tolerance (px); < 0 disables the check
  bool subpixel = true;             // parabola fit through the costs at d-1, d, d+1

  int max_disparity() const { return min_disparity + num_disparities - 1; }
  // InputError(source, "sparse.<field>", expectation) for an invalid value; both from the table of
  // params/stereo.yaml's settings (stereo_config.cpp).
  void validate(const std::string& source) const;
  std::string describe() const;
};

// Why a point got no disparity (for statistics and tests).
enum class SparseMatchStatus : uint8_t { kOk, kOutside, kNoTexture, kNotUnique, kHighCost, kLeftRight, kRange };
const char* to_string(SparseMatchStatus status);

class SparseStereoMatcher {
 public:
  explicit SparseStereoMatcher(const SparseStereoConfig& config = {});
  const SparseStereoConfig& config() const { return config_; }

  // Disparity (px) at the pixel nearest to `point_px` in the left image; 0 when no reliable match.
  // left/right: rectified CV_8UC1 of equal size.
  float match(const cv::Mat& left, const cv::Mat& right, cv::Point2f point_px, SparseMatchStatus* status = nullptr);

  // One disparity per point (resized to points.size()).
  void match(const cv::Mat& left, const cv::Mat& right, const std::vector<cv::Point2f>& points_px,
             std::vector<float>& disparity_px);

 private:
  // Best integer candidate column in `other` for the window at (x, y) of `ref`; candidates are
  // x + direction * d for d in [d_lo, d_hi]. Fills costs_ (index = column - first candidate column).
  struct Search {
    bool ok = false;
    int best_column = 0;
    int first_column = 0;
    int64_t best_cost = 0, second_cost = 0;
    double texture = 0;
  };
  Search search(const cv::Mat& ref, const cv::Mat& other, int x, int y, int direction, int d_lo, int d_hi);

  SparseStereoConfig config_;
  std::vector<int16_t> ref_zero_mean_;  // 4 I - 4 mean(I) of the reference window (quarter grey levels)
  std::vector<int32_t> col_sums_;       // column sums of the candidate strip
  std::vector<int16_t> win_means_;      // 4 mean(I) of each candidate window
  std::vector<int16_t> strip_scaled_;   // 4 I of one strip row
  std::vector<uint16_t> row_costs_;     // per candidate, one window row
  std::vector<int32_t> costs_;          // ZSAD cost per candidate column (quarter grey levels)
};

}  // namespace agvslam::stereo
