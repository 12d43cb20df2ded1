#pragma once
// Moving or not, per segmented object (paper 001): an object of a movable class is masked only while its own
// points move against the ego-motion. Each frame gives a vote from the object's tracked points, judged against
// the static points of the same frame: a point moves when its reprojection offset under the ego-motion (the
// detector's depth test, stereo depth) exceeds the static offsets' median by static_sigmas robust sigmas, or when
// the detector's epipolar or depth test flagged it. With fewer than min_points tested points (a far object) the
// vote comes from the mask itself: its corners' image shift against the shift of static points at its depth (its
// points' disparity, or the floor's where it stands), which is where a static object there would have gone; with
// no depth at all there is no vote. Votes accumulate with a decay and a hysteresis, so one
// noisy frame neither masks a standing person nor unmasks a walking one.

#include <vector>

#include "agvslam/dynamic/detection_result.h"
#include "agvslam/dynamic/disparity_plane.h"
#include "agvslam/semantic/mask_propagation.h"
#include "agvslam/semantic/semantic_config.h"

namespace agvslam::semantic {

// What one frame said about one object.
struct MotionVote {
  int tested_points = 0;  // its points with a reprojection offset
  int moving_points = 0;
  bool from_mask = false;      // the far-object rule decided (too few tested points)
  double mask_offset_px = -1;  // far rule: |own shift - static shift at its depth|, -1: not measured
  double vote = 0;             // 1: moving, 0: standing (no evidence also gives 0)
  bool measured = false;       // false: nothing could be said this frame
};

class ObjectMotionTest {
 public:
  explicit ObjectMotionTest(const MotionConfig& config) : config_(config) {}

  // Votes for each object from the detector's points of this frame and updates its evidence and `moving`.
  // points: DetectorResult::points (current positions cur_px); static points are those outside every object.
  // ground: the floor's disparity plane (DetectorResult::ground_plane), the depth of an object without points of
  // its own where it stands (the bottom of its mask); null or invalid: such an object gets no far-object vote.
  std::vector<MotionVote> update(const std::vector<dynamic::TrackedPoint>& points,
                                 const dynamic::DisparityPlane* ground, std::vector<SemanticObject>& objects) const;

  // The robust threshold on reprojection offsets from the static points' offsets (px).
  double static_threshold_px(const std::vector<float>& static_offsets_px) const;

 private:
  MotionConfig config_;
};

}  // namespace agvslam::semantic
