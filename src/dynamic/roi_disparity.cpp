#include "agvslam/dynamic/roi_disparity.h"

#include <algorithm>

namespace agvslam::dynamic {

RoiMatcher::RoiMatcher(const stereo::SgbmConfig& sgbm, bool pad_left_border)
    : sgbm_(sgbm), pad_left_border_(pad_left_border) {}

void RoiMatcher::match(const StereoFrame& frame, const cv::Rect& roi, int max_disparity_px, double scale, int row_step,
                       cv::Mat& disparity_px) {
  const stereo::SgbmConfig& sc = sgbm_.config();
  const cv::Rect r = roi & cv::Rect(cv::Point(0, 0), frame.left.size());
  const int rows = scale == 1.0 ? row_step : 1;
  // What compute_roi reaches left of the ROI (search range, context margin, half block) and a little more.
  const int reach = sc.min_disparity + sc.num_disparities + sc.roi_margin_px + sc.block_size + 2;
  if (!pad_left_border_ || r.empty() || r.x >= reach) {
    sgbm_.compute_roi(frame.left, frame.right, r, disparity_px, max_disparity_px, scale, rows);
    return;
  }
  const int pad = reach - r.x;
  // The columns compute_roi reads right of the ROI, and the 16 it may add for a minimum width.
  const int width = std::min(frame.left.cols, r.br().x + sc.roi_margin_px + sc.block_size + sc.num_disparities + 16);
  const cv::Rect strip(0, 0, width, frame.left.rows);
  cv::copyMakeBorder(frame.left(strip), padded_left_, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(frame.right(strip), padded_right_, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  sgbm_.compute_roi(padded_left_, padded_right_, r + cv::Point(pad, 0), disparity_px, max_disparity_px, scale, rows);
}

}  // namespace agvslam::dynamic
