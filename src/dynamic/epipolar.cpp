#include "agvslam/dynamic/epipolar.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/video/tracking.hpp>

namespace agvslam::dynamic {

LkTracker::LkTracker(const LkTrackerConfig& config) : config_(config) { config_.validate("LkTrackerConfig"); }

void LkTracker::build_pyramid(const cv::Mat& grey, std::vector<cv::Mat>& pyramid) const {
  // With the Scharr derivatives of every level: calcOpticalFlowPyrLK takes the derivatives of the pyramid it tracks
  // from when they are not there, over the whole image at each level and call (forward, backward, the
  // densified points, the multi-frame verification). Stored here, each image's derivatives are taken once.
  cv::buildOpticalFlowPyramid(grey, pyramid, cv::Size(config_.window_px, config_.window_px), config_.levels, true);
}

int LkTracker::levels_for_motion(double max_motion_px) const {
  if (!(max_motion_px >= 0)) return config_.levels;
  const double needed = config_.motion_margin * max_motion_px;
  int levels = std::min(config_.min_levels, config_.levels);
  while (levels < config_.levels && 0.5 * config_.window_px * static_cast<double>(1 << levels) < needed) ++levels;
  return levels;
}

void LkTracker::track(const std::vector<cv::Mat>& prev_pyramid, const std::vector<cv::Mat>& cur_pyramid,
                      const std::vector<cv::Point2f>& prev_pts, std::vector<cv::Point2f>& cur_pts,
                      std::vector<uint8_t>& ok, int levels, const std::vector<cv::Point2f>* start) {
  ok.assign(prev_pts.size(), 0);
  cur_pts.clear();
  if (prev_pts.empty()) return;
  if (levels < 0 || levels > config_.levels) levels = config_.levels;
  const cv::Size win(config_.window_px, config_.window_px);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, config_.max_iterations, config_.epsilon);
  int flags = 0;
  if (start != nullptr) {
    cur_pts = *start;
    flags = cv::OPTFLOW_USE_INITIAL_FLOW;
  }
  cv::calcOpticalFlowPyrLK(prev_pyramid, cur_pyramid, prev_pts, cur_pts, status_, errors_, win, levels, crit, flags,
                           config_.min_eigen_threshold);
  // Backward pass from the forward result, offset back by the start's offset when there was one (without: no
  // prior; starting it at prev_pts would let a wrong forward track converge back to where it came from, and a
  // track that slipped by a period of a repeated pattern ends a period away from prev_pts either way).
  if (start != nullptr) {
    back_pts_.resize(prev_pts.size());
    for (std::size_t i = 0; i < prev_pts.size(); ++i) back_pts_[i] = cur_pts[i] - ((*start)[i] - prev_pts[i]);
  }
  cv::calcOpticalFlowPyrLK(cur_pyramid, prev_pyramid, cur_pts, back_pts_, back_status_, errors_, win, levels, crit,
                           flags, config_.min_eigen_threshold);
  const cv::Size size = cur_pyramid.front().size();
  const float max_fb2 = static_cast<float>(config_.fb_max_error_px * config_.fb_max_error_px);
  for (std::size_t i = 0; i < prev_pts.size(); ++i) {
    if (!status_[i] || !back_status_[i]) continue;
    const cv::Point2f& p = cur_pts[i];
    if (p.x < 0 || p.y < 0 || p.x > static_cast<float>(size.width - 1) || p.y > static_cast<float>(size.height - 1))
      continue;
    const cv::Point2f e = back_pts_[i] - prev_pts[i];
    if (e.dot(e) > max_fb2) continue;
    ok[i] = 1;
  }
}

double epipolar_distance_px(const cv::Matx33d& F, const cv::Point2f& p_prev, const cv::Point2f& p_cur) {
  const cv::Vec3d line = F * cv::Vec3d(p_prev.x, p_prev.y, 1.0);  // eq. 1
  const double norm = std::sqrt(line[0] * line[0] + line[1] * line[1]);
  if (!(norm > 0)) return 0.0;
  return std::abs(line[0] * p_cur.x + line[1] * p_cur.y + line[2]) / norm;  // eq. 2
}

double robust_sigma(std::vector<double>& residuals) {
  if (residuals.empty()) return 0.0;
  const auto mid = residuals.begin() + static_cast<std::ptrdiff_t>(residuals.size() / 2);
  std::nth_element(residuals.begin(), mid, residuals.end());
  return 1.4826 * *mid;
}

EpipolarTest::EpipolarTest(const EpipolarTestConfig& config) : config_(config) {
  config_.validate("EpipolarTestConfig");
}

void EpipolarTest::run(const std::vector<cv::Point2f>& prev_pts, const std::vector<cv::Point2f>& cur_pts,
                       const std::vector<uint8_t>& usable, const std::vector<float>& disparity_px,
                       EpipolarResult& result) {
  const std::size_t n = prev_pts.size();
  CV_Assert(cur_pts.size() == n && usable.size() == n && disparity_px.size() == n);
  result.valid = false;
  result.static_camera = false;
  result.F = cv::Matx33d::zeros();
  result.inliers = 0;
  result.robust_sigma_px = 0;
  result.a_epi_used_px = config_.a_epi_px;
  result.d_epi_px.assign(n, 0.0);
  result.t_epi_px.assign(n, 0.0);
  result.dynamic.assign(n, 0);

  prev_used_.clear();
  cur_used_.clear();
  index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!usable[i]) continue;
    prev_used_.push_back(prev_pts[i]);
    cur_used_.push_back(cur_pts[i]);
    index_.push_back(static_cast<int>(i));
  }
  if (static_cast<int>(index_.size()) < config_.min_tracks) return;

  scratch_.clear();
  for (std::size_t k = 0; k < index_.size(); ++k) scratch_.push_back(cv::norm(cur_used_[k] - prev_used_[k]));
  lengths_ = scratch_;
  const double median_track = robust_sigma(lengths_) / 1.4826;
  if (median_track < config_.min_parallax_px) {
    // The camera has not moved: F is undefined, and a static point stays where it was.
    result.static_camera = true;
    for (std::size_t k = 0; k < index_.size(); ++k) result.d_epi_px[static_cast<std::size_t>(index_[k])] = scratch_[k];
    result.inliers = static_cast<int>(index_.size());
  } else {
    const cv::Mat F = cv::findFundamentalMat(prev_used_, cur_used_, cv::FM_RANSAC, config_.ransac_threshold_px,
                                             config_.ransac_confidence, config_.ransac_max_iterations, inlier_mask_);
    if (F.rows != 3 || F.cols != 3) return;
    cv::Mat F64;
    F.convertTo(F64, CV_64F);
    result.F = cv::Matx33d(F64.ptr<double>());
    result.inliers = cv::countNonZero(inlier_mask_);
    // Least-squares refit (normalised 8-point) on the RANSAC inliers: the minimal-sample F is noisier.
    if (result.inliers >= 8) {
      prev_inliers_.clear();
      cur_inliers_.clear();
      for (std::size_t k = 0; k < index_.size(); ++k) {
        if (!inlier_mask_.at<uint8_t>(static_cast<int>(k))) continue;
        prev_inliers_.push_back(prev_used_[k]);
        cur_inliers_.push_back(cur_used_[k]);
      }
      const cv::Mat refit = cv::findFundamentalMat(prev_inliers_, cur_inliers_, cv::FM_8POINT);
      if (refit.rows == 3 && refit.cols == 3) {
        refit.convertTo(F64, CV_64F);
        result.F = cv::Matx33d(F64.ptr<double>());
      }
    }
    result.inliers = 0;  // recounted with the refitted F
    for (std::size_t k = 0; k < index_.size(); ++k) {
      const double d = epipolar_distance_px(result.F, prev_used_[k], cur_used_[k]);
      result.d_epi_px[static_cast<std::size_t>(index_[k])] = d;
      result.inliers += d <= config_.ransac_threshold_px;
    }
  }
  result.valid = true;

  scratch_.clear();
  for (int i : index_) scratch_.push_back(result.d_epi_px[static_cast<std::size_t>(i)]);
  result.robust_sigma_px = robust_sigma(scratch_);
  double a = config_.a_epi_px;
  if (config_.adaptive)
    a = std::clamp(config_.adaptive_k * result.robust_sigma_px, config_.a_epi_px, config_.a_epi_max_px);
  result.a_epi_used_px = a;
  for (int i : index_) {
    const std::size_t u = static_cast<std::size_t>(i);
    const double d = disparity_px[u] > 0 ? static_cast<double>(disparity_px[u]) : 0.0;
    result.t_epi_px[u] = a + config_.b_epi * d;  // eq. 3
    result.dynamic[u] = result.d_epi_px[u] > result.t_epi_px[u];
  }
}

bool EpipolarTest::test_track(const EpipolarResult& fitted, const cv::Point2f& prev_px, const cv::Point2f& cur_px,
                              float disparity_px, double* d_epi_px, double* t_epi_px) const {
  if (!fitted.valid) return false;
  const double d = fitted.static_camera ? cv::norm(cur_px - prev_px) : epipolar_distance_px(fitted.F, prev_px, cur_px);
  const double t = fitted.a_epi_used_px + config_.b_epi * (disparity_px > 0 ? static_cast<double>(disparity_px) : 0.0);
  if (d_epi_px) *d_epi_px = d;
  if (t_epi_px) *t_epi_px = t;
  return d > t;
}

}  // namespace agvslam::dynamic
