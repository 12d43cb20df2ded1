#pragma once
// SGBM on the dynamic ROIs alone: disparity is computed only where an outline needs it.

#include <opencv2/core.hpp>

#include "agvslam/core/stereo_frame.h"
#include "agvslam/stereo/sgbm.h"

namespace agvslam::dynamic {

class RoiMatcher {
 public:
  // sgbm: stereo.yaml's sgbm section as the ROIs use it; pad_left_border: roi.pad_left_border.
  RoiMatcher(const stereo::SgbmConfig& sgbm, bool pad_left_border);

  // Disparity (CV_32FC1 of the ROI's size, px, 0 = none) of `roi` searched up to max_disparity_px, SGBM at `scale`
  // (1 or 0.5) and, at scale 1, on every row_step-th row pair. A ROI near the left border, where StereoSGBM leaves
  // the first num_disparities columns it matches without disparity, is matched in images padded on the left (edge
  // replicated) when pad_left_border.
  void match(const StereoFrame& frame, const cv::Rect& roi, int max_disparity_px, double scale, int row_step,
             cv::Mat& disparity_px);
  // The whole frame (debugging).
  void match_full(const StereoFrame& frame, cv::Mat& disparity_px) {
    sgbm_.compute(frame.left, frame.right, disparity_px);
  }

 private:
  stereo::StereoSgbm sgbm_;
  bool pad_left_border_;
  cv::Mat padded_left_, padded_right_;
};

}  // namespace agvslam::dynamic
