// RoiOutliner and RoiMatcher on their own: one group of dynamic points on a rendered box becomes a region of the
// mask through the ROI's disparity outline.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/dynamic/roi_outliner.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
using namespace agvslam::dynamic::testing;

// A frame of the corridor with the box, and tracked points at their true disparity: a grid on the box (moved by
// `box_motion_px`, off the ego-motion by `offset_px`) and one on the background (static).
struct BoxFrame {
  StereoFrame frame;
  cv::Mat gt_mask, gt_disparity;
  DetectorResult result;
  DynamicPoints dynamic;
};

BoxFrame box_frame(bool box_points_dynamic) {
  const CorridorScene scene;
  BoxFrame b;
  b.frame = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), true, 1, &b.gt_mask, &b.gt_disparity);
  cv::Mat inner;
  cv::erode(b.gt_mask, inner, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(13, 13)));
  b.result.has_previous = true;
  b.result.mask.instances = cv::Mat::zeros(b.frame.left.size(), CV_8UC1);
  for (int y = 20; y < inner.rows - 20; y += 24) {
    for (int x = 20; x < inner.cols - 20; x += 24) {
      TrackedPoint p;
      p.cur_px = cv::Point2f(static_cast<float>(x), static_cast<float>(y));
      p.prev_px = p.cur_px - cv::Point2f(6, 0);
      p.cur_disparity_px = p.prev_disparity_px = b.gt_disparity.at<float>(y, x);
      p.tracked = true;
      const bool on_box = inner.at<uint8_t>(y, x) != 0;
      p.dynamic = on_box && box_points_dynamic;
      p.reprojection_px = on_box ? 4.0 : 0.1;
      b.result.points.push_back(p);
      if (p.dynamic) b.dynamic.add(p, static_cast<int>(b.result.points.size() - 1));
    }
  }
  return b;
}

TEST(RoiOutliner, AGroupOnABoxBecomesARegionOfTheMask) {
  const DynamicDetectorConfig c;
  const CorridorScene scene;
  BoxFrame b = box_frame(true);
  const std::vector<DynamicGroup> groups =
      group_dynamic_points(b.dynamic.px, b.dynamic.disparity_px, b.frame.left.size(), c.grouping, scene.baseline_m);
  ASSERT_EQ(groups.size(), 1u);
  RoiOutliner outliner(c.roi, roi_outliner_context(c), scene.calibration(), stereo::SgbmConfig{});
  ObjectTracker objects(c.objects, true);
  FrameRegions regions;
  regions.clear();
  b.result.rois.resize(1);
  RoiSegmentation& seg = b.result.rois[0];
  outliner.begin_frame();
  outliner.outline_group(b.frame, cv::Mat(), groups[0], 0, -1, false, b.dynamic, objects, regions, seg, b.result);
  ASSERT_EQ(seg.outline_verdict, OutlineVerdict::kKept) << to_string(seg.outline_verdict);
  EXPECT_EQ(seg.points.size(), b.dynamic.size());
  for (int idx : seg.points) EXPECT_EQ(b.result.points[static_cast<std::size_t>(idx)].group, 0);
  EXPECT_GE(seg.object_id, 0);
  // The ROI reaches beyond the points' box (margins, the floor), its disparity matched.
  EXPECT_EQ(seg.disparity_px.size(), seg.roi.size());
  EXPECT_GT(cv::countNonZero(seg.disparity_px > 0), seg.roi.area() / 2);
  // The region is the box.
  cv::Mat found;
  cv::compare(b.result.mask.instances, 0, found, cv::CMP_GT);
  EXPECT_GE(iou(found, b.gt_mask), 0.8);
  ASSERT_EQ(b.result.mask.regions.size(), 1u);
  EXPECT_EQ(regions.instance_object()[1], seg.object_id);
  EXPECT_EQ(seg.outline_stats.dynamic_inside, static_cast<int>(b.dynamic.size()));
}

TEST(RoiOutliner, AnOutlineOfStaticTracksIsNotKept) {
  // The same group, but the box's other tracks are static and unmoved: its tracks are mostly static.
  const DynamicDetectorConfig c;
  const CorridorScene scene;
  BoxFrame b = box_frame(true);
  const std::vector<DynamicGroup> groups =
      group_dynamic_points(b.dynamic.px, b.dynamic.disparity_px, b.frame.left.size(), c.grouping, scene.baseline_m);
  ASSERT_EQ(groups.size(), 1u);
  int made_static = 0;
  for (TrackedPoint& p : b.result.points) {
    if (!p.dynamic || made_static >= static_cast<int>(b.dynamic.size()) - 5) continue;
    p.dynamic = false;
    p.reprojection_px = 0.1;
    ++made_static;
  }
  RoiOutliner outliner(c.roi, roi_outliner_context(c), scene.calibration(), stereo::SgbmConfig{});
  ObjectTracker objects(c.objects, true);
  FrameRegions regions;
  regions.clear();
  b.result.rois.resize(1);
  outliner.outline_group(b.frame, cv::Mat(), groups[0], 0, -1, false, b.dynamic, objects, regions, b.result.rois[0],
                         b.result);
  EXPECT_EQ(b.result.rois[0].outline_verdict, OutlineVerdict::kMostlyStaticTracks);
  EXPECT_TRUE(b.result.mask.regions.empty());
  EXPECT_EQ(cv::countNonZero(b.result.mask.instances), 0);
}

TEST(RoiMatcher, PaddingGivesDisparityNearTheLeftBorder) {
  CorridorScene scene;
  scene.box.origin = {-2.3, -1.1, 2.5};
  scene.box.width_m = 0.8;
  const StereoFrame f = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), true, 0);
  const cv::Rect roi(0, 150, 120, 150);
  cv::Mat padded, plain;
  RoiMatcher(stereo::SgbmConfig{}, true).match(f, roi, 40, 1.0, 1, padded);
  RoiMatcher(stereo::SgbmConfig{}, false).match(f, roi, 40, 1.0, 1, plain);
  ASSERT_EQ(padded.size(), roi.size());
  ASSERT_EQ(plain.size(), roi.size());
  // Columns 24-40: right of the box's disparity (~22 px), left of where unpadded SGBM starts matching.
  const cv::Rect near_border(24, 0, 16, roi.height);
  EXPECT_GT(cv::countNonZero(padded(near_border) > 0), near_border.area() / 2);
  EXPECT_LT(cv::countNonZero(plain(near_border) > 0), near_border.area() / 10);
}

TEST(RoiOutliner, OptionsAreValidatedUnderTheirSection) {
  RoiOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.row_step = 3;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "roi.row_step");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
