#pragma once
// Which frames go to the segmentation network (paper 002, III.C): the first frame and the first after a
// relocalisation, a frame after one that held too few dynamic points (something may have come in that geometry
// cannot see yet), every N frames, and the SLAM's new keyframes. The other frames get the masks carried by
// propagation.

#include <cstdint>

#include "agvslam/semantic/semantic_config.h"

namespace agvslam::semantic {

enum class SegmentReason : uint8_t {
  kNone,  // not segmented: the masks are propagated
  kFirstFrame,
  kRelocalised,
  kFewDynamicPoints,
  kEveryNFrames,
  kNewKeyframe,
};
const char* to_string(SegmentReason reason);

// What tracking knows about the frame about to be processed.
struct FrameCues {
  bool relocalised = false;          // the first frame after tracking was lost and found again
  int previous_dynamic_points = -1;  // dynamic points of the previous frame (-1: unknown)
  bool new_keyframe = false;         // the previous frame was made a SLAM keyframe
};

class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeConfig& config) : config_(config) {}

  // The reason to segment this frame (the first rule that applies, in the order of SegmentReason), or kNone.
  // Counts the frame.
  SegmentReason next(const FrameCues& cues);
  // Starts again as at the first frame.
  void reset() { frames_since_segmented_ = -1; }

 private:
  KeyframeConfig config_;
  int frames_since_segmented_ = -1;  // -1: no frame yet
};

}  // namespace agvslam::semantic
