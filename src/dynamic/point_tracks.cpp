#include "agvslam/dynamic/point_tracks.h"
#include "agvslam/core/clock.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "agvslam/core/se3.h"
#include "agvslam/dynamic/bilinear.h"

namespace agvslam::dynamic {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

void DynamicPoints::clear() {
  px.clear();
  disparity_px.clear();
  index.clear();
}

void DynamicPoints::add(const TrackedPoint& p, int point_index) {
  px.push_back(p.cur_px);
  disparity_px.push_back(p.cur_disparity_px);
  index.push_back(point_index);
}

PointTracks::PointTracks(const PointTracksConfig& config, const StereoCalibration& calibration,
                         const stereo::SparseStereoConfig& sparse)
    : config_(config),
      calibration_(calibration),
      features_(config.features),
      tracker_(config.tracking),
      epipolar_(config.epipolar),
      depth_test_(config.depth_test),
      multiframe_(config.multiframe),
      history_(config.multiframe.max_frames + 1),
      sparse_(sparse),
      check_sparse_([&] {
        stereo::SparseStereoConfig c = sparse;
        c.half_window = std::max(1, config.multiframe.check_half_window);
        c.uniqueness_margin = config.multiframe.check_uniqueness_margin;
        return c;
      }()) {}

void PointTracks::reset() {
  last_max_motion_px_ = -1;
  has_motion_prior_ = false;
  prev_pts_.clear();
  prev_disparity_px_.clear();
  history_.clear();
  multiframe_.reset();
}

void PointTracks::build_pyramid(const cv::Mat& left, StageTimings& timings) {
  const auto t = Clock::now();
  tracker_.build_pyramid(left, cur_pyramid_);
  timings.pyramid_ms = ms_since(t);
}

void PointTracks::measure_disparities(const StereoFrame& frame, const std::vector<cv::Point2f>& px,
                                      const std::vector<uint8_t>* usable, const cv::Mat& full_disparity_px,
                                      std::vector<float>& out) {
  out.assign(px.size(), 0.0f);
  for (std::size_t i = 0; i < px.size(); ++i) {
    if (usable != nullptr && i < usable->size() && !(*usable)[i]) continue;
    if (!full_disparity_px.empty()) {
      const int x = static_cast<int>(std::lround(px[i].x)), y = static_cast<int>(std::lround(px[i].y));
      if (x >= 0 && y >= 0 && x < full_disparity_px.cols && y < full_disparity_px.rows) {
        out[i] = full_disparity_px.at<float>(y, x);
      }
    } else {
      out[i] = sparse_.match(frame.left, frame.right, px[i]);
    }
  }
}

bool PointTracks::predicted_starts() {
  lk_start_.clear();
  const double min_px = config_.tracking.predict_min_px;
  if (!has_motion_prior_ || min_px <= 0 || prev_disparity_px_.size() != prev_pts_.size()) return false;
  const PinholeCamera& camera = calibration_.left;
  const cv::Size size = prev_pyramid_.front().size();
  lk_start_ = prev_pts_;
  bool any = false;
  for (std::size_t i = 0; i < prev_pts_.size(); ++i) {
    Eigen::Vector2d uv;
    double depth_m = 0;
    if (!DepthConsistencyTest::predict(camera, calibration_.bf(), T_motion_prior_, prev_pts_[i], prev_disparity_px_[i],
                                       uv, depth_m)) {
      continue;
    }
    const cv::Point2f p(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
    const cv::Point2f step = p - prev_pts_[i];
    if (step.dot(step) <= min_px * min_px) continue;
    if (p.x < 0 || p.y < 0 || p.x > static_cast<float>(size.width - 1) || p.y > static_cast<float>(size.height - 1)) {
      continue;  // leaves the image: LK from the old position decides (usually out too)
    }
    lk_start_[i] = p;
    any = true;
  }
  return any;
}

void PointTracks::follow_tracks(DetectorResult& result) {
  result.lk_levels = tracker_.levels_for_motion(last_max_motion_px_);
  const bool predicted = predicted_starts();
  if (!predicted) {
    tracker_.track(prev_pyramid_, cur_pyramid_, prev_pts_, cur_pts_, tracked_, result.lk_levels);
  } else {
    // The predicted tracks search on the finest levels only (the prediction is a few px off; the coarse levels of a
    // repeated pattern would pull them a period away), the others as before.
    split_.assign(2, {});
    for (std::size_t i = 0; i < prev_pts_.size(); ++i) split_[lk_start_[i] != prev_pts_[i] ? 1 : 0].push_back(i);
    cur_pts_.assign(prev_pts_.size(), cv::Point2f());
    tracked_.assign(prev_pts_.size(), 0);
    for (int part = 0; part < 2; ++part) {
      const std::vector<std::size_t>& idx = split_[static_cast<std::size_t>(part)];
      if (idx.empty()) continue;
      part_prev_.clear();
      part_start_.clear();
      for (std::size_t i : idx) {
        part_prev_.push_back(prev_pts_[i]);
        part_start_.push_back(lk_start_[i]);
      }
      const int levels = part == 1 ? std::min(result.lk_levels, config_.tracking.min_levels) : result.lk_levels;
      tracker_.track(prev_pyramid_, cur_pyramid_, part_prev_, part_cur_, part_ok_, levels,
                     part == 1 ? &part_start_ : nullptr);
      for (std::size_t k = 0; k < idx.size(); ++k) {
        cur_pts_[idx[k]] = part_cur_[k];
        tracked_[idx[k]] = part_ok_[k];
      }
    }
  }
  // The next frame's levels follow the largest motion from where the searches started.
  const std::vector<cv::Point2f>& start = predicted ? lk_start_ : prev_pts_;
  float max_motion2 = -1;
  for (std::size_t i = 0; i < tracked_.size(); ++i) {
    if (!tracked_[i]) continue;
    const cv::Point2f m = cur_pts_[i] - start[i];
    max_motion2 = std::max(max_motion2, m.dot(m));
  }
  last_max_motion_px_ = max_motion2 < 0 ? -1.0 : std::sqrt(static_cast<double>(max_motion2));
}

void PointTracks::track_and_test(const StereoFrame& frame, DetectorResult& result) {
  StageTimings& tm = result.timings;
  auto t = Clock::now();
  follow_tracks(result);
  tm.tracking_ms = ms_since(t);
  t = Clock::now();
  measure_disparities(frame, cur_pts_, &tracked_, result.full_disparity_px, cur_disparity_px_);
  tm.point_disparity_ms += ms_since(t);

  t = Clock::now();
  epipolar_.run(prev_pts_, cur_pts_, tracked_, cur_disparity_px_, result.epipolar);
  tm.epipolar_ms = ms_since(t);
  t = Clock::now();
  if (config_.use_depth_test) {
    depth_test_.run(calibration_.left, calibration_.bf(), prev_pts_, prev_disparity_px_, cur_pts_, cur_disparity_px_,
                    tracked_, result.depth);
  }
  if (config_.use_depth_test && result.depth.valid) drop_ambiguous_tracks(frame, result);
  has_motion_prior_ = config_.use_depth_test && result.depth.valid;
  if (has_motion_prior_) T_motion_prior_ = result.depth.T_cur_prev;
  tm.depth_test_ms = ms_since(t);
  t = Clock::now();
  test_multiframe(frame, result);
  tm.multiframe_ms = ms_since(t);
}

namespace {

// Zero-mean normalised cross-correlation of the (2h+1)^2 patch of `a` around pa with the patch of `b` around pb whose
// offsets are scaled by `scale`; -1 when a patch leaves its image.
double scaled_zncc(const cv::Mat& a, const cv::Point2f& pa, const cv::Mat& b, const Eigen::Vector2d& pb, double scale,
                   int h) {
  const double reach_b = scale * h + 1;
  if (pa.x < h || pa.y < h || pa.x >= a.cols - h - 1 || pa.y >= a.rows - h - 1 || pb.x() < reach_b ||
      pb.y() < reach_b || pb.x() >= b.cols - reach_b - 1 || pb.y() >= b.rows - reach_b - 1) {
    return -1;
  }
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const int n = (2 * h + 1) * (2 * h + 1);
  for (int dy = -h; dy <= h; ++dy) {
    for (int dx = -h; dx <= h; ++dx) {
      const double va = bilinear_u8(a, pa.x + dx, pa.y + dy);
      const double vb = bilinear_u8(b, pb.x() + scale * dx, pb.y() + scale * dy);
      sa += va;
      sb += vb;
      saa += va * va;
      sbb += vb * vb;
      sab += va * vb;
    }
  }
  const double var_a = saa - sa * sa / n, var_b = sbb - sb * sb / n;
  if (!(var_a > 0) || !(var_b > 0)) return -1;
  return (sab - sa * sb / n) / std::sqrt(var_a * var_b);
}

}  // namespace

void PointTracks::drop_ambiguous_tracks(const StereoFrame& frame, DetectorResult& result) {
  const DepthTestConfig& dc = config_.depth_test;
  if (dc.leaving_margin_px < 0 && !(dc.slip_min_px > 0)) return;
  const PinholeCamera& camera = calibration_.left;
  const double w = frame.left.cols, h = frame.left.rows;
  for (std::size_t i = 0; i < prev_pts_.size(); ++i) {
    if (!tracked_[i]) continue;
    Eigen::Vector2d uv;
    double depth_m = 0;
    if (!DepthConsistencyTest::predict(camera, calibration_.bf(), result.depth.T_cur_prev, prev_pts_[i],
                                       prev_disparity_px_[i], uv, depth_m)) {
      continue;
    }
    const double m = dc.leaving_margin_px;
    const bool left_view = m >= 0 && (uv.x() < -m || uv.y() < -m || uv.x() > w - 1 + m || uv.y() > h - 1 + m);
    bool slipped = false;
    const bool flagged = result.depth.dynamic[i] || (!result.epipolar.dynamic.empty() && result.epipolar.dynamic[i]);
    if (!left_view && flagged && dc.slip_min_px > 0 &&
        std::hypot(uv.x() - cur_pts_[i].x, uv.y() - cur_pts_[i].y) > dc.slip_min_px) {
      // The patch grows as the point comes nearer: by its previous depth over the predicted one.
      const double scale = calibration_.bf() / prev_disparity_px_[i] / depth_m;
      slipped = scaled_zncc(prev_pyramid_.front(), prev_pts_[i], frame.left, uv, scale, dc.slip_half_window) >=
                dc.slip_min_zncc;
    }
    if (!left_view && !slipped) continue;
    tracked_[i] = 0;
    result.depth.dynamic[i] = 0;
    if (!result.epipolar.dynamic.empty()) result.epipolar.dynamic[i] = 0;
  }
}

void PointTracks::test_multiframe(const StereoFrame& frame, DetectorResult& result) {
  // Each track's step to this frame, as the depth test saw it: consistent with the ego-motion, or off only in its
  // disparity (a stereo mismatch), for the multi-frame test's chains.
  consistent_.assign(prev_pts_.size(), 0);
  if (result.depth.valid) {
    for (std::size_t i = 0; i < consistent_.size(); ++i) {
      const double r_disp = result.depth.disparity_residual_px[i];
      const bool measured = tracked_[i] && result.depth.reprojection_px[i] >= 0 && r_disp >= 0;
      if (!measured) continue;
      if (!result.depth.dynamic[i]) {
        consistent_[i] = TrackHistory::kStepConsistent;
      } else if (!depth_test_.disparity_off(result.depth, r_disp, cur_disparity_px_[i])) {
        consistent_[i] = TrackHistory::kStepStereoOnly;
      }
    }
  }
  history_.next_frame(cur_pts_, cur_disparity_px_, consistent_);
  multiframe_.add_frame(result.depth.T_cur_prev, config_.use_depth_test && result.depth.valid, frame.left);
  if (config_.use_depth_test) {
    multiframe_.run(calibration_.left, calibration_.bf(), history_, tracked_, cur_pyramid_, config_.tracking,
                    result.multiframe);
  } else {
    result.multiframe = MultiFrameResult{};
  }
  // Depth-edge check of the tracks only the multi-frame test flags.
  if (!result.multiframe.valid || config_.multiframe.edge_check_px <= 0) return;
  std::vector<uint8_t>& flagged = result.multiframe.test.dynamic;
  for (std::size_t i = 0; i < flagged.size(); ++i) {
    if (!flagged[i] || result.depth.dynamic.empty() || result.depth.dynamic[i] ||
        (!result.epipolar.dynamic.empty() && result.epipolar.dynamic[i])) {
      continue;
    }
    if (on_depth_edge_or_ambiguous(frame, cur_pts_[i], cur_disparity_px_[i])) flagged[i] = 0;
  }
}

void PointTracks::collect_points(DetectorResult& result, DynamicPoints& dynamic) const {
  const std::size_t n = prev_pts_.size();
  result.points.resize(n);
  dynamic.clear();
  for (std::size_t i = 0; i < n; ++i) {
    TrackedPoint& p = result.points[i];
    p = TrackedPoint{};
    p.prev_px = prev_pts_[i];
    p.cur_px = cur_pts_[i];
    p.prev_disparity_px = prev_disparity_px_[i];
    p.cur_disparity_px = cur_disparity_px_[i];
    p.tracked = tracked_[i] != 0;
    p.age = history_.age(i);
    if (!p.tracked) continue;
    if (result.epipolar.valid) {
      p.d_epi_px = result.epipolar.d_epi_px[i];
      p.t_epi_px = result.epipolar.t_epi_px[i];
      p.dynamic_epipolar = result.epipolar.dynamic[i] != 0;
    }
    if (result.depth.valid) {
      p.reprojection_px = result.depth.reprojection_px[i];
      p.disparity_residual_px = result.depth.disparity_residual_px[i];
      p.dynamic_depth = result.depth.dynamic[i] != 0;
    }
    if (result.multiframe.valid) {
      p.multiframe_px = result.multiframe.test.reprojection_px[i];
      p.multiframe_disparity_residual_px = result.multiframe.test.disparity_residual_px[i];
      p.dynamic_multiframe = result.multiframe.test.dynamic[i] != 0;
    }
    p.dynamic = flagged_by_enabled_tests(p);
    if (p.dynamic) dynamic.add(p, static_cast<int>(i));
  }
}

TrackedPoint PointTracks::test_new_point(const DetectorResult& result, const cv::Point2f& prev_px,
                                         const cv::Point2f& cur_px, float prev_disparity_px, float cur_disparity_px,
                                         double multiframe_px, bool dynamic_multiframe) const {
  TrackedPoint p;
  p.prev_px = prev_px;
  p.cur_px = cur_px;
  p.prev_disparity_px = prev_disparity_px;
  p.cur_disparity_px = cur_disparity_px;
  p.tracked = true;
  p.densified = true;
  p.age = 1;
  p.dynamic_epipolar =
      epipolar_.test_track(result.epipolar, p.prev_px, p.cur_px, p.cur_disparity_px, &p.d_epi_px, &p.t_epi_px);
  if (config_.use_depth_test && result.depth.valid) {
    depth_test_.slack_residuals(calibration_.left, calibration_.bf(), result.depth.T_cur_prev, p.prev_px,
                                p.prev_disparity_px, p.cur_px, p.cur_disparity_px, p.reprojection_px,
                                p.disparity_residual_px);
    p.dynamic_depth = depth_test_.is_dynamic(result.depth, p.reprojection_px, p.disparity_residual_px,
                                             p.cur_disparity_px > 0 ? p.cur_disparity_px : p.prev_disparity_px);
  }
  p.multiframe_px = multiframe_px;
  p.dynamic_multiframe = dynamic_multiframe;
  p.dynamic = flagged_by_enabled_tests(p);
  return p;
}

void PointTracks::append_new_point(const TrackedPoint& p, DetectorResult& result, DynamicPoints& dynamic) {
  result.points.push_back(p);
  history_.add(p.cur_px, p.cur_disparity_px);
  history_.add_earlier(1, p.prev_px, p.prev_disparity_px);
  if (p.dynamic) dynamic.add(p, static_cast<int>(result.points.size() - 1));
}

bool PointTracks::flagged_by_enabled_tests(const TrackedPoint& p) const {
  return (config_.use_epipolar_test && p.dynamic_epipolar) ||
         (config_.use_depth_test && (p.dynamic_depth || p.dynamic_multiframe));
}

void PointTracks::track_points(const std::vector<cv::Point2f>& prev_px, std::vector<cv::Point2f>& cur_px,
                               std::vector<uint8_t>& ok, int levels) {
  tracker_.track(prev_pyramid_, cur_pyramid_, prev_px, cur_px, ok, levels);
}

float PointTracks::match_disparity(const cv::Mat& left, const cv::Mat& right, const cv::Point2f& px) {
  return sparse_.match(left, right, px);
}

bool PointTracks::on_depth_edge_or_ambiguous(const StereoFrame& frame, const cv::Point2f& px, float disparity_px) {
  const MultiFrameTestConfig& mf = config_.multiframe;
  const double tol = mf.edge_tolerance_px + mf.edge_tolerance_rel * disparity_px;
  bool edge = !(disparity_px > 0);
  if (mf.edge_check_px > 0) {
    const auto r = static_cast<float>(mf.edge_check_px);
    const cv::Point2f offsets[4] = {{-r, 0}, {r, 0}, {0, -r}, {0, r}};
    const auto w = static_cast<float>(frame.left.cols - 1), h = static_cast<float>(frame.left.rows - 1);
    for (int k = 0; k < 4 && !edge; ++k) {
      const cv::Point2f q = px + offsets[k];
      if (q.x < 0 || q.y < 0 || q.x > w || q.y > h) continue;
      const float dq = sparse_.match(frame.left, frame.right, q);
      edge = dq > 0 && std::abs(dq - disparity_px) > tol;
    }
  }
  if (!edge && mf.check_half_window > 0) {
    const float dc = check_sparse_.match(frame.left, frame.right, px);
    edge = !(dc > 0) || std::abs(dc - disparity_px) > tol;
  }
  return edge;
}

void PointTracks::retain_tracks(const DetectorResult& result, bool keep_static_densified) {
  prev_pts_.clear();
  prev_disparity_px_.clear();
  if (!result.has_previous || !config_.tracking.persistent) {
    history_.clear();
    return;
  }
  keep_.assign(history_.size(), 0);
  const std::size_t n = tracked_.size();
  for (std::size_t i = 0; i < history_.size(); ++i) {
    // Beyond n: densified tracks (all tracked); static ones continue only with keep_static_densified.
    keep_[i] = i < n ? tracked_[i] : (keep_static_densified || result.points[i].dynamic ? 1 : 0);
    if (!keep_[i]) continue;
    cv::Point2f p;
    float d = 0;
    history_.observation(i, 0, p, d);
    prev_pts_.push_back(p);
    prev_disparity_px_.push_back(config_.use_depth_test ? d : 0.0f);
  }
  history_.retain(keep_);
}

void PointTracks::select_new_corners(const cv::Mat& left) {
  const LkTrackerConfig& trk = config_.tracking;
  features_.detect(left, corners_);
  new_pts_.clear();
  const float min_d2 = static_cast<float>(trk.min_track_distance_px * trk.min_track_distance_px);
  // The tracks binned in cells of min_track_distance_px: a corner is near a track only in its own or a
  // neighbouring cell.
  const float cell_px = static_cast<float>(std::max(1.0, trk.min_track_distance_px));
  const int cells_x = static_cast<int>(left.cols / cell_px) + 1, cells_y = static_cast<int>(left.rows / cell_px) + 1;
  auto cell_of = [&](const cv::Point2f& p, int& cx, int& cy) {
    cx = std::clamp(static_cast<int>(p.x / cell_px), 0, cells_x - 1);
    cy = std::clamp(static_cast<int>(p.y / cell_px), 0, cells_y - 1);
  };
  cell_start_.assign(static_cast<std::size_t>(cells_x * cells_y) + 1, 0);
  for (const cv::Point2f& p : prev_pts_) {
    int cx, cy;
    cell_of(p, cx, cy);
    ++cell_start_[static_cast<std::size_t>(cy * cells_x + cx) + 1];
  }
  for (std::size_t k = 1; k < cell_start_.size(); ++k) cell_start_[k] += cell_start_[k - 1];
  cell_fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  cell_points_.resize(prev_pts_.size());
  for (const cv::Point2f& p : prev_pts_) {
    int cx, cy;
    cell_of(p, cx, cy);
    cell_points_[static_cast<std::size_t>(cell_fill_[static_cast<std::size_t>(cy * cells_x + cx)]++)] = p;
  }
  for (const Corner& c : corners_) {
    if (static_cast<int>(prev_pts_.size() + new_pts_.size()) >= trk.max_tracks) break;
    int cx, cy;
    cell_of(c.pt, cx, cy);
    bool near = false;
    for (int y = std::max(0, cy - 1); y <= std::min(cells_y - 1, cy + 1) && !near; ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(cells_x - 1, cx + 1) && !near; ++x) {
        const std::size_t cell = static_cast<std::size_t>(y * cells_x + x);
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1] && !near; ++k) {
          const cv::Point2f e = cell_points_[static_cast<std::size_t>(k)] - c.pt;
          near = e.dot(e) < min_d2;
        }
      }
    }
    if (!near) new_pts_.push_back(c.pt);
  }
}

void PointTracks::replenish(const StereoFrame& frame, DetectorResult& result, bool keep_static_densified) {
  StageTimings& tm = result.timings;
  auto t = Clock::now();
  retain_tracks(result, keep_static_densified);
  if (!result.has_previous) multiframe_.add_frame(SE3d::Identity(), false, frame.left);
  select_new_corners(frame.left);
  tm.features_ms = ms_since(t);
  t = Clock::now();
  if (config_.use_depth_test) {
    measure_disparities(frame, new_pts_, nullptr, result.full_disparity_px, new_disp_);
  } else {
    new_disp_.assign(new_pts_.size(), 0.0f);
  }
  for (std::size_t i = 0; i < new_pts_.size(); ++i) {
    prev_pts_.push_back(new_pts_[i]);
    prev_disparity_px_.push_back(new_disp_[i]);
    history_.add(new_pts_[i], new_disp_[i]);
  }
  tm.point_disparity_ms += ms_since(t);
}

}  // namespace agvslam::dynamic
