#pragma once
// Static carving (beyond the paper): an outline kept as dynamic that holds clearly static tracks away from the
// object's dynamic points flooded the surface those tracks lie on (a rack face at the person's depth); it loses the
// pixels nearer to such a track than to any of its dynamic points (a Voronoi split).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/dynamic/detection_result.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `static_carve`.
struct StaticCarveOptions {
  // The carving needs at least min_tracks clearly static tracks inside the outline (0 = off): tested by the depth
  // test at an offset <= max_offset_px and by the multi-frame test at <= max_multiframe_px, each at least
  // min_distance_px from every dynamic point of the object's group.
  int min_tracks = 2;
  double max_offset_px = 0.3;
  double max_multiframe_px = 1.0;
  double min_distance_px = 12;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Removes from `outline` (CV_8UC1, its top-left pixel at `outline_origin` in the image) every pixel nearer (image
// distance) to one of `static_px` than to all of `object_px` (image coordinates), a Voronoi split between the object's
// dynamic points and the static tracks of a flooded surface (decided per 4x4 block by distance transforms, and exactly
// per pixel in the blocks a cell boundary passes). Returns the pixels kept (all of them when either set is empty).
int carve_static_cells(cv::Mat& outline, cv::Point outline_origin, const std::vector<cv::Point2f>& object_px,
                       const std::vector<cv::Point2f>& static_px);

// The clearly static tracks among `points` inside `outline` (its top-left at `outline_origin`) away from `object_px`,
// into `static_px`; when they are at least options.min_tracks, the outline loses their cells (carve_static_cells).
// Returns the outline's pixels, or -1 when it was left as it was.
int carve_static_tracks(const StaticCarveOptions& options, const std::vector<TrackedPoint>& points,
                        const std::vector<cv::Point2f>& object_px, cv::Point outline_origin, cv::Mat& outline,
                        std::vector<cv::Point2f>& static_px);

}  // namespace agvslam::dynamic
