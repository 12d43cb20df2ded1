#include "agvslam/dynamic/object_tracker.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::dynamic {

namespace {
double median_of(std::vector<float>& v) { return median_in_place(v, -1.0f); }

template <class Entries>
auto find_object(Entries& entries, int id) {
  const auto it =
      std::lower_bound(entries.begin(), entries.end(), id, [](const auto& e, int key) { return e.first < key; });
  return it != entries.end() && it->first == id ? it : entries.end();
}
}  // namespace

int cut_to_moved_pixels(cv::Mat& outline, cv::Point outline_origin, const cv::Mat& last_pixels, cv::Point last_origin,
                        cv::Point shift_px, cv::Size grow_px) {
  CV_Assert(outline.type() == CV_8UC1 && last_pixels.type() == CV_8UC1);
  cv::Mat allowed = cv::Mat::zeros(outline.size(), CV_8UC1);
  // The last pixels' rectangle, moved, in the outline's coordinates.
  const cv::Rect moved = cv::Rect(last_origin + shift_px - outline_origin, last_pixels.size()) &
                         cv::Rect(0, 0, outline.cols, outline.rows);
  if (!moved.empty()) {
    last_pixels(cv::Rect(moved.tl() + outline_origin - shift_px - last_origin, moved.size())).copyTo(allowed(moved));
  }
  cv::Mat grown;
  cv::dilate(allowed, grown,
             cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * grow_px.width + 1, 2 * grow_px.height + 1)));
  cv::bitwise_and(outline, grown, outline);
  return cv::countNonZero(outline);
}

ObjectTracker::ObjectTracker(const ObjectTrackerOptions& options, bool disparity_outlines)
    : options_(options), disparity_outlines_(disparity_outlines) {}

void ObjectTracker::reset() {
  track_object_.clear();
  objects_.clear();
  prev_instances_.release();
}

const ObjectTrack* ObjectTracker::find(int id) const {
  const auto it = find_object(objects_, id);
  return it == objects_.end() ? nullptr : &it->second;
}

int ObjectTracker::median_track_motion(int object_id, const DetectorResult& result, cv::Point2d& motion, int* dynamic) {
  motion_dx_.clear();
  motion_dy_.clear();
  int moving = 0;
  const std::size_t n = std::min(track_object_.size(), result.points.size());
  for (std::size_t i = 0; i < n; ++i) {
    const TrackedPoint& p = result.points[i];
    if (track_object_[i] != object_id || !p.tracked) continue;
    motion_dx_.push_back(p.cur_px.x - p.prev_px.x);
    motion_dy_.push_back(p.cur_px.y - p.prev_px.y);
    moving += p.dynamic ? 1 : 0;
  }
  if (dynamic != nullptr) *dynamic = moving;
  const int count = static_cast<int>(motion_dx_.size());
  if (count > 0) motion = cv::Point2d(median_of(motion_dx_), median_of(motion_dy_));
  return count;
}

int ObjectTracker::group_min_points(int grouping_min_points) const {
  return enabled() ? std::min(grouping_min_points, options_.continue_min_points) : grouping_min_points;
}

void ObjectTracker::assign_groups(const DynamicPoints& dynamic, int grouping_min_points,
                                  std::vector<DynamicGroup>& groups, std::vector<int>& group_object) const {
  const bool objects = enabled();
  const auto object_of = [&](int member) {
    const int idx = dynamic.index[static_cast<std::size_t>(member)];
    return static_cast<std::size_t>(idx) < track_object_.size() ? track_object_[static_cast<std::size_t>(idx)] : -1;
  };
  group_object.clear();
  std::vector<DynamicGroup> kept;
  for (DynamicGroup& g : groups) {
    int object = -1, votes = 0;
    if (objects) {
      for (int m : g.members) {
        const int o = object_of(m);
        if (o < 0) continue;
        int count = 0;
        for (int m2 : g.members) count += object_of(m2) == o;
        if (count > votes) {
          votes = count;
          object = o;
        }
      }
    }
    const bool small = static_cast<int>(g.members.size()) < grouping_min_points;
    if (small && votes < options_.continue_min_points) continue;
    if (votes < options_.continue_min_points) object = -1;
    // Groups are largest first: a smaller group continuing an object that a larger one continues already is
    // a part of it (its flood reaches the same connected pixels), not a second object.
    if (object >= 0 && small && std::find(group_object.begin(), group_object.end(), object) != group_object.end())
      continue;
    group_object.push_back(object);
    kept.push_back(std::move(g));
  }
  groups = std::move(kept);
}

void ObjectTracker::add_coasting_groups(const DetectorResult& result, const FrameRegions& regions,
                                        const RoiGroupingConfig& gc, int max_rois, std::vector<DynamicGroup>& groups,
                                        std::vector<int>& group_object, DynamicPoints& dynamic) {
  const cv::Rect image(cv::Point(0, 0), result.mask.instances.size());
  const std::size_t n = std::min(track_object_.size(), result.points.size());
  for (const auto& [id, ob] : objects_) {
    if (static_cast<int>(groups.size()) >= max_rois) break;
    if (ob.detections < options_.coast_min_detections || ob.coasted >= options_.coast_max_frames) continue;
    if (regions.holds_object(id)) continue;
    // Its tracks: inside its outline in the last frame, tracked into this one, at its depth.
    const double tol = gc.t_disp_px + gc.t_disp_rel * ob.median_disparity_px;
    coast_tracks_.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const TrackedPoint& p = result.points[i];
      if (track_object_[i] != id || !p.tracked || !(p.cur_disparity_px > 0)) continue;
      if (std::abs(p.cur_disparity_px - ob.median_disparity_px) > tol) continue;
      coast_tracks_.push_back(static_cast<int>(i));
    }
    if (static_cast<int>(coast_tracks_.size()) < options_.coast_min_tracks) continue;
    // The last rectangle moved with the median motion of its tracks, and the tracks themselves.
    motion_dx_.clear();
    motion_dy_.clear();
    DynamicGroup g;
    float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
    double sum_d = 0;
    for (int i : coast_tracks_) {
      const TrackedPoint& p = result.points[static_cast<std::size_t>(i)];
      motion_dx_.push_back(p.cur_px.x - p.prev_px.x);
      motion_dy_.push_back(p.cur_px.y - p.prev_px.y);
      x0 = std::min(x0, p.cur_px.x);
      y0 = std::min(y0, p.cur_px.y);
      x1 = std::max(x1, p.cur_px.x);
      y1 = std::max(y1, p.cur_px.y);
      sum_d += p.cur_disparity_px;
      g.members.push_back(static_cast<int>(dynamic.size()));
      dynamic.add(p, i);
    }
    const cv::Point shift(cvRound(median_of(motion_dx_)), cvRound(median_of(motion_dy_)));
    g.mean_disparity_px = sum_d / static_cast<double>(coast_tracks_.size());
    g.bounds = cv::Rect(cv::Point(cvFloor(x0), cvFloor(y0)), cv::Point(cvCeil(x1) + 1, cvCeil(y1) + 1));
    const int margin = gc.margin_px + static_cast<int>(std::lround(gc.margin_disparity_factor * g.mean_disparity_px));
    const cv::Rect moved = (ob.rect + shift) | g.bounds;
    g.roi = cv::Rect(moved.x - margin, moved.y - margin, moved.width + 2 * margin, moved.height + 2 * margin) & image;
    if (g.roi.empty()) continue;
    groups.push_back(std::move(g));
    group_object.push_back(id);
  }
}

int ObjectTracker::coast_min_pixels(int object_id) const {
  const ObjectTrack* ob = find(object_id);
  return ob == nullptr ? 0 : static_cast<int>(options_.coast_min_area_ratio * ob->pixels);
}

void ObjectTracker::cut_growth(const DetectorResult& result, RoiSegmentation& seg) {
  if (!(options_.growth_max_ratio > 0) || seg.coasted || seg.object_id < 0 || seg.outline_stats.object_pixels == 0 ||
      prev_instances_.size() != result.mask.instances.size()) {
    return;
  }
  const ObjectTrack* last = find(seg.object_id);
  if (last == nullptr) return;
  const int width = result.mask.instances.cols;
  if (last->detections < 2 || last->coasted > 0 || last->band_frames > 0 || last->pixels <= 0 || last->rect.x <= 2 ||
      last->rect.br().x >= width - 2 || !(seg.outline_stats.object_pixels > options_.growth_max_ratio * last->pixels)) {
    return;
  }
  // An object beside or behind another one may come out from behind it: growth is no evidence there.
  for (const auto& [id, other] : objects_) {
    if (id != seg.object_id && (other.rect & last->rect).area() > 0) return;
  }
  cv::Point2d motion;
  if (median_track_motion(seg.object_id, result, motion) == 0) return;
  const cv::Point shift(static_cast<int>(std::lround(motion.x)), static_cast<int>(std::lround(motion.y)));
  const cv::Size grow(static_cast<int>(std::lround(options_.growth_margin * last->rect.width)) + 2,
                      static_cast<int>(std::lround(options_.growth_margin * last->rect.height)) + 2);
  // The object's last pixels: its instances of the previous frame.
  const cv::Rect last_rect = last->rect & cv::Rect(0, 0, prev_instances_.cols, prev_instances_.rows);
  if (last_rect.empty()) return;
  lut_.create(1, 256, CV_8UC1);
  lut_.setTo(0);
  for (std::size_t i = 1; i < prev_instance_object_.size(); ++i) {
    if (prev_instance_object_[i] == seg.object_id) lut_.at<uint8_t>(static_cast<int>(i)) = 255;
  }
  cv::LUT(prev_instances_(last_rect), lut_, last_pixels_);
  seg.outline_stats.object_pixels =
      cut_to_moved_pixels(seg.outline, seg.roi.tl(), last_pixels_, last_rect.tl(), shift, grow);
}

int ObjectTracker::claim_id(int continued_id, const FrameRegions& regions) {
  const int id = regions.holds_object(continued_id) ? -1 : continued_id;
  return id < 0 ? next_object_id_++ : id;
}

void ObjectTracker::collect_next_objects(const DetectorResult& result, const std::vector<CarriedObject>& carried) {
  next_objects_.clear();
  own_.clear();
  for (const RoiSegmentation& seg : result.rois) {
    if (seg.outline_verdict != OutlineVerdict::kKept || seg.object_id < 0) continue;
    auto it = std::find_if(next_objects_.begin(), next_objects_.end(),
                           [&](const auto& e) { return e.first == seg.object_id; });
    if (it == next_objects_.end()) {
      ObjectTrack ob;
      ob.rect = seg.region.rectangle;
      ob.median_disparity_px = seg.outline_stats.median_disparity_px;
      ob.pixels = seg.outline_stats.object_pixels;
      next_objects_.emplace_back(seg.object_id, ob);
      own_.push_back(seg.coasted ? 0 : 1);
    } else {
      it->second.rect |= seg.region.rectangle;
      it->second.pixels += seg.outline_stats.object_pixels;
      own_[static_cast<std::size_t>(it - next_objects_.begin())] |= seg.coasted ? 0 : 1;
    }
  }
  // Objects carried into the left band: their band pixels belong to them; one no region continues is kept alone.
  band_only_.assign(next_objects_.size(), 0);
  for (const CarriedObject& c : carried) {
    auto it = std::find_if(next_objects_.begin(), next_objects_.end(), [&](const auto& e) { return e.first == c.id; });
    if (it == next_objects_.end()) {
      const ObjectTrack* prev = find(c.id);
      if (prev == nullptr) continue;
      ObjectTrack ob;
      ob.rect = c.rect;
      ob.median_disparity_px = prev->median_disparity_px;
      ob.pixels = c.pixels;
      next_objects_.emplace_back(c.id, ob);
      own_.push_back(0);
      band_only_.push_back(1);
    } else {
      it->second.rect |= c.rect;
      it->second.pixels += c.pixels;
    }
  }
}

void ObjectTracker::update(const DetectorResult& result, const FrameRegions& regions,
                           const std::vector<CarriedObject>& carried, bool keep_carry_masks) {
  collect_next_objects(result, carried);
  const std::vector<int>& instance_object = regions.instance_object();
  for (std::size_t k = 0; k < next_objects_.size(); ++k) {
    ObjectTrack& ob = next_objects_[k].second;
    const ObjectTrack* prev = find(next_objects_[k].first);
    ob.detections = (prev != nullptr ? prev->detections : 0) + own_[k];
    ob.coasted = own_[k] ? 0 : (prev != nullptr ? prev->coasted : 0) + 1;
    ob.band_frames = band_only_[k] ? (prev != nullptr ? prev->band_frames : 0) + 1 : 0;
    // Near the left band (it may reach it by the next frame): its pixels are kept for carrying (with
    // detector.mask_dilation_px > 0 they are the dilated ones, so a carried band part grows by that much per frame,
    // within the band and for at most band_carry.max_frames frames alone).
    if (keep_carry_masks && ob.rect.x < 2 * ob.median_disparity_px + 16) {
      const cv::Rect r = ob.rect & cv::Rect(0, 0, result.mask.instances.cols, result.mask.instances.rows);
      ob.carry_rect = r;
      // Its instances' pixels, in one pass through an instance -> 255 / 0 table.
      lut_.create(1, 256, CV_8UC1);
      lut_.setTo(0);
      for (std::size_t i = 1; i < instance_object.size(); ++i) {
        if (instance_object[i] == next_objects_[k].first) lut_.at<uint8_t>(static_cast<int>(i)) = 255;
      }
      cv::LUT(result.mask.instances(r), lut_, ob.carry_mask);
    }
  }
  std::sort(next_objects_.begin(), next_objects_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::swap(objects_, next_objects_);
}

void ObjectTracker::remember_pixels(const DetectorResult& result, const FrameRegions& regions) {
  if (enabled() && options_.growth_max_ratio > 0 && !result.mask.regions.empty()) {
    result.mask.instances.copyTo(prev_instances_);
    prev_instance_object_ = regions.instance_object();
  } else {
    prev_instances_.release();
  }
}

void ObjectTracker::assign_tracks(const std::vector<cv::Point2f>& tracks, const DetectorResult& result,
                                  const FrameRegions& regions) {
  track_object_.assign(tracks.size(), -1);
  if (!options_.enabled || !result.has_previous || result.mask.regions.empty()) return;
  const cv::Mat& inst = result.mask.instances;
  const std::vector<int>& instance_object = regions.instance_object();
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const cv::Point q(cvRound(tracks[i].x), cvRound(tracks[i].y));
    if (q.x < 0 || q.y < 0 || q.x >= inst.cols || q.y >= inst.rows) continue;
    const int k = inst.at<uint8_t>(q);
    if (k > 0 && static_cast<std::size_t>(k) < instance_object.size())
      track_object_[i] = instance_object[static_cast<std::size_t>(k)];
  }
}

}  // namespace agvslam::dynamic
