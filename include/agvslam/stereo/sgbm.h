#pragma once
// Semi-global block matching (OpenCV StereoSGBM) on rectified pairs: the whole frame (for debugging and
// reference), or only inside given regions of interest (what the dynamic detector uses).
//
// Output convention for every function here: CV_32FC1 disparity in pixels (x_left - x_right), 0 = invalid.

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::stereo {

enum class SgbmMode { kSgbm, kHh, kSgbm3Way, kHh4 };

std::string to_string(SgbmMode mode);
// "sgbm", "hh", "sgbm_3way", "hh4"; false for anything else.
bool parse_sgbm_mode(const std::string& text, SgbmMode& mode);

// params/stereo.yaml, section `sgbm`.
struct SgbmConfig {
  int min_disparity = 0;          // smallest disparity searched (px, >= 0)
  int num_disparities = 64;       // size of the search range, a positive multiple of 16
  int block_size = 5;             // matched block side (odd, 1..11)
  int p1 = 0;                     // smoothness penalty for +-1 px changes; <= 0: 8 * channels * block_size^2
  int p2 = 0;                     // penalty for larger changes; <= 0: 32 * channels * block_size^2
  int disp12_max_diff = 1;        // left-right check tolerance (px); < 0 disables
  int pre_filter_cap = 63;        // clip of the x-derivative prefilter
  int uniqueness_ratio = 10;      // best cost must beat the second best by this percentage
  int speckle_window_size = 100;  // connected blobs smaller than this are invalidated (0 disables)
  int speckle_range = 2;          // max disparity variation inside a blob (px)
  SgbmMode mode = SgbmMode::kSgbm3Way;
  int roi_margin_px = 4;  // context added around each ROI (rows and columns) before matching the crop

  int effective_p1(int channels) const { return p1 > 0 ? p1 : 8 * channels * block_size * block_size; }
  int effective_p2(int channels) const { return p2 > 0 ? p2 : 32 * channels * block_size * block_size; }
  int max_disparity() const { return min_disparity + num_disparities - 1; }

  // Throws InputError(source, "sgbm.<field>", expectation) for an invalid value. Both from the table of
  // params/stereo.yaml's settings (stereo_config.cpp).
  void validate(const std::string& source) const;
  std::string describe() const;
};

class StereoSgbm {
 public:
  // Validates the configuration (InputError with source "SgbmConfig" when invalid).
  explicit StereoSgbm(const SgbmConfig& config = {});

  const SgbmConfig& config() const { return config_; }

  // Whole-frame disparity. left/right: rectified CV_8UC1 or CV_8UC3 of equal size.
  void compute(const cv::Mat& left, const cv::Mat& right, cv::Mat& disparity_px);

  // The crop (in image coordinates) that is matched to produce the disparity inside `roi`: the ROI rows
  // +- margin, and columns from (roi.x - margin - max disparity) so every ROI pixel sees the full range.
  // num_disparities <= 0: the configured range.
  cv::Rect crop_for(const cv::Rect& roi, cv::Size image_size, int num_disparities = 0) const;

  // Disparity inside one ROI (clipped to the image): roi_disparity_px has the clipped ROI's size.
  // max_disparity_px > 0 narrows the search to [min_disparity, max_disparity_px] (rounded up to a multiple of
  // 16 disparities, never beyond the configured range): when the ROI's nearest content is known (the
  // dynamic points' disparities) this makes the crop narrower and the matching proportionally cheaper.
  // scale = 0.5 matches the crop at half resolution (a quarter of the pixels, half the disparities, about
  // 1/8 of the work); the result is upsampled (nearest) to the ROI and given in full-resolution pixels.
  // row_step = 2 (scale 1 only) matches every column but pairs of rows averaged (half the work): disparity
  // keeps its full horizontal resolution (an upright object's sides, where the outline's IoU is decided) and
  // each result row serves two image rows.
  void compute_roi(const cv::Mat& left, const cv::Mat& right, const cv::Rect& roi, cv::Mat& roi_disparity_px,
                   int max_disparity_px = 0, double scale = 1.0, int row_step = 1);

  // The number of disparities compute_roi searches for a given max_disparity_px.
  int roi_num_disparities(int max_disparity_px) const;

  // Disparity inside several ROIs written into a full-size map (0 outside the ROIs). Overlapping ROIs are
  // matched once, as the bounding box of the overlapping group.
  void compute_rois(const cv::Mat& left, const cv::Mat& right, const std::vector<cv::Rect>& rois,
                    cv::Mat& disparity_px);

 private:
  void configure_for_channels(int channels);
  void run(const cv::Mat& left, const cv::Mat& right, cv::Mat& disparity_px);

  SgbmConfig config_;
  cv::Ptr<cv::StereoSGBM> sgbm_;
  int configured_channels_ = 0;
  cv::Mat raw_;  // CV_16S fixed-point output (disparity * 16)
  cv::Mat crop_disparity_, small_left_, small_right_, small_disparity_;
  std::vector<cv::Rect> merged_;
};

// Converts StereoSGBM's fixed-point output to float pixels, 0 where invalid (below min_disparity).
void sgbm_raw_to_px(const cv::Mat& raw_16s, int min_disparity, cv::Mat& disparity_px);

}  // namespace agvslam::stereo
