#include "agvslam/dynamic/band_segmenter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/bilinear.h"
#include "agvslam/dynamic/static_warp.h"

namespace agvslam::dynamic {

namespace {

constexpr float kInvalid = 1e6f;  // a hypothesis that leaves the previous image (its 5x5 mean stays >= 4e4)
constexpr float kInvalidMean = 1e3f;

double point_segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  const double sx = bx - ax, sy = by - ay;
  const double len2 = sx * sx + sy * sy;
  double s = len2 > 0 ? ((px - ax) * sx + (py - ay) * sy) / len2 : 0.0;
  s = std::clamp(s, 0.0, 1.0);
  return std::hypot(px - (ax + s * sx), py - (ay + s * sy));
}

}  // namespace

BandSegmenter::BandSegmenter(const BandSegmenterConfig& config) : config_(config) {
  config_.validate("BandSegmenterConfig");
}

double BandSegmenter::static_segment_length(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                            double u, double v) const {
  const StaticWarp warp(camera, bf_px_m, T_cur_prev);
  double u0, v0, um, vm, u1, v1;
  if (!warp.at(u, v, 0.0, u0, v0) || !warp.at(u, v, 0.5 * config_.max_disparity_px, um, vm) ||
      !warp.at(u, v, config_.max_disparity_px, u1, v1)) {
    return std::numeric_limits<double>::infinity();
  }
  return std::hypot(um - u0, vm - v0) + std::hypot(u1 - um, v1 - vm);
}

double BandSegmenter::static_segment_distance(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                              const cv::Point2f& cur_px, const cv::Point2f& prev_px) const {
  const StaticWarp warp(camera, bf_px_m, T_cur_prev);
  constexpr int kPieces = 8;
  double best = std::numeric_limits<double>::infinity();
  double au = 0, av = 0;
  bool have_a = false;
  for (int k = 0; k <= kPieces; ++k) {
    double bu, bv;
    if (!warp.at(cur_px.x, cur_px.y, config_.max_disparity_px * k / kPieces, bu, bv)) {
      have_a = false;
      continue;
    }
    if (have_a)
      best = std::min(best, point_segment_distance(prev_px.x, prev_px.y, au, av, bu, bv));
    else if (k == kPieces)
      best = std::min(best, std::hypot(prev_px.x - bu, prev_px.y - bv));
    au = bu;
    av = bv;
    have_a = true;
  }
  return best;
}

double BandSegmenter::longest_static_segment(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                             cv::Size image) const {
  const int strip = std::min(config_.strip_px, image.width);
  double longest = 0;
  for (double u : {0.0, 0.5 * (strip - 1), static_cast<double>(strip - 1)}) {
    for (double v : {0.0, 0.5 * (image.height - 1), static_cast<double>(image.height - 1)}) {
      longest = std::max(longest, static_segment_length(camera, bf_px_m, T_cur_prev, u, v));
    }
  }
  return longest;
}

void BandSegmenter::untracked_strip_corners(const cv::Mat& cur_left, const cv::Mat& masked,
                                            const std::vector<cv::Point2f>& occupied_px, int cell_px) {
  const BandSegmenterConfig& c = config_;
  const int w = cur_left.cols, h = cur_left.rows;
  const int strip = std::min(c.strip_px, w);
  const int cells_x = (strip + cell_px - 1) / cell_px, cells_y = (h + cell_px - 1) / cell_px;
  auto cell_of = [&](const cv::Point2f& p) {
    return std::clamp(static_cast<int>(p.y) / cell_px, 0, cells_y - 1) * cells_x +
           std::clamp(static_cast<int>(p.x) / cell_px, 0, cells_x - 1);
  };
  tracked_cell_.assign(static_cast<std::size_t>(cells_x * cells_y), 0);
  for (const cv::Point2f& p : occupied_px) {
    if (p.x >= 0 && p.x < strip && p.y >= 0 && p.y < h) tracked_cell_[static_cast<std::size_t>(cell_of(p))] = 1;
  }
  keypoints_.clear();
  cv::FAST(cur_left(cv::Rect(0, 0, strip, h)), keypoints_, c.fast_threshold, true);
  best_corner_.assign(static_cast<std::size_t>(cells_x * cells_y), -1);
  for (std::size_t k = 0; k < keypoints_.size(); ++k) {
    const cv::Point2f& p = keypoints_[k].pt;
    if (p.x < c.border_px || p.y < c.border_px || p.y >= h - c.border_px) continue;
    const int cell = cell_of(p);
    if (tracked_cell_[static_cast<std::size_t>(cell)]) continue;
    if (!masked.empty() && masked.at<uint8_t>(std::clamp(cvRound(p.y), 0, h - 1), std::clamp(cvRound(p.x), 0, w - 1)))
      continue;
    int& b = best_corner_[static_cast<std::size_t>(cell)];
    if (b < 0 || keypoints_[k].response > keypoints_[static_cast<std::size_t>(b)].response) b = static_cast<int>(k);
  }
  corners_.clear();
  for (int b : best_corner_) {
    if (b >= 0) corners_.push_back(keypoints_[static_cast<std::size_t>(b)].pt);
  }
}

bool BandSegmenter::driving_seeds(const cv::Mat& cur_left, const std::vector<cv::Mat>& cur_pyramid,
                                  const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels,
                                  const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                  const std::vector<cv::Point2f>& track_cur, std::vector<BandSeed>& seeds) {
  seeds.clear();
  const BandSegmenterConfig& c = config_;
  if (!c.enabled || !(c.driving_seed_offset_px > 0) || cur_left.empty()) return false;
  CV_Assert(cur_left.type() == CV_8UC1);
  if (std::min(c.strip_px, cur_left.cols) <= 2 * c.border_px || cur_left.rows <= 2 * c.border_px) return false;
  if (longest_static_segment(camera, bf_px_m, T_cur_prev, cur_left.size()) <= c.max_static_segment_px) return false;
  untracked_strip_corners(cur_left, cv::Mat(), track_cur, c.driving_cell_px);
  if (corners_.empty()) return true;
  tracker.track(cur_pyramid, prev_pyramid, corners_, back_, ok_, lk_levels);
  for (std::size_t i = 0; i < corners_.size(); ++i) {
    if (!ok_[i]) continue;
    const double offset = static_segment_distance(camera, bf_px_m, T_cur_prev, corners_[i], back_[i]);
    if (offset > c.driving_seed_offset_px) seeds.push_back({corners_[i], back_[i], offset});
  }
  return true;
}

namespace {
// The previous image at (x, y) by bilinear interpolation; -1 outside it.
float sample_previous(const cv::Mat& prev_left, double x, double y) {
  const double max_x = prev_left.cols - 1, max_y = prev_left.rows - 1;
  return (x >= 0 && y >= 0 && x < max_x && y < max_y) ? static_cast<float>(bilinear_u8(prev_left, x, y)) : -1.0f;
}
}  // namespace

void BandSegmenter::collect_seeds(const cv::Mat& cur_left, const std::vector<cv::Mat>& cur_pyramid,
                                  const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels,
                                  const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                  const cv::Mat& masked, const std::vector<cv::Point2f>& track_prev,
                                  const std::vector<cv::Point2f>& track_cur, BandResult& out) {
  const BandSegmenterConfig& c = config_;
  const int w = cur_left.cols, h = cur_left.rows;
  const int strip = std::min(c.strip_px, w);
  // The caller's tracks in the strip are tested as they are; FAST corners (the strongest per cell, none on masked
  // pixels) of the cells that hold no track are tracked back into the previous image and tested.
  auto masked_at = [&](const cv::Point2f& p) {
    return !masked.empty() &&
           masked.at<uint8_t>(std::clamp(cvRound(p.y), 0, h - 1), std::clamp(cvRound(p.x), 0, w - 1)) != 0;
  };
  auto test = [&](const cv::Point2f& cur, const cv::Point2f& prev) {
    const double offset = static_segment_distance(camera, bf_px_m, T_cur_prev, cur, prev);
    if (offset > c.seed_offset_px) out.seeds.push_back({cur, prev, offset});
  };
  for (std::size_t i = 0; i < track_cur.size(); ++i) {
    const cv::Point2f& p = track_cur[i];
    if (!(p.x >= 0 && p.x < strip && p.y >= 0 && p.y < h)) continue;
    ++out.tracks;
    if (!masked_at(p)) test(p, track_prev[i]);
  }
  untracked_strip_corners(cur_left, masked, track_cur, c.cell_px);
  out.corners = static_cast<int>(corners_.size());
  if (!corners_.empty()) {
    tracker.track(cur_pyramid, prev_pyramid, corners_, back_, ok_, lk_levels);
    for (std::size_t i = 0; i < corners_.size(); ++i) {
      if (ok_[i]) test(corners_[i], back_[i]);
    }
  }
  if (static_cast<int>(out.seeds.size()) > c.max_seeds) {
    std::nth_element(out.seeds.begin(), out.seeds.begin() + c.max_seeds, out.seeds.end(),
                     [](const BandSeed& a, const BandSeed& b) { return a.offset_px > b.offset_px; });
    out.seeds.resize(static_cast<std::size_t>(c.max_seeds));
  }
}

cv::Rect BandSegmenter::search_area(const std::vector<BandSeed>& seeds, cv::Size image) {
  // The strip (and the closing's reach beyond it) over the rows the seeds' motions reach.
  const BandSegmenterConfig& c = config_;
  const int w = image.width, h = image.height;
  float seed_y0 = static_cast<float>(h), seed_y1 = 0;
  for (const BandSeed& s : seeds) {
    seed_y0 = std::min(seed_y0, s.cur_px.y);
    seed_y1 = std::max(seed_y1, s.cur_px.y);
  }
  const int margin = c.reach_px + c.close_px;
  const int y0 = std::max(0, static_cast<int>(seed_y0) - margin);
  const int y1 = std::min(h, static_cast<int>(seed_y1) + 1 + margin);
  // The seeds' motions, each distinct one (to a quarter pixel) once.
  flows_.clear();
  flow_of_.assign(seeds.size(), -1);
  for (std::size_t j = 0; j < seeds.size(); ++j) {
    const cv::Point2f f = seeds[j].prev_px - seeds[j].cur_px;
    const cv::Point2f q(std::round(4.0f * f.x) / 4.0f, std::round(4.0f * f.y) / 4.0f);
    auto it = std::find(flows_.begin(), flows_.end(), q);
    flow_of_[j] = static_cast<int>(it - flows_.begin());
    if (it == flows_.end()) flows_.push_back(q);
  }
  return cv::Rect(0, y0, std::min(w, std::min(c.strip_px, w) + c.close_px), y1 - y0);
}

void BandSegmenter::static_hypothesis(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera,
                                      double bf_px_m, const SE3d& T_cur_prev, const cv::Rect& area, double longest) {
  // The least error over the segment's samples. (A segment shorter than a step is one sample: the camera stood or
  // turned on the spot.)
  const BandSegmenterConfig& c = config_;
  const StaticWarp warp(camera, bf_px_m, T_cur_prev);
  const int samples =
      longest < c.segment_step_px ? 1 : std::clamp(static_cast<int>(std::ceil(longest / c.segment_step_px)) + 1, 2, 64);
  static_error_.create(area.size(), CV_32F);
  static_error_.setTo(kInvalid);
  for (int k = 0; k < samples; ++k) {
    const double d = samples == 1 ? 0.5 * c.max_disparity_px : c.max_disparity_px * k / (samples - 1);
    for (int y = 0; y < area.height; ++y) {
      const uint8_t* cur = cur_left.ptr<uint8_t>(y + area.y) + area.x;
      float* dst = diff_.ptr<float>(y);
      for (int x = 0; x < area.width; ++x) {
        double pu, pv;
        float v = kInvalid;
        if (warp.at(x + area.x, y + area.y, d, pu, pv)) {
          const float prev = sample_previous(prev_left, pu, pv);
          if (prev >= 0) v = std::abs(static_cast<float>(cur[x]) - prev);
        }
        dst[x] = v;
      }
    }
    cv::blur(diff_, blurred_, cv::Size(5, 5), cv::Point(-1, -1), cv::BORDER_REPLICATE);
    cv::min(static_error_, blurred_, static_error_);
  }
}

void BandSegmenter::seed_hypotheses(const cv::Mat& cur_left, const cv::Mat& prev_left, const cv::Rect& area,
                                    const std::vector<BandSeed>& seeds) {
  // Each distinct seed motion's error image, within reach_px of its seeds.
  const int reach = config_.reach_px;
  seed_error_.resize(flows_.size());
  for (std::size_t j = 0; j < flows_.size(); ++j) {
    const cv::Point2f f = flows_[j];
    float fx0 = static_cast<float>(cur_left.cols), fy0 = static_cast<float>(cur_left.rows), fx1 = 0, fy1 = 0;
    for (std::size_t k = 0; k < seeds.size(); ++k) {
      if (flow_of_[k] != static_cast<int>(j)) continue;
      fx0 = std::min(fx0, seeds[k].cur_px.x);
      fy0 = std::min(fy0, seeds[k].cur_px.y);
      fx1 = std::max(fx1, seeds[k].cur_px.x);
      fy1 = std::max(fy1, seeds[k].cur_px.y);
    }
    const cv::Rect box = cv::Rect(cv::Point(static_cast<int>(fx0) - reach, static_cast<int>(fy0) - reach),
                                  cv::Point(static_cast<int>(fx1) + reach + 1, static_cast<int>(fy1) + reach + 1)) &
                         area;
    seed_error_[j].create(area.size(), CV_32F);
    seed_error_[j].setTo(kInvalid);
    if (box.empty()) continue;
    const cv::Rect local = box - area.tl();
    for (int y = local.y; y < local.br().y; ++y) {
      const uint8_t* cur = cur_left.ptr<uint8_t>(y + area.y) + area.x;
      float* dst = diff_.ptr<float>(y);
      for (int x = local.x; x < local.br().x; ++x) {
        const float prev = sample_previous(prev_left, x + area.x + f.x, y + area.y + f.y);
        dst[x] = prev >= 0 ? std::abs(static_cast<float>(cur[x]) - prev) : kInvalid;
      }
    }
    cv::blur(diff_(local), seed_error_[j](local), cv::Size(5, 5), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  }
}

void BandSegmenter::evidence(const cv::Rect& area, const std::vector<BandSeed>& seeds) {
  // Each pixel's object error: the least over the motions of its nearest seeds (found per 4x4 block, at its
  // centre); the evidence: static minus object error.
  constexpr int kBlock = 4;
  const std::size_t n_seeds = seeds.size();
  const int nearest = std::min<int>(config_.nearest_seeds, static_cast<int>(n_seeds));
  const float max_object_error = static_cast<float>(config_.max_object_error_dn);
  by_distance_.resize(n_seeds);
  evidence_.create(area.size(), CV_32F);
  for (int by = 0; by < area.height; by += kBlock) {
    for (int bx = 0; bx < area.width; bx += kBlock) {
      const float cx_px = static_cast<float>(area.x + bx) + 0.5f * kBlock,
                  cy_px = static_cast<float>(area.y + by) + 0.5f * kBlock;
      for (std::size_t j = 0; j < n_seeds; ++j) {
        const float dx = seeds[j].cur_px.x - cx_px, dy = seeds[j].cur_px.y - cy_px;
        by_distance_[j] = {dx * dx + dy * dy, flow_of_[j]};
      }
      std::partial_sort(by_distance_.begin(), by_distance_.begin() + nearest, by_distance_.end());
      block_flows_.clear();
      for (int q = 0; q < nearest; ++q) {
        const int f = by_distance_[static_cast<std::size_t>(q)].second;
        if (std::find(block_flows_.begin(), block_flows_.end(), f) == block_flows_.end()) block_flows_.push_back(f);
      }
      for (int y = by; y < std::min(by + kBlock, area.height); ++y) {
        const float* se = static_error_.ptr<float>(y);
        float* ev = evidence_.ptr<float>(y);
        for (int x = bx; x < std::min(bx + kBlock, area.width); ++x) {
          float oe = kInvalid;
          for (int f : block_flows_) oe = std::min(oe, seed_error_[static_cast<std::size_t>(f)].ptr<float>(y)[x]);
          // A pixel no seed's motion explains (uncovered background, or another surface) gets no evidence for it.
          ev[x] = (se[x] >= kInvalidMean || oe >= kInvalidMean) ? 0.0f
                  : oe > max_object_error                       ? std::min(0.0f, se[x] - oe)
                                                                : se[x] - oe;
        }
      }
    }
  }
}

void BandSegmenter::binarize(const cv::Rect& area, int strip, const cv::Mat& masked) {
  const BandSegmenterConfig& c = config_;
  cv::blur(evidence_, blurred_, cv::Size(5, 5), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  cv::compare(blurred_, c.evidence_dn, binary_, cv::CMP_GT);
  // Closing with a disc of diameter close_px by two distance transforms (linear in the area, where a morphological
  // closing with a 21 px ellipse costs its area times the kernel's): dilate, then erode what lies within the radius
  // of the dilation's outside (the image's own edges are no outside: a sliver at the border keeps its width).
  const float radius = 0.5f * static_cast<float>(c.close_px);
  cv::compare(binary_, 0, outside_, cv::CMP_EQ);
  cv::distanceTransform(outside_, distance_, cv::DIST_L2, cv::DIST_MASK_3);
  cv::compare(distance_, radius, binary_, cv::CMP_LE);
  cv::distanceTransform(binary_, distance_, cv::DIST_L2, cv::DIST_MASK_3);
  cv::compare(distance_, radius, binary_, cv::CMP_GT);
  // Inside the strip, off what is masked already.
  if (area.width > strip) binary_.colRange(strip, area.width).setTo(0);
  if (!masked.empty()) binary_.setTo(0, masked(area));
  // Rows reaching the last columns, where no 5x5 window fits, continue to the edge.
  for (int y = 0; y < area.height && c.edge_fill_px > 0; ++y) {
    uint8_t* row = binary_.ptr<uint8_t>(y);
    const uint8_t* free = masked.empty() ? nullptr : masked.ptr<uint8_t>(y + area.y);
    int first = -1;
    for (int x = 0; x <= std::min(c.edge_fill_px, area.width - 1); ++x) {
      if (row[x]) {
        first = x;
        break;
      }
    }
    for (int x = 0; x < first; ++x) {
      if (!free || !free[x]) row[x] = 255;
    }
  }
}

void BandSegmenter::seeded_regions(const cv::Rect& area, BandResult& out) {
  // The connected parts that hold a seed.
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(binary_, labels_, stats, centroids, 8, CV_32S);
  std::vector<int> region_of(static_cast<std::size_t>(n), -1);
  for (std::size_t j = 0; j < out.seeds.size(); ++j) {
    const cv::Point q(cvRound(out.seeds[j].cur_px.x) - area.x, cvRound(out.seeds[j].cur_px.y) - area.y);
    if (q.x < 0 || q.y < 0 || q.x >= area.width || q.y >= area.height) continue;
    const int l = labels_.at<int32_t>(q);
    if (l <= 0) continue;
    if (region_of[static_cast<std::size_t>(l)] < 0) {
      region_of[static_cast<std::size_t>(l)] = static_cast<int>(out.regions.size());
      BandRegion r;
      r.rect = cv::Rect(stats.at<int>(l, cv::CC_STAT_LEFT) + area.x, stats.at<int>(l, cv::CC_STAT_TOP) + area.y,
                        stats.at<int>(l, cv::CC_STAT_WIDTH), stats.at<int>(l, cv::CC_STAT_HEIGHT));
      r.pixels = stats.at<int>(l, cv::CC_STAT_AREA);
      cv::compare(labels_(r.rect - area.tl()), l, r.mask, cv::CMP_EQ);
      out.regions.push_back(std::move(r));
    }
    out.regions[static_cast<std::size_t>(region_of[static_cast<std::size_t>(l)])].seeds.push_back(static_cast<int>(j));
  }
}

void BandSegmenter::segment(const cv::Mat& cur_left, const cv::Mat& prev_left, const std::vector<cv::Mat>& cur_pyramid,
                            const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels,
                            const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, const cv::Mat& masked,
                            const std::vector<cv::Point2f>& track_prev, const std::vector<cv::Point2f>& track_cur,
                            BandResult& out) {
  CV_Assert(track_prev.size() == track_cur.size());
  out = BandResult{};
  const BandSegmenterConfig& c = config_;
  if (!c.enabled || cur_left.empty() || prev_left.empty()) return;
  CV_Assert(cur_left.type() == CV_8UC1 && prev_left.type() == CV_8UC1 && cur_left.size() == prev_left.size());
  CV_Assert(masked.empty() || (masked.type() == CV_8UC1 && masked.size() == cur_left.size()));
  const int strip = std::min(c.strip_px, cur_left.cols);
  if (strip <= 2 * c.border_px || cur_left.rows <= 2 * c.border_px) return;
  // The test is sharp only where a static point's previous position hardly depends on its depth.
  const double longest = longest_static_segment(camera, bf_px_m, T_cur_prev, cur_left.size());
  out.static_segment_px = longest;
  if (!(longest <= c.max_static_segment_px)) return;
  out.ran = true;
  collect_seeds(cur_left, cur_pyramid, prev_pyramid, tracker, lk_levels, camera, bf_px_m, T_cur_prev, masked,
                track_prev, track_cur, out);
  if (static_cast<int>(out.seeds.size()) < c.min_seeds) return;
  const cv::Rect area = search_area(out.seeds, cur_left.size());
  diff_.create(area.size(), CV_32F);
  // The static hypothesis against the object hypotheses: the seeds' own image motions (seeds of one mover share
  // theirs).
  static_hypothesis(cur_left, prev_left, camera, bf_px_m, T_cur_prev, area, longest);
  seed_hypotheses(cur_left, prev_left, area, out.seeds);
  evidence(area, out.seeds);
  binarize(area, strip, masked);
  seeded_regions(area, out);
}

}  // namespace agvslam::dynamic
