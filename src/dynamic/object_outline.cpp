#include "agvslam/dynamic/object_outline.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::dynamic {

bool tracks_move_together(double median_offset_px, double static_median_px, const OutlineConfig& config) {
  if (!(config.aggregate_ratio > 0) || median_offset_px < 0) return false;
  return median_offset_px >= config.aggregate_min_px &&
         median_offset_px >= config.aggregate_ratio * std::max(0.0, static_median_px);
}

bool tracks_move_together_multiframe(int multiframe_tested, int multiframe_dynamic, double median_offset_px,
                                     const OutlineConfig& config) {
  if (!(config.aggregate_multiframe_fraction > 0) || multiframe_tested <= 0 ||
      multiframe_tested < config.aggregate_min_tracks) {
    return false;
  }
  return multiframe_dynamic >= config.aggregate_multiframe_fraction * multiframe_tested &&
         median_offset_px >= config.aggregate_multiframe_min_px;
}

ObjectOutliner::ObjectOutliner(const OutlineConfig& config) : config_(config) { config_.validate("OutlineConfig"); }

void ObjectOutliner::prepare_floor(const DisparityPlane* ground, cv::Point origin, int w, int h) {
  ground_ = ground != nullptr && ground->valid ? ground : nullptr;
  if (ground_ == nullptr) return;
  // The plane's column and row terms computed once per ROI (the same sums as disparity_at, in its order).
  ground_x_.resize(static_cast<std::size_t>(w));
  ground_y_.resize(static_cast<std::size_t>(h));
  for (int x = 0; x < w; ++x) ground_x_[static_cast<std::size_t>(x)] = ground_->a * static_cast<double>(x + origin.x);
  for (int y = 0; y < h; ++y) ground_y_[static_cast<std::size_t>(y)] = ground_->b * static_cast<double>(y + origin.y);
}

bool ObjectOutliner::is_floor(int x, int y, float d) const {
  if (ground_ == nullptr) return false;
  const double dg = ground_x_[static_cast<std::size_t>(x)] + ground_y_[static_cast<std::size_t>(y)] + ground_->c;
  return dg > 0 && std::abs(d - dg) <= config_.ground_tolerance_px + config_.ground_tolerance_rel * dg;
}

bool ObjectOutliner::add_seed(const cv::Mat& disparity_px, cv::Point origin, double bf_px_m, const cv::Point2f& p,
                              float d, uint8_t label) {
  if (!(d > 0)) return false;
  const OutlineConfig& c = config_;
  const int w = disparity_px.cols, h = disparity_px.rows;
  const int cx = static_cast<int>(std::lround(p.x)) - origin.x, cy = static_cast<int>(std::lround(p.y)) - origin.y;
  const double tol = c.seed_tolerance_px + c.seed_tolerance_rel * d;
  const int r = c.seed_radius_px;
  int best = -1, best_d2 = 1 << 30;
  for (int y = std::max(0, cy - r); y <= std::min(h - 1, cy + r); ++y) {
    const float* row = disparity_px.ptr<float>(y);
    for (int x = std::max(0, cx - r); x <= std::min(w - 1, cx + r); ++x) {
      const int d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
      if (d2 > r * r || d2 >= best_d2) continue;
      if (!(row[x] > 0) || std::abs(row[x] - d) > tol || is_floor(x, y, row[x])) continue;
      best_d2 = d2;
      best = y * w + x;
    }
  }
  if (best < 0 || label_[static_cast<std::size_t>(best)] != 0) return false;
  const float ref = disparity_px.ptr<float>(best / w)[best % w];
  const double z = bf_px_m / ref;
  Seed s;
  s.lo = static_cast<float>(bf_px_m / (z + c.depth_band_m));
  s.hi = z > c.depth_band_m ? static_cast<float>(bf_px_m / (z - c.depth_band_m)) : 1e9f;
  seed_of_[static_cast<std::size_t>(best)] = static_cast<int32_t>(seeds_.size());
  seeds_.push_back(s);
  label_[static_cast<std::size_t>(best)] = label;
  queue_.push_back(((best / w) << 16) | (best % w));  // the flood's queue holds (y << 16) | x
  return true;
}

void ObjectOutliner::flood(const cv::Mat& disparity_px) {
  // The queue holds (y << 16) | x (no division per pixel).
  const int w = disparity_px.cols, h = disparity_px.rows;
  const float* disparity = disparity_px.ptr<float>(0);
  const std::size_t row_stride = disparity_px.step1();
  for (std::size_t head = 0; head < queue_.size(); ++head) {
    const int px = queue_[head] & 0xffff, py = queue_[head] >> 16;
    const std::size_t p = static_cast<std::size_t>(py) * static_cast<std::size_t>(w) + static_cast<std::size_t>(px);
    const float* drow = disparity + static_cast<std::size_t>(py) * row_stride;
    const float dp = drow[px];
    const int32_t seed = seed_of_[p];
    const Seed& s = seeds_[static_cast<std::size_t>(seed)];
    const uint8_t lab = label_[p];
    const float step = static_cast<float>(config_.step_tolerance_px + config_.step_tolerance_rel * dp);
    auto visit = [&](int qx, int qy, std::size_t q, float dq) {
      if (label_[q] != 0) return;
      if (!(dq > 0) || std::abs(dq - dp) > step || dq < s.lo || dq > s.hi || is_floor(qx, qy, dq)) return;
      label_[q] = lab;
      seed_of_[q] = seed;
      queue_.push_back((qy << 16) | qx);
    };
    if (px > 0) visit(px - 1, py, p - 1, drow[px - 1]);
    if (px + 1 < w) visit(px + 1, py, p + 1, drow[px + 1]);
    if (py > 0)
      visit(px, py - 1, p - static_cast<std::size_t>(w),
            drow[static_cast<std::ptrdiff_t>(px) - static_cast<std::ptrdiff_t>(row_stride)]);
    if (py + 1 < h) visit(px, py + 1, p + static_cast<std::size_t>(w), drow[static_cast<std::size_t>(px) + row_stride]);
  }
}

void ObjectOutliner::fill_unmeasured(const cv::Mat& disparity_px, const cv::Mat& left_roi, cv::Point origin,
                                     double bf_px_m, cv::Mat& mask) {
  const int w = disparity_px.cols, h = disparity_px.rows;
  const float d_object = median_disparity(disparity_px, mask);
  if (!(d_object > 0)) return;
  // Texture as the matcher sees it: the horizontal derivative (grey levels per px) averaged over its 5x5 block.
  cv::Sobel(left_roi, gradient_, CV_32F, 1, 0, 3, 0.125);
  cv::blur(cv::abs(gradient_), texture_, cv::Size(5, 5));
  const double z = bf_px_m / d_object;
  const float lo = static_cast<float>(bf_px_m / (z + config_.depth_band_m));
  const float hi = z > config_.depth_band_m ? static_cast<float>(bf_px_m / (z - config_.depth_band_m)) : 1e9f;
  // Per pixel: 1 unmeasured or at the object's depth (may join), 2 measured floor at its depth (where it stands), 0
  // measured elsewhere or object.
  // The band x < d at the image's left border has no match in the right image at all: left_band.h decides there.
  constexpr uint8_t kOther = 0, kJoinable = 1, kFloor = 2;
  passable_.create(disparity_px.size(), CV_8UC1);
  const float weak = static_cast<float>(config_.weak_texture_dn);
  const int band_end = std::min(w, std::max(0, static_cast<int>(std::ceil(d_object)) - origin.x));
  for (int y = 0; y < h; ++y) {
    const float* d = disparity_px.ptr<float>(y);
    const float* t = texture_.ptr<float>(y);
    const uint8_t* m = mask.ptr<uint8_t>(y);
    uint8_t* p = passable_.ptr<uint8_t>(y);
    for (int x = 0; x < w; ++x) {
      if (m[x] || x < band_end) {
        p[x] = kOther;
      } else if (t[x] < weak || !(d[x] > 0)) {
        p[x] = kJoinable;
      } else if (d[x] < lo || d[x] > hi) {
        p[x] = kOther;  // another depth: the floor behind a person's legs, a rack beside them
      } else {
        p[x] = is_floor(x, y, d[x]) ? kFloor : kJoinable;
      }
    }
  }
  added_.create(disparity_px.size(), CV_8UC1);
  added_.setTo(0);
  if (ground_ != nullptr && ground_->b > 0) {
    // Down each column from the outline's lowest pixel to the floor: a measured floor pixel, or the row where the
    // floor has the object's disparity (where it stands).
    for (int x = 0; x < w; ++x) {
      int y0 = h - 1;
      while (y0 >= 0 && !mask.at<uint8_t>(y0, x)) --y0;
      if (y0 < 0) continue;
      const double floor_row = (d_object - ground_x_[static_cast<std::size_t>(x)] - ground_->c) / ground_->b;
      const int contact = static_cast<int>(std::floor(floor_row)) - origin.y;
      int y = y0 + 1;
      bool reached = false;
      for (; y < h; ++y) {
        const uint8_t p = passable_.at<uint8_t>(y, x);
        if (y >= contact || p == kFloor) {
          reached = true;
          break;
        }
        if (p != kJoinable) break;
      }
      if (!reached) continue;
      for (int yy = y0 + 1; yy < y; ++yy) added_.at<uint8_t>(yy, x) = 255;
    }
  }
  // Along each row, the runs between two pixels of the outline.
  for (int y = 0; y < h; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    const uint8_t* p = passable_.ptr<uint8_t>(y);
    uint8_t* a = added_.ptr<uint8_t>(y);
    int last = -1;     // the last outline pixel of the row so far
    bool open = true;  // every pixel since it may join
    for (int x = 0; x < w; ++x) {
      if (m[x] || a[x]) {
        if (last >= 0 && open) {
          for (int k = last + 1; k < x; ++k) a[k] = 255;
        }
        last = x;
        open = true;
      } else if (p[x] != kJoinable) {
        open = false;
      }
    }
  }
  cv::bitwise_or(mask, added_, mask);
}

void ObjectOutliner::fill_enclosed(const cv::Mat& disparity_px, cv::Mat& mask) {
  // Only the mask's bounding box and a 1 px ring around it can hold an enclosed part (everything beyond is one
  // component with the ring), so the components are labelled there; the ring's side is the ROI border where the box
  // reaches it.
  const int w = disparity_px.cols, h = disparity_px.rows;
  const cv::Rect box = cv::boundingRect(mask);
  const cv::Rect area = cv::Rect(box.x - 1, box.y - 1, box.width + 2, box.height + 2) & cv::Rect(0, 0, w, h);
  cv::bitwise_not(mask(area), holes_);
  const int count =
      area.empty() ? 0
                   : cv::connectedComponentsWithStats(holes_, hole_labels_, hole_stats_, hole_centroids_, 4, CV_32S);
  if (count <= 1) return;
  const int aw = area.width, ah = area.height;
  invalid_count_.assign(static_cast<std::size_t>(count), 0);
  for (int y = 0; y < ah; ++y) {
    const int* l = hole_labels_.ptr<int>(y);
    const float* d = disparity_px.ptr<float>(y + area.y) + area.x;
    for (int x = 0; x < aw; ++x) {
      if (l[x] > 0 && !(d[x] > 0)) ++invalid_count_[static_cast<std::size_t>(l[x])];
    }
  }
  fill_.assign(static_cast<std::size_t>(count), 0);
  bool any = false;
  for (int k = 1; k < count; ++k) {
    const int x0 = hole_stats_.at<int>(k, cv::CC_STAT_LEFT), y0 = hole_stats_.at<int>(k, cv::CC_STAT_TOP);
    const int x1 = x0 + hole_stats_.at<int>(k, cv::CC_STAT_WIDTH), y1 = y0 + hole_stats_.at<int>(k, cv::CC_STAT_HEIGHT);
    if (x0 == 0 || y0 == 0 || x1 == aw || y1 == ah) continue;  // reaches the ring or the ROI border: outside
    const int hole_area = hole_stats_.at<int>(k, cv::CC_STAT_AREA);
    const bool mostly_invalid =
        invalid_count_[static_cast<std::size_t>(k)] >= config_.max_hole_invalid_fraction * hole_area;
    if (mostly_invalid || hole_area < config_.min_hole_fill_px) {
      fill_[static_cast<std::size_t>(k)] = 1;
      any = true;
    }
  }
  if (!any) return;
  for (int y = 0; y < ah; ++y) {
    const int* l = hole_labels_.ptr<int>(y);
    uint8_t* m = mask.ptr<uint8_t>(y + area.y) + area.x;
    for (int x = 0; x < aw; ++x) {
      if (l[x] > 0 && fill_[static_cast<std::size_t>(l[x])]) m[x] = 255;
    }
  }
}

float ObjectOutliner::median_disparity(const cv::Mat& disparity_px, const cv::Mat& mask) {
  // SGBM's disparities are multiples of 1/16 px: counted in 1/16 px bins, the median is exact without sorting
  // (values off that grid: a selection over a second pass).
  const int w = disparity_px.cols, h = disparity_px.rows;
  constexpr int kBins = 16 * 1024;
  disparity_bins_.assign(kBins, 0);
  bool on_grid = true;
  std::size_t valid = 0;
  for (int y = 0; y < h && on_grid; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    const float* d = disparity_px.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      if (!m[x] || !(d[x] > 0)) continue;
      const float scaled = d[x] * 16.0f;
      const int bin = static_cast<int>(scaled);
      on_grid = on_grid && bin < kBins && static_cast<float>(bin) == scaled;
      if (on_grid) ++disparity_bins_[static_cast<std::size_t>(bin)];
      ++valid;
    }
  }
  if (on_grid && valid > 0) {
    const std::size_t rank = valid / 2;  // the element a selection would put at the middle
    std::size_t below = 0;
    for (int b = 0; b < kBins; ++b) {
      below += static_cast<std::size_t>(disparity_bins_[static_cast<std::size_t>(b)]);
      if (below > rank) return static_cast<float>(b) / 16.0f;
    }
  }
  if (on_grid) return 0.0f;
  disparities_.clear();
  for (int y = 0; y < h; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    const float* d = disparity_px.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      if (m[x] && d[x] > 0) disparities_.push_back(d[x]);
    }
  }
  return median_in_place(disparities_, 0.0f);
}

OutlineStats ObjectOutliner::outline(const cv::Mat& disparity_px, cv::Point origin,
                                     const std::vector<cv::Point2f>& points_px,
                                     const std::vector<float>& point_disparity_px,
                                     const std::vector<cv::Point2f>& static_px,
                                     const std::vector<float>& static_disparity_px, const DisparityPlane* ground,
                                     double bf_px_m, cv::Mat& mask, const cv::Mat& left_roi) {
  CV_Assert(disparity_px.type() == CV_32FC1);
  CV_Assert(points_px.size() == point_disparity_px.size() && static_px.size() == static_disparity_px.size());
  OutlineStats stats;
  const int w = disparity_px.cols, h = disparity_px.rows;
  mask.create(disparity_px.size(), CV_8UC1);
  mask.setTo(0);
  if (w == 0 || h == 0 || !(bf_px_m > 0)) return stats;
  CV_Assert(w < (1 << 16) && h < (1 << 15));  // the flood's queue packs (y << 16) | x
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  label_.assign(n, 0);
  seeds_.clear();
  seed_of_.assign(n, -1);
  queue_.clear();
  prepare_floor(ground, origin, w, h);
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    stats.object_seeds += add_seed(disparity_px, origin, bf_px_m, points_px[i], point_disparity_px[i], 1) ? 1 : 0;
  }
  if (stats.object_seeds == 0) return stats;
  if (config_.static_competition) {
    for (std::size_t i = 0; i < static_px.size(); ++i) {
      stats.static_seeds += add_seed(disparity_px, origin, bf_px_m, static_px[i], static_disparity_px[i], 2) ? 1 : 0;
    }
  }
  flood(disparity_px);
  for (int y = 0; y < h; ++y) {
    uint8_t* m = mask.ptr<uint8_t>(y);
    const uint8_t* l = label_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(w);
    for (int x = 0; x < w; ++x) m[x] = l[x] == 1 ? 255 : 0;
  }
  if (config_.weak_texture_dn > 0 && !left_roi.empty()) {
    CV_Assert(left_roi.type() == CV_8UC1 && left_roi.size() == disparity_px.size());
    fill_unmeasured(disparity_px, left_roi, origin, bf_px_m, mask);
  }
  fill_enclosed(disparity_px, mask);
  if (config_.erode_px > 0) {
    const int k = 2 * config_.erode_px + 1;
    cv::erode(mask, eroded_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)), cv::Point(-1, -1), 1,
              cv::BORDER_CONSTANT, cv::Scalar(255));
    std::swap(mask, eroded_);
  }
  stats.object_pixels = cv::countNonZero(mask);
  stats.median_disparity_px = median_disparity(disparity_px, mask);
  return stats;
}

}  // namespace agvslam::dynamic
