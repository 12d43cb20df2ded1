#include "agvslam/dynamic/frame_regions.h"

#include <algorithm>
#include <cmath>

#include "agvslam/dynamic/region_search.h"

namespace agvslam::dynamic {

void FrameRegions::clear() {
  instance_object_.assign(1, -1);
  instance_near_moving_.assign(1, 0);
  kept_.clear();
  next_instance_ = 1;
}

int FrameRegions::new_instance(int object_id) {
  const int instance = next_instance_++;
  instance_object_.resize(static_cast<std::size_t>(std::min(next_instance_, 256)), -1);
  if (instance < 256) instance_object_[static_cast<std::size_t>(instance)] = object_id;
  return instance;
}

bool FrameRegions::holds_object(int object_id) const {
  return std::find(instance_object_.begin(), instance_object_.end(), object_id) != instance_object_.end();
}

void FrameRegions::mark_near_moving(int first, int end, bool near_moving) {
  const std::size_t size = static_cast<std::size_t>(std::clamp(end, 1, 256));
  if (instance_near_moving_.size() < size) instance_near_moving_.resize(size, 0);
  for (int k = first; k < end && k < 256; ++k)
    instance_near_moving_[static_cast<std::size_t>(k)] |= near_moving ? 1 : 0;
}

bool FrameRegions::merge_stacked(RoiSegmentation& seg, const cv::Rect& rect, bool near_moving,
                                 const StackingRule& stacking, DynamicMask& mask) {
  const double median_d = seg.outline_stats.median_disparity_px;
  const RoiGroupingConfig& gc = stacking.grouping;
  for (Kept& k : kept_) {
    const double d = std::max(k.median_disparity_px, median_d);
    if (std::abs(k.median_disparity_px - median_d) > gc.t_disp_px + gc.t_disp_rel * d) continue;
    const double px_per_m = std::min(k.median_disparity_px, median_d) / stacking.baseline_m;
    // Columns overlap by half the narrower, or by a quarter when one lies wholly above the other (a near
    // person's torso and striding legs, split where the thighs have no texture) ...
    const int overlap = std::min(rect.br().x, k.rect.br().x) - std::max(rect.x, k.rect.x);
    const int gap = std::max(rect.y, k.rect.y) - std::min(rect.br().y, k.rect.br().y);
    const int narrower = std::min(rect.width, k.rect.width);
    if (2 * overlap < narrower && !(gap >= 0 && 4 * overlap >= narrower)) continue;
    // ... the vertical gap is within T_s or 0.8 m, and together they are no taller than an object can be.
    if (gap > std::max(gc.a_s_px + gc.b_s * d, 0.8 * px_per_m)) continue;
    if ((k.rect | rect).height > stacking.max_height_m * px_per_m) continue;
    mask.instances(rect).setTo(static_cast<uint8_t>(std::min(k.instance, 255)),
                               seg.outline(cv::Rect(rect.tl() - seg.roi.tl(), rect.size())));
    k.rect |= rect;
    mask.regions[k.region_index] = k.rect;
    mark_near_moving(k.instance, k.instance + 1, near_moving);
    if (k.instance < static_cast<int>(instance_object_.size())) {
      seg.object_id = instance_object_[static_cast<std::size_t>(k.instance)];
    }
    return true;
  }
  return false;
}

void FrameRegions::keep_outline(RoiSegmentation& seg, const cv::Rect& rect, bool near_moving,
                                const StackingRule& stacking, bool split_side_by_side, DynamicMask& mask) {
  if (stacking.enabled && seg.outline_stats.median_disparity_px > 0 &&
      merge_stacked(seg, rect, near_moving, stacking, mask)) {
    return;
  }
  kept_.push_back({rect, seg.outline_stats.median_disparity_px, next_instance_, mask.regions.size()});
  mask.regions.push_back(rect);
  const int first_instance = next_instance_;
  next_instance_ = label_region_objects(seg.outline(cv::Rect(rect.tl() - seg.roi.tl(), rect.size())),
                                        split_side_by_side, next_instance_, mask.instances(rect));
  instance_object_.resize(static_cast<std::size_t>(std::min(next_instance_, 256)), -1);
  for (int k = first_instance; k < next_instance_ && k < 256; ++k) {
    instance_object_[static_cast<std::size_t>(k)] = seg.object_id;
  }
  mark_near_moving(first_instance, next_instance_, near_moving);
}

void FrameRegions::add_unowned_region(const cv::Mat& region_pixels, const cv::Rect& rect, bool split_side_by_side,
                                      DynamicMask& mask) {
  mask.regions.push_back(rect);
  next_instance_ = label_region_objects(region_pixels, split_side_by_side, next_instance_, mask.instances(rect));
}

void FrameRegions::add_band_rect(const cv::Rect& painted, int instance, bool new_region, DynamicMask& mask) {
  // The region that holds the instance: regions number their instances in the order they were kept, so the last
  // one starting at or below it.
  auto holder = std::find_if(kept_.rbegin(), kept_.rend(), [&](const Kept& k) { return k.instance <= instance; });
  if (new_region || holder == kept_.rend()) {
    mask.regions.push_back(painted);
  } else {
    holder->rect |= painted;
    mask.regions[holder->region_index] = holder->rect;
  }
}

}  // namespace agvslam::dynamic
