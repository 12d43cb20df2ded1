#include "agvslam/dynamic/left_band.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace agvslam::dynamic {

namespace {
// The instance (1..255) with the largest positive count in `counts` (per instance id; ties: the lowest), its count in
// best_count; 0 for none.
int most_counted(const std::vector<int>& counts, int& best_count) {
  int best = 0;
  best_count = 0;
  for (int k = 1; k < 256; ++k) {
    if (counts[static_cast<std::size_t>(k)] > best_count) {
      best = k;
      best_count = counts[static_cast<std::size_t>(k)];
    }
  }
  return best;
}
}  // namespace

LeftBand::LeftBand(const BandSegmenterConfig& band, const BandCarryOptions& carry, int min_region_pixels,
                   const StereoCalibration& calibration)
    : band_config_(band),
      carry_(carry),
      min_region_pixels_(min_region_pixels),
      calibration_(calibration),
      band_(band) {}

void LeftBand::add_driving_seeds(const StereoFrame& frame, const cv::Mat& prev_left, const cv::Mat& prev_right,
                                 PointTracks& tracks, DynamicPoints& dynamic, DetectorResult& result) {
  band_track_cur_.clear();
  for (const TrackedPoint& p : result.points) {
    if (p.tracked && p.cur_px.x < band_config_.strip_px) band_track_cur_.push_back(p.cur_px);
  }
  if (!band_.driving_seeds(frame.left, tracks.cur_pyramid(), tracks.prev_pyramid(), tracks.lk(), result.lk_levels,
                           calibration_.left, calibration_.bf(), result.depth.T_cur_prev, band_track_cur_,
                           driving_seeds_)) {
    return;
  }
  result.band_driving_seeds = static_cast<int>(driving_seeds_.size());
  for (const BandSeed& seed : driving_seeds_) {
    // A corner seen now but not by the tracks: its own disparities and the frame's tests, as a densified point.
    const float prev_d = tracks.match_disparity(prev_left, prev_right, seed.prev_px);
    const float cur_d = tracks.match_disparity(frame.left, frame.right, seed.cur_px);
    const TrackedPoint p = tracks.test_new_point(result, seed.prev_px, seed.cur_px, prev_d, cur_d, -1, false);
    if (!p.dynamic) continue;  // the others are not kept as tracks: the quadtree decides where tracks start
    ++result.band_driving_dynamic;
    tracks.append_new_point(p, result, dynamic);
  }
}

int LeftBand::carry_instance(int id, const ObjectTrack& ob, const cv::Rect& moved, int band_px,
                             const FrameRegions& regions, const cv::Mat& instances, int& carry_id) {
  carry_id = id;
  // The instance of the region continuing the object in this frame, if any.
  const std::vector<int>& instance_object = regions.instance_object();
  const auto continuing = std::find(instance_object.begin() + 1, instance_object.end(), id);
  if (continuing != instance_object.end()) return static_cast<int>(continuing - instance_object.begin());
  // ... or, when none does, the region whose pixels its carried mask overlaps most beside the band (the same
  // person continued by a region of another object, e.g. its torso where the legs were the object).
  const cv::Rect beside = moved & cv::Rect(band_px, 0, std::max(0, instances.cols - band_px), instances.rows);
  overlap_count_.assign(256, 0);
  int mask_beside = 0;
  for (int y = beside.y; y < beside.br().y; ++y) {
    const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
    const uint8_t* dst = instances.ptr<uint8_t>(y);
    for (int x = beside.x; x < beside.br().x; ++x) {
      if (!src[x]) continue;
      ++mask_beside;
      ++overlap_count_[dst[x]];
    }
  }
  int best_count = 0;
  const int best = most_counted(overlap_count_, best_count);
  if (best > 0 && 10 * best_count >= mask_beside && static_cast<std::size_t>(best) < instance_object.size() &&
      instance_object[static_cast<std::size_t>(best)] >= 0) {
    carry_id = instance_object[static_cast<std::size_t>(best)];
    return best;
  }
  return -1;
}

void LeftBand::carry(ObjectTracker& objects, FrameRegions& regions, DetectorResult& result) {
  carried_.clear();
  if (!objects.enabled() || carry_.max_frames <= 0 || objects.objects().empty()) return;
  cv::Mat& inst = result.mask.instances;
  for (const auto& [id, ob] : objects.objects()) {
    if (ob.carry_mask.empty() || ob.band_frames >= carry_.max_frames) continue;
    // Its tracks held into this frame (in the band without disparity: their image motion alone).
    cv::Point2d motion;
    int dynamic = 0;
    const int held = objects.median_track_motion(id, result, motion, &dynamic);
    if (held < carry_.min_tracks || dynamic < carry_.min_dynamic) continue;
    const cv::Point shift(cvRound(motion.x), cvRound(motion.y));
    // The band without stereo at the object's depth (and the 2 px beside it where SGBM seldom gives a match).
    const int band = std::min(inst.cols, static_cast<int>(std::ceil(ob.median_disparity_px)) + 2);
    const cv::Rect moved = ob.carry_rect + shift;
    const cv::Rect area = moved & cv::Rect(0, 0, band, inst.rows);
    if (area.empty()) continue;
    int carry_id = id;
    int instance = carry_instance(id, ob, moved, band, regions, inst, carry_id);
    int candidates = 0;
    for (int y = area.y; y < area.br().y; ++y) {
      const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
      const uint8_t* dst = inst.ptr<uint8_t>(y);
      for (int x = area.x; x < area.br().x; ++x) candidates += (src[x] && !dst[x]) ? 1 : 0;
    }
    const bool band_only = instance < 0;
    if (candidates == 0 || (band_only && (candidates < min_region_pixels_ || regions.next_instance() > 255))) continue;
    if (band_only) instance = regions.new_instance(id);
    int x0 = area.br().x, y0 = area.br().y, x1 = -1, y1 = -1;
    for (int y = area.y; y < area.br().y; ++y) {
      const uint8_t* src = ob.carry_mask.ptr<uint8_t>(y - moved.y) - moved.x;
      uint8_t* dst = inst.ptr<uint8_t>(y);
      for (int x = area.x; x < area.br().x; ++x) {
        if (!src[x] || dst[x]) continue;
        dst[x] = static_cast<uint8_t>(instance);
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
      }
    }
    const cv::Rect painted(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
    regions.add_band_rect(painted, instance, band_only, result.mask);
    carried_.push_back({carry_id, instance, band_only, painted, candidates});
  }
}

int LeftBand::joined_instance(const BandRegion& region, const cv::Mat& instances) {
  const cv::Rect image(0, 0, instances.cols, instances.rows);
  const int reach = band_config_.merge_distance_px;
  // The object of the mask it touches most (within merge_distance_px) ...
  const cv::Rect around = cv::Rect(region.rect.x - reach, region.rect.y - reach, region.rect.width + 2 * reach,
                                   region.rect.height + 2 * reach) &
                          image;
  cv::Mat reach_mask = cv::Mat::zeros(around.size(), CV_8UC1);
  region.mask.copyTo(reach_mask(region.rect - around.tl()));
  if (reach > 0) {
    cv::dilate(reach_mask, reach_mask,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 2 * reach + 1)));
  }
  overlap_count_.assign(256, 0);
  for (int y = 0; y < around.height; ++y) {
    const uint8_t* m = reach_mask.ptr<uint8_t>(y);
    const uint8_t* k = instances.ptr<uint8_t>(y + around.y) + around.x;
    for (int x = 0; x < around.width; ++x) {
      if (m[x] && k[x]) ++overlap_count_[k[x]];
    }
  }
  int best_count = 0;
  int instance = most_counted(overlap_count_, best_count);
  if (instance != 0 || band_config_.stack_gap_px <= 0) return instance;
  // ... or the one it is stacked on (above or below within stack_gap_px, over at least half of its columns).
  const int gap = band_config_.stack_gap_px;
  const cv::Rect window =
      cv::Rect(region.rect.x, region.rect.y - gap, region.rect.width, region.rect.height + 2 * gap) & image;
  overlap_count_.assign(256, 0);
  column_seen_.assign(256, -1);
  for (int x = window.x; x < window.br().x; ++x) {
    for (int y = window.y; y < window.br().y; ++y) {
      const int k = instances.at<uint8_t>(y, x);
      if (k == 0 || column_seen_[static_cast<std::size_t>(k)] == x) continue;
      column_seen_[static_cast<std::size_t>(k)] = x;
      ++overlap_count_[static_cast<std::size_t>(k)];
    }
  }
  for (int k = 1; k < 256; ++k) {
    const int columns = overlap_count_[static_cast<std::size_t>(k)];
    if (2 * columns >= region.rect.width && columns > best_count) {
      instance = k;
      best_count = columns;
    }
  }
  return instance;
}

cv::Rect LeftBand::paint_region(const BandRegion& region, int instance, bool alone, cv::Mat& instances) {
  // Joined to an object, the region adds in each row where the object has pixels only those left of them (its
  // outline ends where stereo does, at x ~ d; right of it the region would add background the object uncovers).
  int x0 = region.rect.br().x, y0 = region.rect.br().y, x1 = -1, y1 = -1;
  for (int y = 0; y < region.rect.height; ++y) {
    const uint8_t* m = region.mask.ptr<uint8_t>(y);
    uint8_t* k = instances.ptr<uint8_t>(y + region.rect.y);
    int limit = region.rect.br().x;
    if (!alone) {
      int first = 0;
      while (first < instances.cols && k[first] != instance) ++first;
      if (first < instances.cols) limit = std::min(limit, first);
    }
    for (int x = region.rect.x; x < limit; ++x) {
      if (!m[x - region.rect.x] || k[x]) continue;
      k[x] = static_cast<uint8_t>(instance);
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y + region.rect.y);
      y1 = std::max(y1, y + region.rect.y);
    }
  }
  return x1 < 0 ? cv::Rect() : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

void LeftBand::segment(const StereoFrame& frame, const cv::Mat& prev_left, PointTracks& tracks, FrameRegions& regions,
                       DetectorResult& result) {
  band_prev_.clear();
  band_cur_.clear();
  for (const TrackedPoint& p : result.points) {
    if (!p.tracked || p.cur_px.x >= band_config_.strip_px) continue;
    band_prev_.push_back(p.prev_px);
    band_cur_.push_back(p.cur_px);
  }
  band_.segment(frame.left, prev_left, tracks.cur_pyramid(), tracks.prev_pyramid(), tracks.lk(), result.lk_levels,
                calibration_.left, calibration_.bf(), result.depth.T_cur_prev, result.mask.instances, band_prev_,
                band_cur_, result.band);
  // Largest first: a person's torso and legs may be two regions (a smooth belt between them), the legs joining the
  // torso's object.
  band_order_.resize(result.band.regions.size());
  for (std::size_t i = 0; i < band_order_.size(); ++i) band_order_[i] = static_cast<int>(i);
  std::sort(band_order_.begin(), band_order_.end(), [&](int a, int b) {
    return result.band.regions[static_cast<std::size_t>(a)].pixels >
           result.band.regions[static_cast<std::size_t>(b)].pixels;
  });
  cv::Mat& inst = result.mask.instances;
  for (int index : band_order_) {
    const BandRegion& region = result.band.regions[static_cast<std::size_t>(index)];
    int instance = joined_instance(region, inst);
    const bool alone = instance == 0;
    if (alone) {
      // An object of its own: upright (a person stepping into view, not a shadow on the floor) and large enough.
      if (region.pixels < band_config_.min_pixels || region.rect.height < band_config_.min_height_px ||
          region.rect.height < region.rect.width || regions.next_instance() > 255) {
        continue;
      }
      instance = regions.new_instance(-1);
    }
    const cv::Rect painted = paint_region(region, instance, alone, inst);
    if (painted.empty()) continue;
    regions.add_band_rect(painted, instance, alone, result.mask);
    (alone ? result.band_objects : result.band_joined) += 1;
  }
}

}  // namespace agvslam::dynamic
