#include "agvslam/stereo/sgbm.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace agvslam::stereo {

void sgbm_raw_to_px(const cv::Mat& raw_16s, int min_disparity, cv::Mat& disparity_px) {
  CV_Assert(raw_16s.type() == CV_16SC1);
  disparity_px.create(raw_16s.size(), CV_32FC1);
  const int invalid_below = min_disparity * 16;  // SGBM marks invalid pixels with (min_disparity - 1) * 16
  for (int y = 0; y < raw_16s.rows; ++y) {
    const int16_t* src = raw_16s.ptr<int16_t>(y);
    float* dst = disparity_px.ptr<float>(y);
    for (int x = 0; x < raw_16s.cols; ++x) {
      const int v = src[x];
      dst[x] = v >= invalid_below && v > 0 ? static_cast<float>(v) * (1.0f / 16.0f) : 0.0f;
    }
  }
}

namespace {
int to_cv_mode(SgbmMode mode) {
  switch (mode) {
    case SgbmMode::kSgbm:
      return cv::StereoSGBM::MODE_SGBM;
    case SgbmMode::kHh:
      return cv::StereoSGBM::MODE_HH;
    case SgbmMode::kSgbm3Way:
      return cv::StereoSGBM::MODE_SGBM_3WAY;
    case SgbmMode::kHh4:
      return cv::StereoSGBM::MODE_HH4;
  }
  return cv::StereoSGBM::MODE_SGBM;
}
}  // namespace

StereoSgbm::StereoSgbm(const SgbmConfig& config) : config_(config) {
  config_.validate("SgbmConfig");
  sgbm_ = cv::StereoSGBM::create(config_.min_disparity, config_.num_disparities, config_.block_size);
  sgbm_->setDisp12MaxDiff(config_.disp12_max_diff);
  sgbm_->setPreFilterCap(config_.pre_filter_cap);
  sgbm_->setUniquenessRatio(config_.uniqueness_ratio);
  sgbm_->setSpeckleWindowSize(config_.speckle_window_size);
  sgbm_->setSpeckleRange(config_.speckle_range);
  sgbm_->setMode(to_cv_mode(config_.mode));
  configure_for_channels(1);
}

void StereoSgbm::configure_for_channels(int channels) {
  if (channels == configured_channels_) return;
  sgbm_->setP1(config_.effective_p1(channels));
  sgbm_->setP2(config_.effective_p2(channels));
  configured_channels_ = channels;
}

void StereoSgbm::run(const cv::Mat& left, const cv::Mat& right, cv::Mat& disparity_px) {
  CV_Assert(!left.empty() && left.size() == right.size() && left.type() == right.type());
  CV_Assert(left.depth() == CV_8U);
  configure_for_channels(left.channels());
  sgbm_->compute(left, right, raw_);
  sgbm_raw_to_px(raw_, config_.min_disparity, disparity_px);
}

void StereoSgbm::compute(const cv::Mat& left, const cv::Mat& right, cv::Mat& disparity_px) {
  run(left, right, disparity_px);
}

int StereoSgbm::roi_num_disparities(int max_disparity_px) const {
  if (max_disparity_px <= 0) return config_.num_disparities;
  const int needed = max_disparity_px - config_.min_disparity + 1;
  const int rounded = std::max(16, (needed + 15) / 16 * 16);
  return std::min(rounded, config_.num_disparities);
}

cv::Rect StereoSgbm::crop_for(const cv::Rect& roi, cv::Size image_size, int num_disparities) const {
  const int num = num_disparities > 0 ? num_disparities : config_.num_disparities;
  const int max_disparity = config_.min_disparity + num - 1;
  const int margin = config_.roi_margin_px + config_.block_size / 2;
  const int x0 = roi.x - margin - max_disparity - 1;
  const int y0 = roi.y - margin;
  int x1 = roi.x + roi.width + margin;
  const int y1 = roi.y + roi.height + margin;
  // StereoSGBM needs a crop wider than the search range: widen to the right near the left image border.
  const int min_width = max_disparity + 1 + 2 * margin + 16;
  x1 = std::max(x1, std::max(x0, 0) + min_width);
  return cv::Rect(cv::Point(x0, y0), cv::Point(x1, y1)) & cv::Rect(cv::Point(0, 0), image_size);
}

void StereoSgbm::compute_roi(const cv::Mat& left, const cv::Mat& right, const cv::Rect& roi, cv::Mat& roi_disparity_px,
                             int max_disparity_px, double scale, int row_step) {
  CV_Assert(scale == 1.0 || scale == 0.5);
  CV_Assert(row_step == 1 || row_step == 2);
  const cv::Rect image_rect(cv::Point(0, 0), left.size());
  const cv::Rect clipped = roi & image_rect;
  if (clipped.empty()) {
    roi_disparity_px.release();
    return;
  }
  const int num = roi_num_disparities(max_disparity_px);
  const cv::Rect crop = crop_for(clipped, left.size(), num);
  if (scale == 1.0) {
    if (num != config_.num_disparities) sgbm_->setNumDisparities(num);
    if (row_step == 1) {
      run(left(crop), right(crop), crop_disparity_);
    } else {
      const cv::Size rows_halved(crop.width, (crop.height + 1) / 2);
      cv::resize(left(crop), small_left_, rows_halved, 0, 0, cv::INTER_AREA);
      cv::resize(right(crop), small_right_, rows_halved, 0, 0, cv::INTER_AREA);
      run(small_left_, small_right_, small_disparity_);
      crop_disparity_.create(crop.size(), CV_32FC1);
      for (int y = 0; y < crop.height; ++y) small_disparity_.row(y / 2).copyTo(crop_disparity_.row(y));
    }
    if (num != config_.num_disparities) sgbm_->setNumDisparities(config_.num_disparities);
  } else {
    // Half resolution: half the disparities (rounded up to 16), then back to full-resolution pixels.
    const int half_num = std::max(16, (num / 2 + 15) / 16 * 16);
    const int saved_min = config_.min_disparity;
    cv::resize(left(crop), small_left_, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
    cv::resize(right(crop), small_right_, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
    sgbm_->setNumDisparities(half_num);
    sgbm_->setMinDisparity(saved_min / 2);
    configure_for_channels(small_left_.channels());
    sgbm_->compute(small_left_, small_right_, raw_);
    sgbm_->setNumDisparities(config_.num_disparities);
    sgbm_->setMinDisparity(saved_min);
    sgbm_raw_to_px(raw_, saved_min / 2, small_disparity_);
    small_disparity_ *= 2.0f;
    cv::resize(small_disparity_, crop_disparity_, crop.size(), 0, 0, cv::INTER_NEAREST);
  }
  crop_disparity_(cv::Rect(clipped.tl() - crop.tl(), clipped.size())).copyTo(roi_disparity_px);
}

void StereoSgbm::compute_rois(const cv::Mat& left, const cv::Mat& right, const std::vector<cv::Rect>& rois,
                              cv::Mat& disparity_px) {
  const cv::Rect image_rect(cv::Point(0, 0), left.size());
  disparity_px.create(left.size(), CV_32FC1);
  disparity_px.setTo(0.0f);
  // Group overlapping ROIs so that shared pixels are matched once.
  merged_.clear();
  for (const cv::Rect& r : rois) {
    const cv::Rect c = r & image_rect;
    if (!c.empty()) merged_.push_back(c);
  }
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 0; i < merged_.size() && !changed; ++i) {
      for (std::size_t j = i + 1; j < merged_.size(); ++j) {
        if ((merged_[i] & merged_[j]).empty()) continue;
        merged_[i] |= merged_[j];
        merged_.erase(merged_.begin() + static_cast<std::ptrdiff_t>(j));
        changed = true;
        break;
      }
    }
  }
  for (const cv::Rect& box : merged_) {
    const cv::Rect crop = crop_for(box, left.size());
    run(left(crop), right(crop), crop_disparity_);
    for (const cv::Rect& r : rois) {
      const cv::Rect part = r & box;
      if (part.empty()) continue;
      crop_disparity_(cv::Rect(part.tl() - crop.tl(), part.size())).copyTo(disparity_px(part));
    }
  }
}

}  // namespace agvslam::stereo
