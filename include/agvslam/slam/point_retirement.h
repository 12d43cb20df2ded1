#pragma once
// Retirement of map points on objects that move after they were mapped (RetirementConfig in slam_config.h).
//
// A parked forklift, a pallet or a standing person is static when the AGV first sees it, so its points enter the
// map; when it moves, those points are wrong. Each point keeps a reference appearance: the left image's patch at its
// projection when it was last matched within the chi-square bound (and whenever the image still looks like it
// there). After each tracked frame, every local map point with a reference that is predicted in view gives one
// outcome for its window (MapPoint::retirement):
//   - the image at its predicted pixel still looks like the reference: its surface is there, no evidence (a static
//     point in a detector's false mask region, one the matcher missed, or one matched to the wrong keypoint);
//   - it does not and it was not matched: the images are probed at its projection (probe_stereo): a surface at its
//     depth inside the dynamic mask is evidence that the object it lies on moves; a surface behind it is evidence
//     that it left (the camera sees through where it was); a surface at its depth outside the mask is no evidence;
//     a surface in front of it (an occluder) or a patch without texture gives no outcome at all, so a point that
//     is merely hidden keeps its window. A textured patch that matches nothing in the right image at any disparity
//     (the surface behind lies beyond the search range or its patch spans a depth edge) is evidence too, but only
//     alongside a surface seen behind the point.
// A match beyond the chi-square bound gives no outcome: on a static point it is a mismatch as often as not, and a
// point on an object that moved is seen through once the object has gone. A match to a keypoint without stereo
// depth is treated as no match: it confirms the point's direction, not its depth (a standing camera sees the
// surface behind a point that left at the same pixel).
// Only points whose surface changed reach the stereo probe, which is the costly part.
// A point with evidence in min_frames of its last window_frames outcomes, at least one of them a surface seen
// behind it, is retired: its keyframes' keypoints are blocked (KeyFrame::retire_keypoint) and it is set bad, so it
// leaves the map, relocalisation, loop closing and any map saved afterwards. A masked surface at the point's depth
// alone is not enough: a mover passing in front of a static point within the disparity tolerance looks the same
// as the point's own object moving; only free space seen where the point was tells them apart.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "agvslam/slam/frame.h"
#include "agvslam/slam/optimizer.h"
#include "agvslam/slam/slam_config.h"

namespace agvslam::slam {

class Map;
class MapPoint;

enum class RetirementReason { kMask, kAbsent };
const char* to_string(RetirementReason reason);

// Points retired, by reason.
struct RetirementCounts {
  uint64_t mask = 0;    // mostly in the dynamic mask with a surface at their depth
  uint64_t absent = 0;  // mostly not found: a surface seen behind them, or no stereo match
  uint64_t total() const { return mask + absent; }
  RetirementCounts& operator+=(const RetirementCounts& o) {
    mask += o.mask;
    absent += o.absent;
    return *this;
  }
};

// What the rectified stereo pair shows at a left-image pixel, against an expected disparity.
enum class SurfaceAt {
  kUnknown,  // no texture, or outside the images
  kNoMatch,  // textured, but no disparity in the range correlates
  kAtDepth,  // the best match is within the tolerance of the expected disparity
  kBehind,   // the best match is at a smaller disparity (farther)
  kInFront,  // the best match is at a larger disparity (nearer)
};
const char* to_string(SurfaceAt surface);

// Compares the left patch at (u_px, v_px) with right patches along the row over disparities 0 .. 2 x
// expected_disparity_px + tolerance_px (zero-mean normalised correlation, sub-pixel by a parabola); the surface is
// at the best correlation if that reaches probe_min_zncc.
SurfaceAt probe_stereo(const cv::Mat& left, const cv::Mat& right, double u_px, double v_px,
                       double expected_disparity_px, double tolerance_px, const RetirementConfig& config);

// The images of the frame being tracked (CV_8UC1, rectified; mask non-zero = moving object, may be empty).
struct FrameImages {
  cv::Mat left, right, dynamic_mask;
};

class PointRetirement {
 public:
  PointRetirement(const RetirementConfig& config, const StereoIntrinsics& intrinsics);

  // One match the pose of `frame` was estimated with (inlier or outlier of the motion-only BA).
  struct Match {
    MapPointPtr point;
    int keypoint;
  };
  // After `frame` was tracked (its pose is final): outcomes for the matched points and for the unmatched points of
  // `local_points` that project into the image within their scale-invariance range; retires those whose window
  // holds enough evidence (with the map mutex held). Returns the points retired on this frame, by reason.
  RetirementCounts update(const Frame& frame, const std::vector<Match>& matches,
                          const std::vector<MapPoint*>& local_points, const FrameImages& images, Map& map);

  // Removes `point` from its keyframes (blocking their keypoints) and from the map.
  static void retire(MapPoint& point, Map& map);

 private:
  enum class Outcome { kNoEvidence, kMask, kAbsent, kNoMatch };
  // Adds one outcome to the point's window; true (and the reason with the most evidence) when the window now holds
  // min_frames of evidence, one of them a surface seen behind the point.
  bool record(MapPoint& point, uint64_t frame_id, Outcome outcome, RetirementReason& reason) const;

  // Whether the left image at (u_px, v_px) correlates with the point's reference appearance (probe_min_zncc), which
  // then becomes the new reference; nullopt when it has none, the patch leaves the image or either patch has no
  // texture.
  std::optional<bool> looks_as_before(MapPoint& point, const cv::Mat& left, double u_px, double v_px) const;

  RetirementConfig config_;
  StereoIntrinsics intrinsics_;
  uint16_t window_bits_;
};

}  // namespace agvslam::slam
