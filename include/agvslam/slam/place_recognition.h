#pragma once
// The slot for issue 5's place recognition (bag-of-words vocabulary and keyframe database): the slam module calls
// these hooks, the `place` module implements them. Without an implementation (the default), keyframes carry no
// BowData, tracking recovers from loss only near the last reference keyframe, and there is no loop closing.
//
//   on_keyframe_inserted   local-mapping thread, map mutex held, when a keyframe enters the map: compute kf.bow
//                          (words, and the direct index at the chosen level) and add it to the inverted index.
//   on_keyframe_erased     local-mapping thread, map mutex held, just before a culled keyframe leaves the map.
//   relocalisation_candidates   tracking thread, map mutex held, for a frame while lost: keyframes that may show
//                          the same place (best first). Tracking matches each (brute force until BoW matching
//                          lands), estimates the pose and continues.
// A loop-closing thread attaches to LocalMapping::set_keyframe_sink (called after each keyframe, without the
// map mutex).

#include <vector>

#include "agvslam/slam/frame.h"
#include "agvslam/slam/key_frame.h"

namespace agvslam::slam {

class PlaceRecognition {
 public:
  virtual ~PlaceRecognition() = default;
  virtual void on_keyframe_inserted(KeyFrame& kf) = 0;
  virtual void on_keyframe_erased(KeyFrame& kf) = 0;
  virtual std::vector<KeyFrame*> relocalisation_candidates(const Frame& frame) = 0;
};

}  // namespace agvslam::slam
