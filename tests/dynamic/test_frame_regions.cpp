// FrameRegions on its own: kept outlines become instances of the mask, stacked ones merge, side-by-side pieces are
// objects of their own, and the left band's pixels join the region holding their instance.
#include <gtest/gtest.h>

#include "agvslam/dynamic/frame_regions.h"

namespace agvslam::dynamic {
namespace {

const cv::Size kImage(640, 480);

DynamicMask empty_mask() {
  DynamicMask m;
  m.instances = cv::Mat::zeros(kImage, CV_8UC1);
  return m;
}

// A kept outline filling `rect` (its ROI) at 20 px of disparity, of object `object_id`.
RoiSegmentation outline_of(const cv::Rect& rect, int object_id) {
  RoiSegmentation seg;
  seg.roi = rect;
  seg.object_id = object_id;
  seg.outline = cv::Mat(rect.size(), CV_8UC1, cv::Scalar(255));
  seg.outline_stats.median_disparity_px = 20;
  return seg;
}

TEST(FrameRegions, StartsEmpty) {
  FrameRegions regions;
  regions.clear();
  EXPECT_EQ(regions.next_instance(), 1);
  EXPECT_EQ(regions.instance_object(), (std::vector<int>{-1}));
  EXPECT_FALSE(regions.holds_object(3));
  EXPECT_EQ(regions.new_instance(3), 1);
  EXPECT_TRUE(regions.holds_object(3));
  EXPECT_EQ(regions.next_instance(), 2);
}

TEST(FrameRegions, AStackedOutlineJoinsTheRegionBelowOrAbove) {
  StackingRule stacking;
  stacking.baseline_m = 0.12;
  FrameRegions regions;
  regions.clear();
  DynamicMask mask = empty_mask();
  RoiSegmentation torso = outline_of(cv::Rect(100, 50, 60, 100), 4);
  RoiSegmentation legs = outline_of(cv::Rect(105, 150, 50, 100), 9);
  regions.keep_outline(torso, torso.roi, false, stacking, true, mask);
  regions.keep_outline(legs, legs.roi, true, stacking, true, mask);
  ASSERT_EQ(mask.regions.size(), 1u);
  EXPECT_EQ(mask.regions[0], cv::Rect(100, 50, 60, 200));
  EXPECT_EQ(legs.object_id, 4);  // the legs take the torso's object
  EXPECT_EQ(cv::countNonZero(mask.instances == 1), torso.roi.area() + legs.roi.area());
  EXPECT_EQ(regions.next_instance(), 2);
  EXPECT_EQ(regions.instance_near_moving()[1], 1);  // marked by the legs
  // Without the rule they are two objects.
  stacking.enabled = false;
  regions.clear();
  DynamicMask apart = empty_mask();
  regions.keep_outline(torso, torso.roi, false, stacking, true, apart);
  regions.keep_outline(legs, legs.roi, false, stacking, true, apart);
  EXPECT_EQ(apart.regions.size(), 2u);
  EXPECT_EQ(regions.instance_object(), (std::vector<int>{-1, 4, 4}));
}

TEST(FrameRegions, PiecesSideBySideAreObjectsOfTheirOwn) {
  FrameRegions regions;
  regions.clear();
  DynamicMask mask = empty_mask();
  RoiSegmentation two = outline_of(cv::Rect(100, 100, 200, 100), 5);
  two.outline(cv::Rect(60, 0, 80, 100)).setTo(0);  // two people 80 px apart
  regions.keep_outline(two, two.roi, false, StackingRule{}, true, mask);
  EXPECT_EQ(mask.regions.size(), 1u);
  EXPECT_EQ(regions.next_instance(), 3);
  EXPECT_EQ(regions.instance_object(), (std::vector<int>{-1, 5, 5}));
  EXPECT_EQ(cv::countNonZero(mask.instances == 1), 60 * 100);
  EXPECT_EQ(cv::countNonZero(mask.instances == 2), 60 * 100);
  regions.clear();
  DynamicMask one = empty_mask();
  regions.keep_outline(two, two.roi, false, StackingRule{}, false, one);
  EXPECT_EQ(regions.next_instance(), 2);
}

TEST(FrameRegions, BandPixelsJoinTheRegionHoldingTheirInstance) {
  FrameRegions regions;
  regions.clear();
  DynamicMask mask = empty_mask();
  RoiSegmentation first = outline_of(cv::Rect(40, 100, 50, 100), 1);
  RoiSegmentation second = outline_of(cv::Rect(300, 100, 50, 100), 2);
  StackingRule stacking;
  regions.keep_outline(first, first.roi, false, stacking, true, mask);
  regions.keep_outline(second, second.roi, false, stacking, true, mask);
  regions.add_band_rect(cv::Rect(10, 120, 30, 60), 1, false, mask);
  ASSERT_EQ(mask.regions.size(), 2u);
  EXPECT_EQ(mask.regions[0], cv::Rect(10, 100, 80, 100));
  EXPECT_EQ(mask.regions[1], second.roi);
  regions.add_band_rect(cv::Rect(0, 300, 20, 60), regions.new_instance(-1), true, mask);
  EXPECT_EQ(mask.regions.size(), 3u);
}

}  // namespace
}  // namespace agvslam::dynamic
