#include "agvslam/dynamic/multiframe_test.h"

#include <algorithm>
#include <cmath>
#include <opencv2/video/tracking.hpp>

namespace agvslam::dynamic {

// ---- TrackHistory --------------------------------------------------------------------------------------------

TrackHistory::TrackHistory(int depth) : depth_(std::max(1, depth)) {}

void TrackHistory::clear() {
  age_.clear();
  run_.clear();
  strict_run_.clear();
  px_.clear();
  d_.clear();
}

void TrackHistory::next_frame(const std::vector<cv::Point2f>& px, const std::vector<float>& d,
                              const std::vector<uint8_t>& consistent) {
  CV_Assert(px.size() == size() && d.size() == size() && consistent.size() == size());
  ++frame_;
  const auto depth = static_cast<std::size_t>(depth_);
  const auto slot = static_cast<std::size_t>(frame_ % depth_);
  for (std::size_t i = 0; i < size(); ++i) {
    px_[i * depth + slot] = px[i];
    d_[i * depth + slot] = d[i];
    age_[i] = std::min(age_[i] + 1, depth_ - 1);
    run_[i] = consistent[i] ? std::min(run_[i] + 1, depth_ - 1) : 0;
    strict_run_[i] = consistent[i] == kStepConsistent ? std::min(strict_run_[i] + 1, depth_ - 1) : 0;
  }
}

void TrackHistory::retain(const std::vector<uint8_t>& keep) {
  CV_Assert(keep.size() == size());
  const auto depth = static_cast<std::size_t>(depth_);
  std::size_t out = 0;
  for (std::size_t i = 0; i < size(); ++i) {
    if (!keep[i]) continue;
    if (out != i) {
      std::copy_n(px_.begin() + static_cast<std::ptrdiff_t>(i * depth), depth,
                  px_.begin() + static_cast<std::ptrdiff_t>(out * depth));
      std::copy_n(d_.begin() + static_cast<std::ptrdiff_t>(i * depth), depth,
                  d_.begin() + static_cast<std::ptrdiff_t>(out * depth));
      age_[out] = age_[i];
      run_[out] = run_[i];
      strict_run_[out] = strict_run_[i];
    }
    ++out;
  }
  age_.resize(out);
  run_.resize(out);
  strict_run_.resize(out);
  px_.resize(out * depth);
  d_.resize(out * depth);
}

void TrackHistory::add(const cv::Point2f& px, float d) {
  const auto depth = static_cast<std::size_t>(depth_);
  const auto slot = static_cast<std::size_t>(frame_ % depth_);
  const std::size_t row = age_.size();
  px_.resize((row + 1) * depth, cv::Point2f(0, 0));
  d_.resize((row + 1) * depth, 0.0f);
  px_[row * depth + slot] = px;
  d_[row * depth + slot] = d;
  age_.push_back(0);
  run_.push_back(0);
  strict_run_.push_back(0);
}

void TrackHistory::add_earlier(int back, const cv::Point2f& px, float d) {
  CV_Assert(!age_.empty() && back >= 1);
  if (back >= depth_) return;
  const auto depth = static_cast<std::size_t>(depth_);
  const std::size_t row = age_.size() - 1;
  const auto slot = static_cast<std::size_t>(((frame_ - back) % depth_ + depth_) % depth_);
  px_[row * depth + slot] = px;
  d_[row * depth + slot] = d;
  age_.back() = std::max(age_.back(), back);
}

bool TrackHistory::observation(std::size_t i, int back, cv::Point2f& px, float& d) const {
  if (i >= size() || back < 0 || back > age_[i] || back >= depth_) return false;
  const auto depth = static_cast<std::size_t>(depth_);
  const auto slot = static_cast<std::size_t>(((frame_ - back) % depth_ + depth_) % depth_);
  px = px_[i * depth + slot];
  d = d_[i * depth + slot];
  return true;
}

// ---- MultiFrameTest ------------------------------------------------------------------------------------------

namespace {
DepthTestConfig inner_test_config(const MultiFrameTestConfig& c) {
  c.validate("MultiFrameTestConfig");
  DepthTestConfig d;
  d.min_points = c.min_points;
  d.min_disparity_px = c.min_disparity_px;
  d.ransac_reprojection_px = c.ransac_reprojection_px;
  d.a_reproj_px = c.a_reproj_px;
  d.b_reproj = c.b_reproj;
  d.a_disp_px = c.a_disp_px;
  d.b_disp = c.b_disp;
  d.adaptive = true;
  d.adaptive_k = c.adaptive_k;
  d.max_scale = c.max_scale;
  d.prior_min_inlier_fraction = c.prior_min_inlier_fraction;
  return d;
}
}  // namespace

double offset_across_edge(const cv::Mat& image, const cv::Point2f& p, int half, const PinholeCamera& camera,
                          double bf_px_m, const SE3d& T_cur_ref, const cv::Point2f& ref_px, float ref_disparity_px,
                          double ratio) {
  const int x0 = cvRound(p.x) - half, y0 = cvRound(p.y) - half;
  if (x0 < 1 || y0 < 1 || x0 + 2 * half + 1 >= image.cols - 1 || y0 + 2 * half + 1 >= image.rows - 1) return -1;
  double gxx = 0, gxy = 0, gyy = 0;
  for (int y = y0; y <= y0 + 2 * half; ++y) {
    const uint8_t* r = image.ptr<uint8_t>(y);
    const uint8_t* up = image.ptr<uint8_t>(y - 1);
    const uint8_t* down = image.ptr<uint8_t>(y + 1);
    for (int x = x0; x <= x0 + 2 * half; ++x) {
      const double gx = 0.5 * (r[x + 1] - r[x - 1]);
      const double gy = 0.5 * (down[x] - up[x]);
      gxx += gx * gx;
      gxy += gx * gy;
      gyy += gy * gy;
    }
  }
  const double tr = gxx + gyy, det = gxx * gyy - gxy * gxy;
  const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  const double l_max = 0.5 * tr + disc, l_min = 0.5 * tr - disc;
  if (!(l_max > 0) || l_min >= ratio * l_max) return -1;
  // Eigenvector of l_max.
  Eigen::Vector2d v = std::abs(gxy) > 1e-12 ? Eigen::Vector2d(l_max - gyy, gxy)
                                            : (gxx >= gyy ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1));
  v.normalize();
  Eigen::Vector2d predicted;
  double depth_m = 0;
  if (!DepthConsistencyTest::predict(camera, bf_px_m, T_cur_ref, ref_px, ref_disparity_px, predicted, depth_m))
    return -1;
  return std::abs((predicted - Eigen::Vector2d(p.x, p.y)).dot(v));
}

MultiFrameTest::MultiFrameTest(const MultiFrameTestConfig& config)
    : config_(config), test_(inner_test_config(config)) {}

void MultiFrameTest::reset() {
  for (Frame& f : frames_) spare_.push_back(std::move(f.left));
  frames_.clear();
}

void MultiFrameTest::add_frame(const SE3d& T_cur_prev, bool valid, const cv::Mat& left) {
  if (!valid || frames_.empty() || frames_.back().left.size() != left.size()) reset();
  Frame f;
  f.T_w_c = frames_.empty() ? SE3d::Identity() : frames_.back().T_w_c * T_cur_prev.inverse();
  if (!spare_.empty()) {
    f.left = std::move(spare_.back());
    spare_.pop_back();
  }
  left.copyTo(f.left);
  frames_.push_back(std::move(f));
  while (static_cast<int>(frames_.size()) > config_.max_frames + 1) {
    spare_.push_back(std::move(frames_.front().left));
    frames_.pop_front();
  }
}

int MultiFrameTest::held_steps(const TrackHistory& history, std::size_t i) const {
  // Steps a track's history holds since the reference: those the per-frame depth test passed, or (chain_stereo_only)
  // those its stereo agreed on.
  return config_.chain_stereo_only ? history.consistent_steps(i) : history.consistent_steps_strict(i);
}

int MultiFrameTest::choose_reference(const TrackHistory& history, const std::vector<uint8_t>& usable,
                                     SE3d& T_ref_cur) const {
  // Candidate references, newest first: k frames back along the chain.
  const std::size_t n = history.size();
  const int h = static_cast<int>(frames_.size());
  const int max_back = std::min({h - 1, config_.max_frames, history.depth() - 1});
  const double max_rotation_rad = config_.max_rotation_deg * M_PI / 180.0;
  const SE3d& T_w_cur = frames_.back().T_w_c;
  auto count_both = [&](int k) {
    int count = 0;
    cv::Point2f p;
    float d = 0;
    for (std::size_t i = 0; i < n; ++i) {
      count +=
          usable[i] && held_steps(history, i) >= k && history.observation(i, k, p, d) && d >= config_.min_disparity_px
              ? 1
              : 0;
    }
    return count;
  };
  int chosen = -1;
  T_ref_cur = SE3d::Identity();
  for (int k = config_.min_frames; k <= max_back; ++k) {
    const SE3d T = frames_[static_cast<std::size_t>(h - 1 - k)].T_w_c.inverse() * T_w_cur;
    if (rotation_angle_rad(T) > max_rotation_rad) break;  // older ones turned even more (on a turning vehicle)
    if (count_both(k) < config_.min_points) break;        // older ones share even fewer tracks
    chosen = k;
    T_ref_cur = T;
    if (T.translation().norm() >= config_.min_translation_m) break;
  }
  return chosen;
}

void MultiFrameTest::verify_flagged(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history,
                                    const std::vector<cv::Mat>& cur_pyramid, const LkTrackerConfig& tracking,
                                    int chosen, MultiFrameResult& result) {
  // LK of the current patch straight into the reference image, from the track's own reference position.
  cand_cur_.clear();
  cand_ref_.clear();
  cand_index_.clear();
  for (std::size_t i = 0; i < history.size(); ++i) {
    if (!result.test.dynamic[i]) continue;
    cand_cur_.push_back(cur_px_[i]);
    cand_ref_.push_back(ref_px_[i]);
    cand_index_.push_back(static_cast<int>(i));
  }
  result.flagged = static_cast<int>(cand_index_.size());
  if (cand_index_.empty()) return;
  const cv::Size win(tracking.window_px, tracking.window_px);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, tracking.max_iterations,
                              tracking.epsilon);
  const cv::Mat& ref_left = result.reference_left;
  cv::buildOpticalFlowPyramid(ref_left, ref_pyramid_, win, config_.verify_levels, false);
  cv::calcOpticalFlowPyrLK(cur_pyramid, ref_pyramid_, cand_cur_, cand_ref_, status_, errors_, win,
                           config_.verify_levels, crit, cv::OPTFLOW_USE_INITIAL_FLOW, tracking.min_eigen_threshold);
  cand_back_ = cand_cur_;
  cv::calcOpticalFlowPyrLK(ref_pyramid_, cur_pyramid, cand_ref_, cand_back_, back_status_, errors_, win,
                           config_.verify_levels, crit, cv::OPTFLOW_USE_INITIAL_FLOW, tracking.min_eigen_threshold);
  const float fb2 = static_cast<float>(config_.verify_fb_px * config_.verify_fb_px);
  const cv::Size size = ref_left.size();
  for (std::size_t k = 0; k < cand_index_.size(); ++k) {
    const auto i = static_cast<std::size_t>(cand_index_[k]);
    result.test.dynamic[i] = 0;
    const cv::Point2f found = cand_ref_[k];
    const cv::Point2f fb = cand_back_[k] - cand_cur_[k];
    if (!status_[k] || !back_status_[k] || fb.dot(fb) > fb2 ||
        !(found.x >= 0 && found.y >= 0 && found.x < size.width && found.y < size.height)) {
      result.test.reprojection_px[i] = -1;  // not verifiable: neither dynamic nor static
      result.test.disparity_residual_px[i] = -1;
      continue;
    }
    judge_verified(camera, bf_px_m, history, cur_pyramid[0], tracking.window_px / 2, chosen, i, found, result);
    result.confirmed += result.test.dynamic[i];
  }
}

void MultiFrameTest::judge_verified(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history,
                                    const cv::Mat& cur_left, int half_window_px, int chosen, std::size_t i,
                                    const cv::Point2f& found, MultiFrameResult& result) const {
  const float shift2 = static_cast<float>(config_.verify_max_shift_px * config_.verify_max_shift_px);
  const cv::Point2f shift = found - ref_px_[i];
  const bool same_point = shift.dot(shift) <= shift2;
  // The found reference position with the reference disparity, moved into the current camera: how far from
  // the current position?
  double offset = -1, r_disp = -1;
  DepthConsistencyTest::residuals(camera, bf_px_m, result.T_cur_ref, found, ref_d_[i], cur_px_[i], cur_d_[i], offset,
                                  r_disp);
  const double d = cur_d_[i] > 0 ? cur_d_[i] : ref_d_[i];
  const double t_2d = result.test.a_reproj_used_px + config_.b_reproj * d;
  bool off_2d = offset >= 0 && offset > t_2d;
  if (off_2d && config_.aperture_ratio > 0 && offset < 1e5) {
    const double across = offset_across_edge(cur_left, cur_px_[i], half_window_px, camera, bf_px_m, result.T_cur_ref,
                                             found, ref_d_[i], config_.aperture_ratio);
    if (across >= 0) off_2d = across > t_2d;
  }
  bool off_depth = same_point && r_disp >= 0 && r_disp > result.test.a_disp_used_px + config_.b_disp * d;
  // A track the per-frame depth test flagged since the reference (chained on stereo alone) must be off by
  // chain_stereo_factor times the thresholds: noisy static tracks fail the per-frame test now and then too.
  if (history.consistent_steps_strict(i) < chosen) {
    off_2d = off_2d && offset > config_.chain_stereo_factor * t_2d;
    off_depth = off_depth && r_disp > config_.chain_stereo_factor * (result.test.a_disp_used_px + config_.b_disp * d);
  }
  result.test.reprojection_px[i] = offset;
  result.test.disparity_residual_px[i] = same_point ? r_disp : -1;
  result.test.dynamic[i] = off_2d || off_depth ? 1 : 0;
}

void MultiFrameTest::run(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history,
                         const std::vector<uint8_t>& usable, const std::vector<cv::Mat>& cur_pyramid,
                         const LkTrackerConfig& tracking, MultiFrameResult& result) {
  const std::size_t n = history.size();
  CV_Assert(usable.size() == n);
  result.valid = false;
  result.frames_back = 0;
  result.translation_m = 0;
  result.rotation_deg = 0;
  result.candidates = 0;
  result.flagged = 0;
  result.confirmed = 0;
  result.T_cur_ref = SE3d::Identity();
  result.reference_left.release();
  result.test = DepthTestResult{};
  result.test.reprojection_px.assign(n, -1.0);
  result.test.disparity_residual_px.assign(n, -1.0);
  result.test.dynamic.assign(n, 0);
  if (!config_.enabled || frames_.size() < 2) return;

  SE3d T_ref_cur;
  const int chosen = choose_reference(history, usable, T_ref_cur);
  if (chosen < 0) return;
  result.frames_back = chosen;
  result.translation_m = T_ref_cur.translation().norm();
  result.rotation_deg = rotation_angle_rad(T_ref_cur) * 180.0 / M_PI;

  ref_px_.assign(n, cv::Point2f(0, 0));
  cur_px_.assign(n, cv::Point2f(0, 0));
  ref_d_.assign(n, 0.0f);
  cur_d_.assign(n, 0.0f);
  both_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!usable[i] || held_steps(history, i) < chosen) continue;
    if (!history.observation(i, chosen, ref_px_[i], ref_d_[i]) || !history.observation(i, 0, cur_px_[i], cur_d_[i]))
      continue;
    both_[i] = 1;
    result.candidates += ref_d_[i] >= config_.min_disparity_px ? 1 : 0;
  }
  // The reference plays the "previous" frame of the depth-consistency test: motion, residuals, decisions.
  const SE3d T_cur_ref_chained = T_ref_cur.inverse();
  test_.run(camera, bf_px_m, ref_px_, ref_d_, cur_px_, cur_d_, both_, result.test, &T_cur_ref_chained);
  if (!result.test.valid) return;
  result.T_cur_ref = result.test.T_cur_prev;
  result.reference_left = frames_[frames_.size() - 1 - static_cast<std::size_t>(chosen)].left;
  result.valid = true;
  // Verification of the flagged tracks.
  verify_flagged(camera, bf_px_m, history, cur_pyramid, tracking, chosen, result);
}

}  // namespace agvslam::dynamic
