#pragma once
// A 3-D landmark seen by keyframes (ORB-SLAM2's MapPoint).
//
// Ownership and threads: the Map owns its map points (shared_ptr); keyframes and frames hold shared_ptrs to the
// points they observe; a point refers back to its keyframes by raw pointer (a keyframe leaves every point's
// observations before it is dropped, in KeyFrame::set_bad). Everything here is read and written with the Map's
// mutex held (Map::mutex()), except the `track` scratch, which only the tracking thread touches, and the `mapping`
// scratch, which only the local-mapping thread touches.
//
// Serialisation (map_io.h): every field that defines a point is plain data (id, position, descriptor, normal,
// distance range, observations as (keyframe id, keypoint index), reference keyframe id, counters).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "agvslam/slam/frame.h"

namespace agvslam::slam {

class Map;

struct Observation {
  KeyFrame* keyframe = nullptr;
  int index = -1;  // keypoint index in the keyframe
};

class MapPoint : public std::enable_shared_from_this<MapPoint> {
 public:
  MapPoint(uint64_t id, const Eigen::Vector3d& p_w, KeyFrame* reference_keyframe, uint64_t first_frame_id);
  // A point read from a map file (its first keyframe may have been culled).
  MapPoint(uint64_t id, const Eigen::Vector3d& p_w, uint64_t first_keyframe_id, uint64_t first_frame_id);

  const uint64_t id;
  const uint64_t first_keyframe_id;  // the keyframe that created it
  const uint64_t first_frame_id;

  Eigen::Vector3d p_w;                                 // position in the world frame (m)
  Eigen::Vector3d normal_w = Eigen::Vector3d::Zero();  // mean viewing direction (unit)
  Descriptor descriptor{};                             // the observations' most central descriptor
  float min_distance_m = 0, max_distance_m = 0;        // scale-invariance range
  KeyFrame* reference_keyframe = nullptr;
  int visible = 1;  // frames in whose frustum it was
  int found = 1;    // frames that matched it

  const std::vector<Observation>& observations() const { return observations_; }
  // Number of views: a stereo observation counts 2 (ORB-SLAM2's nObs).
  int observation_count() const { return n_obs_; }
  int index_in(const KeyFrame* kf) const;  // keypoint index in kf, -1 when not observed there
  bool is_in(const KeyFrame* kf) const { return index_in(kf) >= 0; }

  void add_observation(KeyFrame* kf, int index);
  // Removes kf's observation; the point is set bad when 2 or fewer views remain.
  void erase_observation(KeyFrame* kf, Map& map);

  bool bad() const { return bad_; }
  // Set by point retirement (point_retirement.h) before set_bad: the point lay on an object that moved, so the
  // keypoints that saw it must not take a point again (a keyframe still in the mapper's queue blocks its own).
  void mark_retired() { retired_ = true; }
  bool retired() const { return retired_; }
  // Marks the point bad, removes it from its keyframes and from the map.
  void set_bad(Map& map);
  // Moves this point's observations to `other` (where other is not already seen) and sets this one bad; frames
  // that still hold this point find `other` through replaced().
  void replace(const MapPointPtr& other, Map& map);
  const MapPointPtr& replaced() const { return replaced_; }

  void increase_visible(int n = 1) { visible += n; }
  void increase_found(int n = 1) { found += n; }
  double found_ratio() const { return static_cast<double>(found) / static_cast<double>(visible); }

  // The observation descriptor with the least median distance to the others.
  void compute_distinctive_descriptor();
  // Mean viewing direction and the distance range from the reference keyframe's observation.
  void update_normal_and_depth();
  int predict_scale_level(double distance_m, const FrameGeometry& geometry) const {
    return geometry.predict_scale_level(distance_m, max_distance_m);
  }
  float max_invariance_distance() const { return 1.2f * max_distance_m; }
  float min_invariance_distance() const { return 0.8f * min_distance_m; }

  // Tracking-thread scratch (ORB-SLAM2's mTrackProj*, mnTrackScaleLevel, ...).
  struct TrackScratch {
    bool in_view = false;
    float proj_x = 0, proj_y = 0, proj_x_right = 0;
    int scale_level = 0;
    float view_cos = 0;
    uint64_t reference_for_frame = UINT64_MAX;  // already in the local map of this frame
    uint64_t last_frame_seen = UINT64_MAX;      // already matched in this frame
  } track;

  // Tracking-thread record of the retirement evidence (point_retirement.h): one bit per conclusive frame, the
  // newest in bit 0; `frames` marks the frames with an outcome, the others the frames with that evidence.
  struct RetirementWindow {
    uint16_t frames = 0;
    uint16_t mask = 0;                 // in the dynamic mask with a surface at its depth
    uint16_t absent = 0;               // not matched, a surface seen behind it
    uint16_t no_match = 0;             // not matched, its textured patch matches no disparity
    uint64_t last_frame = UINT64_MAX;  // the frame of the newest outcome (one per frame)
    // What the left image showed at its projection the last time it was matched within the chi-square bound
    // (grey levels, row-major, (2 probe_half_size_px + 1)^2 of them): a point whose surface still looks like this
    // has not moved, whatever the mask or the stereo probe say.
    std::array<uint8_t, 49> reference_patch{};
    bool has_reference = false;
  } retirement;

  // Local-mapping-thread scratch.
  struct MappingScratch {
    uint64_t ba_local_for_kf = UINT64_MAX;
    uint64_t fuse_candidate_for_kf = UINT64_MAX;
  } mapping;

 private:
  std::vector<Observation> observations_;
  int n_obs_ = 0;
  bool bad_ = false;
  bool retired_ = false;
  MapPointPtr replaced_;
};

}  // namespace agvslam::slam
