#include "agvslam/dynamic/object_confirmer.h"

#include <algorithm>
#include <opencv2/core.hpp>

namespace agvslam::dynamic {

bool ConfirmOptions::near_moving(double roi_disparity_px, double median_offset_px, int box_area_px,
                                 int roi_area_px) const {
  return near_min_px > 0 && roi_disparity_px >= near_min_disparity_px && median_offset_px >= near_min_offset_px &&
         static_cast<double>(box_area_px) >= near_min_roi_fill * roi_area_px;
}

bool lies_half_inside_another(const std::vector<cv::Rect>& boxes, std::size_t k) {
  const cv::Rect& b = boxes.at(k);
  for (std::size_t j = 0; j < boxes.size(); ++j) {
    if (j != k && !boxes[j].empty() && 2 * (b & boxes[j]).area() >= b.area()) return true;
  }
  return false;
}

ObjectConfirmer::ObjectConfirmer(const ConfirmOptions& options) : options_(options) {}

int ObjectConfirmer::measure_objects(const cv::Mat& instances, const cv::Rect& area) {
  object_pixels_.assign(256, 0);
  box_limits_.assign(4 * 256, 0);  // per instance: x0, y0, x1, y1 (inclusive)
  int max_instance = 0;
  for (int y = area.y; y < area.br().y; ++y) {
    const uint8_t* row = instances.ptr<uint8_t>(y);
    for (int x = area.x; x < area.br().x; ++x) {
      const int k = row[x];
      if (k == 0) continue;
      int* b = &box_limits_[4 * static_cast<std::size_t>(k)];
      if (object_pixels_[static_cast<std::size_t>(k)]++ == 0) {
        b[0] = b[2] = x;
        b[1] = b[3] = y;
        max_instance = std::max(max_instance, k);
      } else {
        b[0] = std::min(b[0], x);
        b[2] = std::max(b[2], x);
        b[3] = y;  // rows are scanned in order
      }
    }
  }
  object_boxes_.assign(static_cast<std::size_t>(max_instance) + 1, cv::Rect());
  for (int k = 1; k <= max_instance; ++k) {
    const int* b = &box_limits_[4 * static_cast<std::size_t>(k)];
    if (object_pixels_[static_cast<std::size_t>(k)] > 0) {
      object_boxes_[static_cast<std::size_t>(k)] = cv::Rect(b[0], b[1], b[2] - b[0] + 1, b[3] - b[1] + 1);
    }
  }
  return max_instance;
}

bool ObjectConfirmer::confirmed(int instance, const std::vector<uint8_t>& near_moving) const {
  const auto k = static_cast<std::size_t>(instance);
  const cv::Rect& b = object_boxes_[k];
  const int pixels = object_pixels_[k];
  if (options_.below_px > 0 && pixels >= options_.below_px) return true;
  // A near object whose tracks are far off the ego-motion is no flicker of noise: reported at once, unless its
  // box lies half inside another object's (a fragment beside the object it belongs to).
  if (pixels >= options_.near_min_px && k < near_moving.size() && near_moving[k] != 0 &&
      !lies_half_inside_another(object_boxes_, k)) {
    return true;
  }
  for (const cv::Rect& prev : prev_boxes_) {
    const double overlap = (b & prev).area();
    if (overlap > 0 && overlap >= options_.min_box_iou * (b.area() + prev.area() - overlap)) return true;
  }
  return false;
}

int ObjectConfirmer::confirm(DynamicMask& mask, int dilation_px, const std::vector<uint8_t>& near_moving) {
  cv::Mat& inst = mask.instances;
  // Object pixels lie in the regions' rectangles (grown by the mask dilation): only their union is scanned.
  cv::Rect area;
  for (const cv::Rect& r : mask.regions) area |= r;
  area = cv::Rect(area.x - dilation_px, area.y - dilation_px, area.width + 2 * dilation_px,
                  area.height + 2 * dilation_px) &
         cv::Rect(0, 0, inst.cols, inst.rows);
  const int max_instance = mask.regions.empty() ? 0 : measure_objects(inst, area);
  if (mask.regions.empty()) object_boxes_.assign(1, cv::Rect());
  int unconfirmed = 0;
  if (options_.min_box_iou > 0 && max_instance > 0) {
    drop_object_.assign(object_boxes_.size(), 0);
    for (int k = 1; k <= max_instance; ++k) {
      if (object_boxes_[static_cast<std::size_t>(k)].empty() || confirmed(k, near_moving)) continue;
      drop_object_[static_cast<std::size_t>(k)] = 1;
      ++unconfirmed;
    }
    if (unconfirmed > 0) {
      for (int y = area.y; y < area.br().y; ++y) {
        uint8_t* row = inst.ptr<uint8_t>(y);
        for (int x = area.x; x < area.br().x; ++x) {
          if (row[x] && drop_object_[row[x]]) row[x] = 0;
        }
      }
      cv::compare(inst, 0, mask.image, cv::CMP_GT);
      // The rectangles left without a reported pixel go too.
      auto& regions = mask.regions;
      regions.erase(std::remove_if(regions.begin(), regions.end(),
                                   [&](const cv::Rect& r) { return cv::countNonZero(inst(r)) == 0; }),
                    regions.end());
    }
  }
  prev_boxes_.clear();
  for (const cv::Rect& b : object_boxes_) {
    if (!b.empty()) prev_boxes_.push_back(b);
  }
  return unconfirmed;
}

}  // namespace agvslam::dynamic
