#include "agvslam/dynamic/detection_result.h"

#include <cstdio>

namespace agvslam::dynamic {

std::string StageTimings::describe() const {
  char buf[440];
  std::snprintf(buf, sizeof(buf),
                "total %.2f ms: pyramid %.2f, tracking %.2f, point disparity %.2f, epipolar %.2f, depth test %.2f, "
                "multi-frame %.2f, densify %.2f, grouping %.2f, ROI disparity %.2f, SLIC %.2f, planes %.2f, boundaries "
                "%.2f, regions %.2f, "
                "motion carve %.2f, band %.2f, features %.2f",
                total_ms, pyramid_ms, tracking_ms, point_disparity_ms, epipolar_ms, depth_test_ms, multiframe_ms,
                densify_ms, grouping_ms, roi_disparity_ms, slic_ms, planes_ms, boundaries_ms, regions_ms,
                motion_carve_ms, band_ms, features_ms);
  return buf;
}

std::string to_string(OutlineVerdict verdict) {
  switch (verdict) {
    case OutlineVerdict::kKept:
      return "kept";
    case OutlineVerdict::kNoSeed:
      return "no seed";
    case OutlineVerdict::kTooSmall:
      return "too small";
    case OutlineVerdict::kMostlyStaticTracks:
      return "mostly static tracks";
    case OutlineVerdict::kTooTall:
      return "too tall";
    case OutlineVerdict::kMovesWithBackground:
      return "moves with the background";
  }
  return "unknown";
}

int DetectorResult::dynamic_point_count() const {
  int n = 0;
  for (const TrackedPoint& p : points) n += p.dynamic;
  return n;
}

}  // namespace agvslam::dynamic
