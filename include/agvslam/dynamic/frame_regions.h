#pragma once
// The regions of the mask being built for one frame: which object each instance id belongs to, which instances are
// near outlines far off the ego-motion (reported without confirmation), and the rectangles of the regions kept so
// far (for stacked regions and the left band's pixels). Filled by the ROI outlines, then the left band; read by the
// object tracker and the confirmation.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/roi_grouping.h"

namespace agvslam::dynamic {

// detector.merge_stacked_regions: regions of one frame stacked in one column range at agreeing depth are one object.
struct StackingRule {
  bool enabled = true;
  RoiGroupingConfig grouping;  // t_disp_px / t_disp_rel (agreeing depth), a_s_px / b_s (the vertical gap T_s)
  double max_height_m = 3.0;   // together no taller than this
  double baseline_m = 0.12;
};

class FrameRegions {
 public:
  struct Kept {
    cv::Rect rect;
    double median_disparity_px;
    int instance;              // its first instance id
    std::size_t region_index;  // in DynamicMask::regions
  };

  // Starts a frame: no instance, no region (instance ids start at 1).
  void clear();

  int next_instance() const { return next_instance_; }
  // A new instance id for `object_id` (-1: none); instance ids above 255 get no object.
  int new_instance(int object_id);
  // Per instance id (0: none): its object id, -1 when it has none.
  const std::vector<int>& instance_object() const { return instance_object_; }
  // Per instance id: a near outline far off the ego-motion (confirm.near_*).
  const std::vector<uint8_t>& instance_near_moving() const { return instance_near_moving_; }
  // Whether a region of this frame belongs to `object_id`.
  bool holds_object(int object_id) const;

  // A kept outline (RoiSegmentation::outline, CV_8UC1 in ROI coordinates) becomes part of `mask` within `rect` (image
  // coordinates): merged into a region it is stacked on (`stacking`; seg.object_id becomes that region's object), or a
  // new region whose side-by-side pieces are separate instances when split_side_by_side.
  void keep_outline(RoiSegmentation& seg, const cv::Rect& rect, bool near_moving, const StackingRule& stacking,
                    bool split_side_by_side, DynamicMask& mask);
  // A region of the superpixel / rectangle modes: its pixels in `region_pixels` (CV_8UC1, the rectangle's size)
  // become new instances of no object.
  void add_unowned_region(const cv::Mat& region_pixels, const cv::Rect& rect, bool split_side_by_side,
                          DynamicMask& mask);
  // Pixels `painted` into the left band for `instance`: a region of their own (new_region), or a part of the region
  // that holds the instance.
  void add_band_rect(const cv::Rect& painted, int instance, bool new_region, DynamicMask& mask);

 private:
  // Merges into a kept region the new one is stacked on; false when there is none.
  bool merge_stacked(RoiSegmentation& seg, const cv::Rect& rect, bool near_moving, const StackingRule& stacking,
                     DynamicMask& mask);
  void mark_near_moving(int first, int end, bool near_moving);

  std::vector<int> instance_object_{-1};
  std::vector<uint8_t> instance_near_moving_{0};
  std::vector<Kept> kept_;
  int next_instance_ = 1;
};

}  // namespace agvslam::dynamic
