#pragma once
// Edge refinement of an object outline at full resolution (beyond paper 004; mask_mode disparity).
//
// SGBM's cost window spills over an object's side onto the background, so the ROI disparity "fattens" the
// object: its outline runs a few pixels into the background at its left and right sides (and more where the ROI
// was matched on pairs of rows). The sides decide most of an upright object's outline, and there the question
// "object or background?" has two candidate answers for each pixel: the object's disparity d_f (that of the
// outline's row run, away from its ends) and the background's d_b (the first disparities outside the run). For
// each end of each row run of the outline, every pixel within band_px of it is matched at both disparities with a
// window one column wide and 2 * half_rows + 1 rows tall (it cannot straddle a near-vertical side, which is what
// fattens a square window), and the side is put where the pixels on one side of it fit one hypothesis and those
// on the other side the other best (a 1-D two-label split, its cost the sum of the pixels' matching costs).
// Beside an object's right side the background is seen by both cameras; beside its left side lies a strip that
// the object hides from the right camera (and that has no SGBM disparity), so a left side is split in the right
// image, at x - d_f, where the background beside it is seen by both. A pixel's background cost is capped at
// occlusion_cost. A side whose two disparities differ by less than min_disparity_gap_px, or whose background
// disparity is unknown, is left as it is, as is a side where the split wins by less than min_gain per pixel moved.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `edge_refine`.
struct EdgeRefineConfig {
  int band_px = 6;                    // pixels either side of each run end that may change (0 = off)
  int half_rows = 2;                  // the matching window: one column, 2 * half_rows + 1 rows
  int background_px = 8;              // d_b: median of the first this many disparities outside the band (searched
                                      // up to 4x as far: beside a left side lies a strip without disparity)
  double min_disparity_gap_px = 1.0;  // sides where d_f - d_b is smaller are left alone
  double occlusion_cost = 12.0;       // cap of a pixel's background cost (mean |grey difference| per window pixel)
  double min_gain = 1.0;              // a side moves only when the split's cost falls by this much per px moved

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct EdgeRefineStats {
  int sides = 0;  // run ends looked at
  int moved = 0;  // ... whose position changed
  int pixels_added = 0, pixels_removed = 0;
};

class EdgeRefiner {
 public:
  explicit EdgeRefiner(const EdgeRefineConfig& config = {});
  const EdgeRefineConfig& config() const { return config_; }

  // left/right: the rectified grey images (CV_8UC1); roi: where outline and disparity_px lie in them; outline:
  // CV_8UC1 of the ROI (non-zero = object), changed in place; disparity_px: CV_32FC1 of the ROI (0 = none).
  EdgeRefineStats refine(const cv::Mat& left, const cv::Mat& right, cv::Rect roi, const cv::Mat& disparity_px,
                         cv::Mat& outline);

 private:
  EdgeRefineConfig config_;
  std::vector<uint8_t> row_;
  std::vector<float> values_;
  std::vector<float> cost_fg_, cost_bg_;
};

}  // namespace agvslam::dynamic
