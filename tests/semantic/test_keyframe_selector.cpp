// Which frames are segmented (paper 002's rules).
#include <gtest/gtest.h>

#include "agvslam/semantic/keyframe_selector.h"

namespace agvslam::semantic {
namespace {

FrameCues busy() {
  FrameCues c;
  c.previous_dynamic_points = 50;  // enough that the "few dynamic points" rule stays quiet
  return c;
}

TEST(KeyframeSelector, FirstFrameThenEveryNFrames) {
  KeyframeSelector s(KeyframeConfig{});
  EXPECT_EQ(s.next(busy()), SegmentReason::kFirstFrame);
  for (int round = 0; round < 3; ++round) {
    for (int i = 0; i < 4; ++i) EXPECT_EQ(s.next(busy()), SegmentReason::kNone) << round << " " << i;
    EXPECT_EQ(s.next(busy()), SegmentReason::kEveryNFrames) << round;
  }
}

TEST(KeyframeSelector, FirstFrameAfterRelocalisation) {
  KeyframeSelector s(KeyframeConfig{});
  s.next(busy());
  s.next(busy());
  FrameCues c = busy();
  c.relocalised = true;
  EXPECT_EQ(s.next(c), SegmentReason::kRelocalised);
  EXPECT_EQ(s.next(busy()), SegmentReason::kNone);  // the count starts again
}

TEST(KeyframeSelector, TooFewDynamicPointsInThePreviousFrame) {
  KeyframeSelector s(KeyframeConfig{});
  s.next(busy());
  FrameCues few = busy();
  few.previous_dynamic_points = 2;
  // At most every other frame, so a scene without movers is not segmented on every frame.
  EXPECT_EQ(s.next(few), SegmentReason::kNone);
  EXPECT_EQ(s.next(few), SegmentReason::kFewDynamicPoints);
  EXPECT_EQ(s.next(few), SegmentReason::kNone);
  EXPECT_EQ(s.next(few), SegmentReason::kFewDynamicPoints);

  KeyframeConfig off;
  off.min_dynamic_points = 0;
  KeyframeSelector t(off);
  t.next(few);
  EXPECT_EQ(t.next(few), SegmentReason::kNone);
  EXPECT_EQ(t.next(few), SegmentReason::kNone);
}

TEST(KeyframeSelector, NewSlamKeyframe) {
  KeyframeSelector s(KeyframeConfig{});
  s.next(busy());
  FrameCues kf = busy();
  kf.new_keyframe = true;
  EXPECT_EQ(s.next(kf), SegmentReason::kNewKeyframe);
  KeyframeConfig off;
  off.on_new_keyframe = false;
  KeyframeSelector t(off);
  t.next(busy());
  EXPECT_EQ(t.next(kf), SegmentReason::kNone);
}

TEST(KeyframeSelector, ResetStartsAgainAtTheFirstFrame) {
  KeyframeSelector s(KeyframeConfig{});
  s.next(busy());
  s.next(busy());
  s.reset();
  EXPECT_EQ(s.next(busy()), SegmentReason::kFirstFrame);
}

}  // namespace
}  // namespace agvslam::semantic
