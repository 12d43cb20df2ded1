#pragma once
// The band x < d at the left image border, which the right camera does not see: no stereo match there, so no
// outline reaches into it. Three things make up for that (beyond the paper):
//  - while the AGV drives, candidate movers in the left strip (BandSegmenter::driving_seeds) that the epipolar or
//    depth test flags join the frame's dynamic points;
//  - an object leaving the view to the left moves pixels into the band that earlier frames outlined: its last mask is
//    carried with the median motion of its tracks (the left image alone) and its pixels in the band join it, or are
//    its region when no region of this frame continues it (band_carry.*);
//  - the band segmenter's regions (what moved there by the left image alone) join the object of the mask they touch
//    or are stacked on, or are objects of their own.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/band_segmenter.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/frame_regions.h"
#include "agvslam/dynamic/object_tracker.h"
#include "agvslam/dynamic/point_tracks.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `band_carry`.
struct BandCarryOptions {
  // An object is carried for at most max_frames frames in a row without a region of its own (0 = off) ...
  int max_frames = 6;
  // ... while it still moves: at least min_tracks of its tracks held into this frame, min_dynamic of them dynamic.
  int min_tracks = 3;
  int min_dynamic = 2;

  void validate(const std::string& source) const;
  std::string describe() const;
};

class LeftBand {
 public:
  // band: the band segmenter (section `band`); min_region_pixels: the least pixels of a carried region of its own
  // (outline.min_pixels).
  LeftBand(const BandSegmenterConfig& band, const BandCarryOptions& carry, int min_region_pixels,
           const StereoCalibration& calibration);
  // The band segmenter is enabled (band.enabled): driving seeds and segmented regions.
  bool enabled() const { return band_config_.enabled; }

  // While the AGV drives: the strip's candidate movers, tracked from the previous frame (prev_left / prev_right) and
  // tested like densified points; the dynamic ones join result.points, the tracks and `dynamic`
  // (result.band_driving_seeds / band_driving_dynamic).
  void add_driving_seeds(const StereoFrame& frame, const cv::Mat& prev_left, const cv::Mat& prev_right,
                         PointTracks& tracks, DynamicPoints& dynamic, DetectorResult& result);
  // Objects of the last frame near the left border: their pixels carried into the band, painted into
  // result.mask.instances (carried()).
  void carry(ObjectTracker& objects, FrameRegions& regions, DetectorResult& result);
  const std::vector<CarriedObject>& carried() const { return carried_; }
  // The band segmenter on this frame (result.band), its regions joined to the mask (result.band_joined /
  // band_objects).
  void segment(const StereoFrame& frame, const cv::Mat& prev_left, PointTracks& tracks, FrameRegions& regions,
               DetectorResult& result);

 private:
  // The instance the carried mask of object `id` (moved to `moved`, band columns < band_px) joins: the region
  // continuing the object, or the one its pixels beside the band overlap most (carry_id: that region's object);
  // -1 for none.
  int carry_instance(int id, const ObjectTrack& ob, const cv::Rect& moved, int band_px, const FrameRegions& regions,
                     const cv::Mat& instances, int& carry_id);
  // The instance of the mask a band region joins: the one it touches most within band.merge_distance_px, else the
  // one it is stacked on (band.stack_gap_px); 0 for none.
  int joined_instance(const BandRegion& region, const cv::Mat& instances);
  // Paints the region's pixels into `instances` as `instance` (joined to an object: only left of the object's pixels
  // in each row); the rectangle painted (empty: none).
  static cv::Rect paint_region(const BandRegion& region, int instance, bool alone, cv::Mat& instances);

  BandSegmenterConfig band_config_;
  BandCarryOptions carry_;
  int min_region_pixels_;
  StereoCalibration calibration_;
  BandSegmenter band_;

  std::vector<CarriedObject> carried_;
  // Scratch.
  std::vector<BandSeed> driving_seeds_;
  std::vector<cv::Point2f> band_track_cur_;
  std::vector<cv::Point2f> band_prev_, band_cur_;  // this frame's tracks in the band strip
  std::vector<int> overlap_count_;                 // per instance: pixels (or columns) near a carried mask or region
  std::vector<int> band_order_, column_seen_;
};

}  // namespace agvslam::dynamic
