// ObjectTracker on its own: objects kept over frames from the regions of each frame, groups continuing them,
// coasting, and the growth cut.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/object_tracker.h"

namespace agvslam::dynamic {
namespace {

const cv::Size kImage(640, 480);

// A frame whose mask holds one kept region of `object_id` (its whole rectangle) at `median_disparity_px`.
DetectorResult frame_with_object(const cv::Rect& rect, int object_id, double median_disparity_px,
                                 FrameRegions& regions) {
  DetectorResult r;
  r.has_previous = true;
  r.mask.instances = cv::Mat::zeros(kImage, CV_8UC1);
  regions.clear();
  const int instance = regions.new_instance(object_id);
  r.mask.instances(rect).setTo(instance);
  cv::compare(r.mask.instances, 0, r.mask.image, cv::CMP_GT);
  r.mask.regions = {rect};
  RoiSegmentation seg;
  seg.outline_verdict = OutlineVerdict::kKept;
  seg.object_id = object_id;
  seg.region.rectangle = rect;
  seg.outline_stats.median_disparity_px = median_disparity_px;
  seg.outline_stats.object_pixels = rect.area();
  r.rois = {seg};
  return r;
}

TrackedPoint track(cv::Point2f prev_px, cv::Point2f motion_px, float disparity_px, bool dynamic) {
  TrackedPoint p;
  p.prev_px = prev_px;
  p.cur_px = prev_px + motion_px;
  p.prev_disparity_px = p.cur_disparity_px = disparity_px;
  p.tracked = true;
  p.dynamic = dynamic;
  return p;
}

// Keeps object 7 at `rect` for `frames` frames; its tracks are `inside` (then `outside`, of no object).
void keep_object(ObjectTracker& tracker, const cv::Rect& rect, int frames, const std::vector<cv::Point2f>& tracks,
                 FrameRegions& regions) {
  for (int f = 0; f < frames; ++f) {
    const DetectorResult r = frame_with_object(rect, 7, 20, regions);
    tracker.update(r, regions, {}, false);
    tracker.remember_pixels(r, regions);
    tracker.assign_tracks(tracks, r, regions);
  }
}

TEST(ObjectTracker, KeepsTheObjectsOfEachFrameAndTheirTracks) {
  ObjectTracker tracker(ObjectTrackerOptions{}, true);
  ASSERT_TRUE(tracker.enabled());
  EXPECT_FALSE(ObjectTracker(ObjectTrackerOptions{}, false).enabled());  // superpixel / rectangle modes
  FrameRegions regions;
  const cv::Rect rect(200, 100, 40, 100);
  const std::vector<cv::Point2f> tracks = {{210, 120}, {220, 150}, {230, 180}, {400, 300}};
  keep_object(tracker, rect, 2, tracks, regions);
  ASSERT_EQ(tracker.objects().size(), 1u);
  const ObjectTrack* ob = tracker.find(7);
  ASSERT_NE(ob, nullptr);
  EXPECT_EQ(ob->detections, 2);
  EXPECT_EQ(ob->coasted, 0);
  EXPECT_EQ(ob->rect, rect);
  EXPECT_EQ(tracker.find(8), nullptr);
  EXPECT_EQ(tracker.track_object(), (std::vector<int>{7, 7, 7, -1}));
  EXPECT_EQ(tracker.coast_min_pixels(7), static_cast<int>(0.5 * rect.area()));
  EXPECT_EQ(tracker.coast_min_pixels(8), 0);
  tracker.reset();
  EXPECT_TRUE(tracker.objects().empty());
  EXPECT_TRUE(tracker.track_object().empty());
}

TEST(ObjectTracker, SmallGroupsContinueTheirObject) {
  ObjectTracker tracker(ObjectTrackerOptions{}, true);
  FrameRegions regions;
  // Tracks 0-2 and 5-7 lie on object 7, tracks 3-4 on nothing.
  const std::vector<cv::Point2f> tracks = {{210, 120}, {220, 150}, {230, 180}, {400, 300},
                                           {410, 310}, {212, 130}, {222, 160}, {232, 170}};
  keep_object(tracker, cv::Rect(200, 100, 40, 100), 1, tracks, regions);
  DynamicPoints dynamic;
  for (std::size_t i = 0; i < tracks.size(); ++i) dynamic.add(track(tracks[i], {3, 0}, 20, true), static_cast<int>(i));
  const int min_points = 5;
  EXPECT_EQ(tracker.group_min_points(min_points), ObjectTrackerOptions{}.continue_min_points);
  // Largest first: six points (three of object 7), three of object 7, two of nothing.
  std::vector<DynamicGroup> groups(3);
  groups[0].members = {0, 1, 2, 3, 4, 5};
  groups[1].members = {5, 6, 7};
  groups[2].members = {3, 4};
  std::vector<int> group_object;
  tracker.assign_groups(dynamic, min_points, groups, group_object);
  // The large group continues object 7; the small one continuing it too is a part of it; the pair is no ROI.
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].members.size(), 6u);
  EXPECT_EQ(group_object, (std::vector<int>{7}));
  // Alone, the small group is a ROI of object 7.
  std::vector<DynamicGroup> small(1);
  small[0].members = {5, 6, 7};
  tracker.assign_groups(dynamic, min_points, small, group_object);
  ASSERT_EQ(small.size(), 1u);
  EXPECT_EQ(group_object, (std::vector<int>{7}));
}

TEST(ObjectTracker, AnObjectWithoutARegionCoastsOnItsTracks) {
  ObjectTracker tracker(ObjectTrackerOptions{}, true);
  FrameRegions regions;
  const cv::Rect rect(200, 100, 40, 100);
  const std::vector<cv::Point2f> tracks = {{210, 120}, {220, 150}, {230, 180}, {400, 300}};
  keep_object(tracker, rect, 2, tracks, regions);
  ASSERT_TRUE(tracker.may_coast());
  // This frame: its tracks moved by (+5, 0) at its depth; no region continues it.
  DetectorResult r;
  r.mask.instances = cv::Mat::zeros(kImage, CV_8UC1);
  for (const cv::Point2f& p : tracks) r.points.push_back(track(p, {5, 0}, 20, false));
  regions.clear();
  std::vector<DynamicGroup> groups;
  std::vector<int> group_object;
  DynamicPoints dynamic;
  tracker.add_coasting_groups(r, regions, RoiGroupingConfig{}, 8, groups, group_object, dynamic);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(group_object, (std::vector<int>{7}));
  EXPECT_EQ(dynamic.size(), 3u);  // its three tracks seed the outline
  EXPECT_EQ(groups[0].roi & (rect + cv::Point(5, 0)), rect + cv::Point(5, 0));
  // A region of this frame continuing it: no coasting; nor beyond max_rois.
  const int instance = regions.new_instance(7);
  EXPECT_EQ(instance, 1);
  groups.clear();
  group_object.clear();
  tracker.add_coasting_groups(r, regions, RoiGroupingConfig{}, 8, groups, group_object, dynamic);
  EXPECT_TRUE(groups.empty());
  regions.clear();
  tracker.add_coasting_groups(r, regions, RoiGroupingConfig{}, 0, groups, group_object, dynamic);
  EXPECT_TRUE(groups.empty());
  // Seen only once, an object does not coast.
  ObjectTracker once(ObjectTrackerOptions{}, true);
  keep_object(once, rect, 1, tracks, regions);
  regions.clear();
  once.add_coasting_groups(r, regions, RoiGroupingConfig{}, 8, groups, group_object, dynamic);
  EXPECT_TRUE(groups.empty());
}

TEST(ObjectTracker, IdsAreNewUnlessTheFrameHoldsTheContinuedOne) {
  ObjectTracker tracker(ObjectTrackerOptions{}, true);
  FrameRegions regions;
  regions.clear();
  const int first = tracker.claim_id(-1, regions);
  const int second = tracker.claim_id(-1, regions);
  EXPECT_EQ(second, first + 1);
  EXPECT_EQ(tracker.claim_id(first, regions), first);
  regions.new_instance(first);
  EXPECT_EQ(tracker.claim_id(first, regions), second + 1);
}

TEST(ObjectTracker, AnOutlineThatSuddenlyGrewIsCutToItsLastPixels) {
  ObjectTracker tracker(ObjectTrackerOptions{}, true);
  FrameRegions regions;
  const cv::Rect rect(200, 100, 40, 100);
  const std::vector<cv::Point2f> tracks = {{210, 120}, {220, 150}, {230, 180}};
  keep_object(tracker, rect, 2, tracks, regions);
  // This frame: the object moved by (+6, -2); its outline in a ROI at (150, 60) also holds a slab beside it.
  DetectorResult r;
  r.mask.instances = cv::Mat::zeros(kImage, CV_8UC1);
  for (const cv::Point2f& p : tracks) r.points.push_back(track(p, {6, -2}, 20, true));
  RoiSegmentation seg;
  seg.roi = cv::Rect(150, 60, 200, 200);
  seg.object_id = 7;
  seg.outline = cv::Mat::zeros(seg.roi.size(), CV_8UC1);
  const cv::Rect object_now = rect + cv::Point(6, -2) - seg.roi.tl();
  seg.outline(object_now).setTo(255);
  seg.outline(cv::Rect(0, 0, 120, 60)).setTo(255);
  seg.outline_stats.object_pixels = cv::countNonZero(seg.outline);
  ASSERT_GT(seg.outline_stats.object_pixels, ObjectTrackerOptions{}.growth_max_ratio * rect.area());
  tracker.cut_growth(r, seg);
  EXPECT_EQ(seg.outline_stats.object_pixels, cv::countNonZero(seg.outline));
  EXPECT_EQ(cv::countNonZero(seg.outline(object_now)), object_now.area());
  // Grown by 0.08 of its size + 2 px: (5, 10) px.
  const cv::Rect allowed(object_now.x - 5, object_now.y - 10, object_now.width + 10, object_now.height + 20);
  EXPECT_EQ(seg.outline_stats.object_pixels,
            cv::countNonZero(seg.outline(allowed & cv::Rect(cv::Point(), seg.roi.size()))));
  // A coasted outline is not cut.
  RoiSegmentation coasted;
  coasted.roi = seg.roi;
  coasted.object_id = 7;
  coasted.coasted = true;
  coasted.outline = cv::Mat(seg.roi.size(), CV_8UC1, cv::Scalar(255));
  coasted.outline_stats.object_pixels = seg.roi.area();
  tracker.cut_growth(r, coasted);
  EXPECT_EQ(coasted.outline_stats.object_pixels, seg.roi.area());
}

TEST(ObjectTracker, CutToMovedPixelsKeepsTheLastPixelsMovedAndAMargin) {
  // The object (a 40 x 100 px block) was at (200, 100) and moved by (+6, -2); this frame's outline, in a ROI at
  // (150, 60), holds it and a 120 x 60 px slab beside and above it. Cut to the last pixels moved and grown by
  // (4, 8), only the block and the margin around it remain.
  cv::Mat last = cv::Mat::zeros(100, 40, CV_8UC1);
  last.setTo(255);
  const cv::Point last_origin(200, 100), shift(6, -2), roi_origin(150, 60);
  cv::Mat outline = cv::Mat::zeros(200, 200, CV_8UC1);
  const cv::Rect object_now = cv::Rect(last_origin + shift - roi_origin, last.size());
  outline(object_now).setTo(255);
  const cv::Rect slab(0, 0, 120, 60);
  outline(slab).setTo(255);
  ASSERT_GT((slab & object_now).area(), 0);
  const int before = cv::countNonZero(outline);
  const int kept = cut_to_moved_pixels(outline, roi_origin, last, last_origin, shift, cv::Size(4, 8));
  EXPECT_EQ(kept, cv::countNonZero(outline));
  EXPECT_LT(kept, before);
  EXPECT_EQ(cv::countNonZero(outline(object_now)), object_now.area());
  const cv::Rect allowed(object_now.x - 4, object_now.y - 8, object_now.width + 8, object_now.height + 16);
  EXPECT_EQ(kept, cv::countNonZero(outline(allowed & cv::Rect(0, 0, outline.cols, outline.rows))));
  EXPECT_EQ(cv::countNonZero(outline(cv::Rect(0, 0, allowed.x, outline.rows))), 0);
  // Last pixels that moved out of the ROI altogether leave nothing.
  cv::Mat far_outline = cv::Mat::zeros(50, 50, CV_8UC1);
  far_outline.setTo(255);
  EXPECT_EQ(cut_to_moved_pixels(far_outline, cv::Point(600, 400), last, last_origin, shift, cv::Size(4, 8)), 0);
}

TEST(ObjectTracker, OptionsAreValidatedUnderTheirSection) {
  ObjectTrackerOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.growth_max_ratio = 0.5;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "objects.growth_max_ratio");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
