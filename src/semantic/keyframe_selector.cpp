#include "agvslam/semantic/keyframe_selector.h"

namespace agvslam::semantic {

const char* to_string(SegmentReason reason) {
  switch (reason) {
    case SegmentReason::kNone:
      return "none";
    case SegmentReason::kFirstFrame:
      return "first frame";
    case SegmentReason::kRelocalised:
      return "relocalised";
    case SegmentReason::kFewDynamicPoints:
      return "few dynamic points";
    case SegmentReason::kEveryNFrames:
      return "every N frames";
    case SegmentReason::kNewKeyframe:
      return "new keyframe";
  }
  return "?";
}

SegmentReason KeyframeSelector::next(const FrameCues& cues) {
  SegmentReason reason = SegmentReason::kNone;
  if (frames_since_segmented_ < 0) {
    reason = SegmentReason::kFirstFrame;
  } else if (cues.relocalised) {
    reason = SegmentReason::kRelocalised;
  } else if (config_.min_dynamic_points > 0 && cues.previous_dynamic_points >= 0 &&
             cues.previous_dynamic_points < config_.min_dynamic_points && frames_since_segmented_ + 1 >= 2) {
    // At most every other frame: a scene with no movers at all would otherwise be segmented on every frame.
    reason = SegmentReason::kFewDynamicPoints;
  } else if (frames_since_segmented_ + 1 >= config_.every_n_frames) {
    reason = SegmentReason::kEveryNFrames;
  } else if (config_.on_new_keyframe && cues.new_keyframe) {
    reason = SegmentReason::kNewKeyframe;
  }
  frames_since_segmented_ = reason == SegmentReason::kNone ? frames_since_segmented_ + 1 : 0;
  return reason;
}

}  // namespace agvslam::semantic
