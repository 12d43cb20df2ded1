#pragma once
// Objects over frames (beyond the paper, mask_mode disparity): the tracks inside a region's outline belong to its
// object in the next frame, so a group of dynamic points continues the object most of its points belong to (even
// when smaller than grouping.min_points). An object no region continues coasts on its own tracks (paper 002's mask
// propagation with the detector's own tracks), and an outline that suddenly grew far beyond its object's last
// pixels is cut back to them.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/frame_regions.h"
#include "agvslam/dynamic/point_tracks.h"
#include "agvslam/dynamic/roi_grouping.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `objects`.
struct ObjectTrackerOptions {
  bool enabled = true;
  // A group of dynamic points of which at least this many belong to one object of the previous frame is a ROI even
  // when smaller than grouping.min_points: a person who showed only a few moving corners this frame.
  int continue_min_points = 3;
  // Coasting: an object kept in at least coast_min_detections frames on its own evidence that has no region in this
  // frame is outlined again from at least coast_min_tracks of its tracks at its depth, in its last rectangle moved
  // with them, for at most coast_max_frames frames in a row (0 = off). Its outline must keep at least
  // coast_min_area_ratio of the object's last pixels (a smaller one is a fragment).
  int coast_max_frames = 4;
  int coast_min_detections = 2;
  int coast_min_tracks = 3;
  double coast_min_area_ratio = 0.5;
  // An object found on its own evidence in >= 2 frames (not coasted, not cut by the left/right border, its rectangle
  // overlapping no other object's) whose outline grew by more than growth_max_ratio in one frame flooded a surface
  // beside it: the outline is cut to the object's last pixels, moved with its tracks and grown by growth_margin of
  // its last width / height + 2 px (0 = off).
  double growth_max_ratio = 1.6;
  double growth_margin = 0.08;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// An object of the last frame that had a region (or was carried into the left band).
struct ObjectTrack {
  cv::Rect rect;  // its region in that frame
  double median_disparity_px = 0;
  int pixels = 0;       // its outline's pixels in that frame
  int detections = 0;   // frames kept on its own evidence
  int coasted = 0;      // frames in a row it has coasted since
  int band_frames = 0;  // frames in a row it was only carried in the left band (band_carry.*)
  cv::Rect carry_rect;  // its pixels in that frame, kept near the left band only (band_carry.*) ...
  cv::Mat carry_mask;   // ... CV_8UC1 of carry_rect's size, 255 = the object's
};

// An object whose pixels this frame's left band carried (LeftBand::carry).
struct CarriedObject {
  int id;
  int instance;    // the instance its band pixels were painted with
  bool band_only;  // no region of this frame continues it
  cv::Rect rect;   // the band pixels painted
  int pixels;
};

// objects.growth_max_ratio: cuts `outline` (CV_8UC1, its top-left pixel at `outline_origin` in the image) to the
// pixels of `last_pixels` (CV_8UC1, non-zero = the object's pixels in the previous frame, its top-left at
// `last_origin`) moved by `shift_px` and grown by `grow_px` on each side (a rectangle). Returns the pixels kept.
int cut_to_moved_pixels(cv::Mat& outline, cv::Point outline_origin, const cv::Mat& last_pixels, cv::Point last_origin,
                        cv::Point shift_px, cv::Size grow_px);

class ObjectTracker {
 public:
  // disparity_outlines: regions.mask_mode is disparity (the other modes have no objects over frames).
  ObjectTracker(const ObjectTrackerOptions& options, bool disparity_outlines);
  // Objects are followed: enabled, with disparity outlines.
  bool enabled() const { return options_.enabled && disparity_outlines_; }
  // Forgets every object (ids keep counting).
  void reset();

  // The objects of the last frame, by id ascending; null when `id` is none of them.
  const std::vector<std::pair<int, ObjectTrack>>& objects() const { return objects_; }
  const ObjectTrack* find(int id) const;
  // Per track (row of DetectorResult::points for the tracks followed from the last frame): its object there, -1 none.
  const std::vector<int>& track_object() const { return track_object_; }

  // The tracks of `object_id` followed into this frame: their number, their median image motion (px, set when there
  // is one) and, when `dynamic` is given, how many of them are dynamic.
  int median_track_motion(int object_id, const DetectorResult& result, cv::Point2d& motion, int* dynamic = nullptr);

  // The minimum points of a ROI when objects continue (continue_min_points may be fewer than grouping's).
  int group_min_points(int grouping_min_points) const;
  // Each group (largest first) takes the object most of its points belong to (group_object[g], -1: none); a group
  // smaller than grouping_min_points stays only when continue_min_points of its points continue one object that no
  // larger group continues.
  void assign_groups(const DynamicPoints& dynamic, int grouping_min_points, std::vector<DynamicGroup>& groups,
                     std::vector<int>& group_object) const;
  // Whether an object may coast this frame.
  bool may_coast() const { return enabled() && options_.coast_max_frames > 0 && !objects_.empty(); }
  // A group per object of the last frame that no region of this frame continues (regions) and that still has
  // coast_min_tracks tracks at its depth, appended to groups / group_object (its tracks appended to `dynamic`),
  // while groups stay within max_rois.
  void add_coasting_groups(const DetectorResult& result, const FrameRegions& regions, const RoiGroupingConfig& grouping,
                           int max_rois, std::vector<DynamicGroup>& groups, std::vector<int>& group_object,
                           DynamicPoints& dynamic);
  // The pixels a coasted outline of `object_id` needs (0 for an object that is none of the last frame's).
  int coast_min_pixels(int object_id) const;
  // objects.growth_max_ratio on a continued outline (seg.outline and outline_stats.object_pixels).
  void cut_growth(const DetectorResult& result, RoiSegmentation& seg);
  // The id of a kept outline's object: the continued one unless a region of this frame took it already, else a new id.
  int claim_id(int continued_id, const FrameRegions& regions);

  // After the mask: the objects with regions (or carried band pixels) in this frame become the objects; with
  // keep_carry_masks, those near the left band keep their pixels for carrying.
  void update(const DetectorResult& result, const FrameRegions& regions, const std::vector<CarriedObject>& carried,
              bool keep_carry_masks);
  // ... each object's pixels of this frame, for the next frame's growth check.
  void remember_pixels(const DetectorResult& result, const FrameRegions& regions);
  // ... and each track's object for the next frame: the region it lies in now (tracks: PointTracks::tracks() after
  // replenishing).
  void assign_tracks(const std::vector<cv::Point2f>& tracks, const DetectorResult& result, const FrameRegions& regions);

 private:
  // The objects' entries of this frame from the kept outlines and the carried band pixels (next_objects_, own_,
  // band_only_).
  void collect_next_objects(const DetectorResult& result, const std::vector<CarriedObject>& carried);

  ObjectTrackerOptions options_;
  bool disparity_outlines_;
  std::vector<std::pair<int, ObjectTrack>> objects_;  // by object id, ascending
  int next_object_id_ = 0;
  std::vector<int> track_object_;
  cv::Mat prev_instances_;                 // the last frame's instances (objects.growth_max_ratio) ...
  std::vector<int> prev_instance_object_;  // ... and their objects

  // Scratch.
  std::vector<std::pair<int, ObjectTrack>> next_objects_;
  std::vector<uint8_t> own_;        // per entry of next_objects_: kept on its own evidence this frame
  std::vector<uint8_t> band_only_;  // per entry of next_objects_: only carried in the band this frame
  std::vector<int> coast_tracks_;
  std::vector<float> motion_dx_, motion_dy_;
  cv::Mat lut_, last_pixels_;
};

}  // namespace agvslam::dynamic
