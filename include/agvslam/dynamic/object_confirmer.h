#pragma once
// Confirmation of the mask's objects (beyond the paper): an object (an instance of the mask) is reported only when
// its bounding box overlaps one found in the previous frame, reported or not: a moving object persists, a false
// region seldom does. Large (near) objects, and near ones whose tracks are far off the ego-motion, are reported at
// once.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/dynamic/detection_result.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `confirm`.
struct ConfirmOptions {
  double min_box_iou = 0.3;  // the least IoU with a box of the previous frame (0 = off: every object is reported)
  int below_px = 30000;      // objects of this many px or more are reported at once (0: every object waits)
  // ... and so are near objects whose tracks are far off the ego-motion: their ROI's points at a mean disparity of at
  // least near_min_disparity_px, their outline's tracks at a median depth-test offset of at least near_min_offset_px,
  // holding at least near_min_px (0 = off), their box filling at least near_min_roi_fill of the ROI (a partial
  // outline, such as a torso whose legs took the floor's disparity, is no object yet) and lying less than half inside
  // another object's box of the frame (a fragment of it).
  double near_min_disparity_px = 12;
  double near_min_offset_px = 3.0;
  int near_min_px = 1000;
  double near_min_roi_fill = 0.35;

  // Whether a kept outline is near and moving: its ROI's points at roi_disparity_px, its tracks' median offset, the
  // area of its box and of its ROI (px).
  bool near_moving(double roi_disparity_px, double median_offset_px, int box_area_px, int roi_area_px) const;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Whether boxes[k] lies at least half inside another non-empty box of `boxes` (a fragment beside the object it
// belongs to, such as an arm outlined apart from its person).
bool lies_half_inside_another(const std::vector<cv::Rect>& boxes, std::size_t k);

class ObjectConfirmer {
 public:
  explicit ObjectConfirmer(const ConfirmOptions& options = {});
  // Forgets the previous frame's boxes.
  void reset() { prev_boxes_.clear(); }

  // Removes from `mask` the objects not confirmed (and the rectangles left without a pixel); returns their number.
  // Every object's box is kept for the next frame. dilation_px: how far the mask was grown beyond its regions'
  // rectangles; near_moving: per instance id, a near outline far off the ego-motion.
  int confirm(DynamicMask& mask, int dilation_px, const std::vector<uint8_t>& near_moving);

 private:
  // Each instance's bounding box and pixel count within `area` (object_boxes_, object_pixels_); the largest id.
  int measure_objects(const cv::Mat& instances, const cv::Rect& area);
  bool confirmed(int instance, const std::vector<uint8_t>& near_moving) const;

  ConfirmOptions options_;
  std::vector<cv::Rect> prev_boxes_;  // the objects found (reported or not) in the previous frame
  // Scratch.
  std::vector<cv::Rect> object_boxes_;
  std::vector<int> object_pixels_;
  std::vector<int> box_limits_;
  std::vector<uint8_t> drop_object_;
};

}  // namespace agvslam::dynamic
