#include "agvslam/dynamic/densifier.h"

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/video/tracking.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::dynamic {

Densifier::Densifier(const DensifyOptions& options, const DensifierContext& context,
                     const StereoCalibration& calibration)
    : options_(options), context_(context), calibration_(calibration) {}

bool Densifier::select_seeds(const DetectorResult& result, const PointTracks& tracks, const DynamicPoints& dynamic) {
  // When both per-frame tests ran, a point both flag; otherwise every dynamic point.
  const bool both =
      context_.use_epipolar_test && context_.use_depth_test && result.epipolar.valid && result.depth.valid;
  // ... or one the depth test flags well beyond its threshold: a far person walking along the epipolar lines.
  auto strong_depth = [&](const TrackedPoint& p) {
    return options_.depth_seed_factor > 0 && p.dynamic_depth && p.reprojection_px >= 0 &&
           p.reprojection_px >= options_.depth_seed_factor * tracks.depth_test().reprojection_threshold_px(
                                                                 result.depth, std::max(0.0f, p.cur_disparity_px));
  };
  seed_pts_.clear();
  seed_disp_.clear();
  seed_index_.clear();
  for (std::size_t k = 0; k < dynamic.index.size(); ++k) {
    const TrackedPoint& p = result.points[static_cast<std::size_t>(dynamic.index[k])];
    if (both && !(p.dynamic_epipolar && p.dynamic_depth) && !p.dynamic_multiframe && !strong_depth(p)) continue;
    seed_pts_.push_back(dynamic.px[k]);
    seed_disp_.push_back(dynamic.disparity_px[k]);
    seed_index_.push_back(dynamic.index[k]);
  }
  return static_cast<int>(seed_pts_.size()) >= options_.min_seeds;
}

bool Densifier::needs_points(const DynamicGroup& g, const DynamicPoints& dynamic) const {
  const int min_points = context_.grouping.min_points;
  if (static_cast<int>(g.members.size()) >= min_points) return false;  // already a ROI
  // A group beside enough dynamic points (those that are no seeds included) becomes a ROI anyway.
  const float reach2 = static_cast<float>(context_.grouping.a_s_px * context_.grouping.a_s_px);
  int near_dynamic = 0;
  for (const cv::Point2f& q : dynamic.px) {
    for (int m : g.members) {
      const cv::Point2f d = q - seed_pts_[static_cast<std::size_t>(m)];
      if (d.dot(d) <= reach2) {
        ++near_dynamic;
        break;
      }
    }
  }
  return near_dynamic < 2 * min_points;
}

bool Densifier::group_reference_motion(const DynamicGroup& g, const DetectorResult& result, const PointTracks& tracks,
                                       cv::Point2f& motion) {
  const SE3d T_ref_cur = result.multiframe.T_cur_ref.inverse();
  mf_vx_.clear();
  mf_vy_.clear();
  for (int m : g.members) {
    const auto idx = static_cast<std::size_t>(seed_index_[static_cast<std::size_t>(m)]);
    const TrackedPoint& sp = result.points[idx];
    cv::Point2f ref_px;
    float ref_d = 0;
    Eigen::Vector2d pred;
    double depth_m = 0;
    if (idx >= tracks.history().size() ||
        !tracks.history().observation(idx, result.multiframe.frames_back, ref_px, ref_d) ||
        !(sp.cur_disparity_px > 0) ||
        !DepthConsistencyTest::predict(calibration_.left, calibration_.bf(), T_ref_cur, sp.cur_px, sp.cur_disparity_px,
                                       pred, depth_m)) {
      continue;
    }
    mf_vx_.push_back(ref_px.x - static_cast<float>(pred.x()));
    mf_vy_.push_back(ref_px.y - static_cast<float>(pred.y()));
  }
  if (static_cast<int>(mf_vx_.size()) < options_.min_seeds) return false;
  motion = cv::Point2f(static_cast<float>(median_in_place(mf_vx_, -1.0f)),
                       static_cast<float>(median_in_place(mf_vy_, -1.0f)));
  return true;
}

void Densifier::add_corners(const DynamicGroup& g, const cv::Mat& prev_left, const cv::Rect& inner,
                            const DetectorResult& result, const PointTracks& tracks) {
  // The window around the group's previous positions.
  float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
  for (int m : g.members) {
    const cv::Point2f& p = result.points[static_cast<std::size_t>(seed_index_[static_cast<std::size_t>(m)])].prev_px;
    x0 = std::min(x0, p.x);
    y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x);
    y1 = std::max(y1, p.y);
  }
  const int r =
      static_cast<int>(std::lround(options_.radius_px + options_.radius_disparity_factor * g.mean_disparity_px));
  const cv::Rect window = cv::Rect(cv::Point(static_cast<int>(x0) - r, static_cast<int>(y0) - r),
                                   cv::Point(static_cast<int>(x1) + r + 1, static_cast<int>(y1) + r + 1)) &
                          inner;
  if (window.width < 8 || window.height < 8) return;
  keypoints_.clear();
  cv::FAST(prev_left(window), keypoints_, context_.features.min_threshold, true);
  std::sort(keypoints_.begin(), keypoints_.end(),
            [](const cv::KeyPoint& a, const cv::KeyPoint& c) { return a.response > c.response; });
  const std::size_t first_new = extra_prev_.size();
  cv::Point2f group_motion(0, 0);
  const bool group_motion_valid = options_.multiframe_levels >= 0 && result.multiframe.valid &&
                                  group_reference_motion(g, result, tracks, group_motion);
  const std::vector<cv::Point2f>& existing = tracks.tracks();
  const float min_d2 = static_cast<float>(options_.min_distance_px * options_.min_distance_px);
  const int track_cap = context_.tracking.max_tracks + options_.extra_tracks;
  for (const cv::KeyPoint& kp : keypoints_) {
    if (static_cast<int>(extra_prev_.size() - first_new) >= options_.max_points) break;
    if (static_cast<int>(existing.size() + extra_prev_.size()) >= track_cap) break;
    const cv::Point2f p(kp.pt.x + static_cast<float>(window.x), kp.pt.y + static_cast<float>(window.y));
    bool near = false;
    for (const cv::Point2f& q : existing) {
      const cv::Point2f d = q - p;
      if (d.dot(d) < min_d2) {
        near = true;
        break;
      }
    }
    for (std::size_t k = 0; k < extra_prev_.size() && !near; ++k) {
      const cv::Point2f d = extra_prev_[k] - p;
      near = d.dot(d) < min_d2;
    }
    if (!near) {
      extra_prev_.push_back(p);
      extra_group_motion_.push_back(group_motion);
      extra_group_valid_.push_back(group_motion_valid ? 1 : 0);
    }
  }
}

void Densifier::densify(const StereoFrame& frame, const cv::Mat& prev_left, const cv::Mat& prev_right,
                        PointTracks& tracks, DynamicPoints& dynamic, DetectorResult& result) {
  if (!select_seeds(result, tracks, dynamic)) return;
  RoiGroupingConfig small = context_.grouping;
  small.min_points = options_.min_seeds;
  const std::vector<DynamicGroup> groups =
      group_dynamic_points(seed_pts_, seed_disp_, frame.left.size(), small, calibration_.baseline_m);
  const int b = context_.features.border_px;
  const cv::Rect inner(b, b, frame.left.cols - 2 * b, frame.left.rows - 2 * b);
  extra_prev_.clear();
  extra_group_motion_.clear();
  extra_group_valid_.clear();
  for (const DynamicGroup& g : groups) {
    if (needs_points(g, dynamic)) add_corners(g, prev_left, inner, result, tracks);
  }
  if (extra_prev_.empty()) return;

  tracks.track_points(extra_prev_, extra_cur_, extra_ok_, result.lk_levels);
  extra_prev_disp_.assign(extra_prev_.size(), 0.0f);
  extra_cur_disp_.assign(extra_prev_.size(), 0.0f);
  for (std::size_t i = 0; i < extra_prev_.size(); ++i) {
    if (!extra_ok_[i]) continue;
    extra_cur_disp_[i] = tracks.match_disparity(frame.left, frame.right, extra_cur_[i]);
    if (context_.use_depth_test) extra_prev_disp_[i] = tracks.match_disparity(prev_left, prev_right, extra_prev_[i]);
  }
  test_multiframe(frame, result, tracks);
  for (std::size_t i = 0; i < extra_prev_.size(); ++i) {
    if (!extra_ok_[i]) continue;
    tracks.append_new_point(tracks.test_new_point(result, extra_prev_[i], extra_cur_[i], extra_prev_disp_[i],
                                                  extra_cur_disp_[i], extra_mf_px_[i], extra_mf_[i] != 0),
                            result, dynamic);
  }
}

void Densifier::track_into_reference(const cv::Mat& cur_left, const cv::Mat& ref_left) {
  const LkTrackerConfig& trk = context_.tracking;
  const int levels = options_.multiframe_levels;
  const cv::Size win(trk.window_px, trk.window_px);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, trk.max_iterations, trk.epsilon);
  // LK on the part of both images the points and their predictions lie in, with room for the pyramid's reach
  // (OpenCV takes the derivatives of every pyramid level it is given, so whole images would cost ~10x more).
  cv::Rect area = cv::boundingRect(mf_cur_) | cv::boundingRect(mf_pred_);
  const int margin = trk.window_px * (1 << levels);
  area = cv::Rect(area.x - margin, area.y - margin, area.width + 2 * margin, area.height + 2 * margin) &
         cv::Rect(0, 0, ref_left.cols, ref_left.rows);
  const cv::Point2f origin(static_cast<float>(area.x), static_cast<float>(area.y));
  for (std::size_t k = 0; k < mf_cur_.size(); ++k) {
    mf_cur_[k] -= origin;
    mf_pred_[k] -= origin;
  }
  cv::buildOpticalFlowPyramid(cur_left(area), mf_cur_pyramid_, win, levels, false);
  cv::buildOpticalFlowPyramid(ref_left(area), mf_ref_pyramid_, win, levels, false);
  mf_ref_ = mf_pred_;
  cv::calcOpticalFlowPyrLK(mf_cur_pyramid_, mf_ref_pyramid_, mf_cur_, mf_ref_, mf_status_, mf_errors_, win, levels,
                           crit, cv::OPTFLOW_USE_INITIAL_FLOW, trk.min_eigen_threshold);
  mf_back_ = mf_cur_;
  cv::calcOpticalFlowPyrLK(mf_ref_pyramid_, mf_cur_pyramid_, mf_ref_, mf_back_, mf_back_status_, mf_errors_, win,
                           levels, crit, cv::OPTFLOW_USE_INITIAL_FLOW, trk.min_eigen_threshold);
  for (std::size_t k = 0; k < mf_cur_.size(); ++k) {
    mf_cur_[k] += origin;
    mf_pred_[k] += origin;
    mf_ref_[k] += origin;
    mf_back_[k] += origin;
  }
}

bool Densifier::moved_with_group(std::size_t k, const StereoFrame& frame, const DetectorResult& result,
                                 PointTracks& tracks) {
  const MultiFrameTestConfig& mf = context_.multiframe;
  const cv::Mat& ref_left = result.multiframe.reference_left;
  const float w = static_cast<float>(ref_left.cols - 1), h = static_cast<float>(ref_left.rows - 1);
  const auto i = static_cast<std::size_t>(mf_index_[k]);
  const cv::Point2f found = mf_ref_[k];
  const cv::Point2f fb = mf_back_[k] - mf_cur_[k];
  const float fb2 = static_cast<float>(mf.verify_fb_px * mf.verify_fb_px);
  if (!mf_status_[k] || !mf_back_status_[k] || fb.dot(fb) > fb2 ||
      !(found.x >= 0 && found.y >= 0 && found.x <= w && found.y <= h)) {
    return false;
  }
  const float d = extra_cur_disp_[i];
  const cv::Point2f off = found - mf_pred_[k];
  const double offset = std::sqrt(static_cast<double>(off.dot(off)));
  extra_mf_px_[i] = offset;
  const double threshold = options_.multiframe_factor * (result.multiframe.test.a_reproj_used_px + mf.b_reproj * d);
  if (!(offset > threshold)) return false;
  // ... and it moved with its group (a static point whose current disparity is wrong, on repetitive racking, is
  // predicted off and LK finds it somewhere else: off by as much, but not the way the group moved).
  const cv::Point2f& gm = extra_group_motion_[i];
  const cv::Point2f dv = off - gm;
  const double group_offset = std::sqrt(static_cast<double>(gm.dot(gm)));
  if (!(group_offset > threshold) ||
      std::sqrt(static_cast<double>(dv.dot(dv))) > std::max(threshold, options_.multiframe_agreement * group_offset)) {
    return false;
  }
  // On an edge-like patch only the offset across the edge counts (multiframe.aperture_ratio).
  if (mf.aperture_ratio > 0) {
    const SE3d T_ref_cur = result.multiframe.T_cur_ref.inverse();
    const double across = offset_across_edge(ref_left, found, context_.tracking.window_px / 2, calibration_.left,
                                             calibration_.bf(), T_ref_cur, extra_cur_[i], d, mf.aperture_ratio);
    if (across >= 0 && !(across > threshold)) return false;
  }
  // Not on a depth edge (its window mixes two surfaces that move apart over the frames), not an ambiguous match.
  return !tracks.on_depth_edge_or_ambiguous(frame, extra_cur_[i], d);
}

void Densifier::test_multiframe(const StereoFrame& frame, const DetectorResult& result, PointTracks& tracks) {
  const std::size_t n = extra_prev_.size();
  extra_mf_.assign(n, 0);
  extra_mf_px_.assign(n, -1.0);
  if (options_.multiframe_levels < 0 || !context_.use_depth_test || !result.multiframe.valid ||
      result.multiframe.reference_left.empty()) {
    return;
  }
  const cv::Mat& ref_left = result.multiframe.reference_left;
  const SE3d T_ref_cur = result.multiframe.T_cur_ref.inverse();
  const float w = static_cast<float>(ref_left.cols - 1), h = static_cast<float>(ref_left.rows - 1);
  // Where each point, static at its current disparity, was in the reference frame.
  mf_cur_.clear();
  mf_pred_.clear();
  mf_index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!extra_ok_[i] || !extra_group_valid_[i] || !(extra_cur_disp_[i] >= context_.multiframe.min_disparity_px))
      continue;
    Eigen::Vector2d pred;
    double depth_m = 0;
    if (!DepthConsistencyTest::predict(calibration_.left, calibration_.bf(), T_ref_cur, extra_cur_[i],
                                       extra_cur_disp_[i], pred, depth_m)) {
      continue;
    }
    const cv::Point2f q(static_cast<float>(pred.x()), static_cast<float>(pred.y()));
    if (!(q.x >= 0 && q.y >= 0 && q.x <= w && q.y <= h)) continue;
    mf_cur_.push_back(extra_cur_[i]);
    mf_pred_.push_back(q);
    mf_index_.push_back(static_cast<int>(i));
  }
  if (mf_index_.empty()) return;
  track_into_reference(frame.left, ref_left);
  for (std::size_t k = 0; k < mf_index_.size(); ++k) {
    if (moved_with_group(k, frame, result, tracks)) extra_mf_[static_cast<std::size_t>(mf_index_[k])] = 1;
  }
}

}  // namespace agvslam::dynamic
