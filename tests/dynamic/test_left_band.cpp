// LeftBand's carrying on its own: an object near the left border whose tracks move left is carried into the band
// x < d without stereo.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/left_band.h"

namespace agvslam::dynamic {
namespace {

const cv::Size kImage(640, 480);

StereoCalibration calibration() {
  StereoCalibration c;
  c.left.fx = c.left.fy = 460;
  c.left.cx = 319.5;
  c.left.cy = 239.5;
  c.left.width = kImage.width;
  c.left.height = kImage.height;
  c.baseline_m = 0.12;
  return c;
}

TrackedPoint track(cv::Point2f prev_px, cv::Point2f motion_px, bool dynamic) {
  TrackedPoint p;
  p.prev_px = prev_px;
  p.cur_px = prev_px + motion_px;
  p.prev_disparity_px = p.cur_disparity_px = 30;
  p.tracked = true;
  p.dynamic = dynamic;
  return p;
}

// Object 7 outlined for two frames at `rect` (median disparity 30 px: the band without stereo is x < 32), its
// pixels kept for carrying; `tracks` lie on it.
void keep_near_the_band(ObjectTracker& objects, const cv::Rect& rect, const std::vector<cv::Point2f>& tracks) {
  FrameRegions regions;
  for (int f = 0; f < 2; ++f) {
    DetectorResult r;
    r.has_previous = true;
    r.mask.instances = cv::Mat::zeros(kImage, CV_8UC1);
    regions.clear();
    r.mask.instances(rect).setTo(regions.new_instance(7));
    r.mask.regions = {rect};
    RoiSegmentation seg;
    seg.outline_verdict = OutlineVerdict::kKept;
    seg.object_id = 7;
    seg.region.rectangle = rect;
    seg.outline_stats.median_disparity_px = 30;
    seg.outline_stats.object_pixels = rect.area();
    r.rois = {seg};
    objects.update(r, regions, {}, true);
    objects.assign_tracks(tracks, r, regions);
  }
}

// This frame: the object's tracks moved by `motion` (`dynamic` of them dynamic); nothing else found.
DetectorResult moved_frame(const std::vector<cv::Point2f>& tracks, cv::Point2f motion, std::size_t dynamic) {
  DetectorResult r;
  r.has_previous = true;
  r.mask.instances = cv::Mat::zeros(kImage, CV_8UC1);
  for (std::size_t i = 0; i < tracks.size(); ++i) r.points.push_back(track(tracks[i], motion, i < dynamic));
  return r;
}

TEST(LeftBand, AnObjectLeavingToTheLeftIsCarriedIntoTheBand) {
  ObjectTracker objects(ObjectTrackerOptions{}, true);
  const cv::Rect rect(40, 150, 60, 120);
  const std::vector<cv::Point2f> tracks = {{60, 170}, {70, 200}, {80, 240}, {90, 260}};
  keep_near_the_band(objects, rect, tracks);
  ASSERT_FALSE(objects.find(7)->carry_mask.empty());
  LeftBand band(BandSegmenterConfig{}, BandCarryOptions{}, 150, calibration());
  DetectorResult r = moved_frame(tracks, {-20, 0}, 4);
  FrameRegions regions;
  regions.clear();
  band.carry(objects, regions, r);
  // Moved to x = 20..80, its pixels in the band x < 32 are the object's region (no region continues it).
  ASSERT_EQ(band.carried().size(), 1u);
  const CarriedObject& c = band.carried().front();
  EXPECT_EQ(c.id, 7);
  EXPECT_TRUE(c.band_only);
  EXPECT_EQ(c.rect, cv::Rect(20, 150, 12, 120));
  EXPECT_EQ(c.pixels, 12 * 120);
  EXPECT_EQ(cv::countNonZero(r.mask.instances), 12 * 120);
  EXPECT_EQ(r.mask.instances.at<uint8_t>(200, 25), c.instance);
  ASSERT_EQ(r.mask.regions.size(), 1u);
  EXPECT_EQ(r.mask.regions[0], c.rect);
  EXPECT_EQ(regions.instance_object()[static_cast<std::size_t>(c.instance)], 7);
  // The object is kept for the next frame as carried only.
  objects.update(r, regions, band.carried(), true);
  EXPECT_EQ(objects.find(7)->band_frames, 1);
}

TEST(LeftBand, AnObjectThatStoppedMovingIsNotCarried) {
  ObjectTracker objects(ObjectTrackerOptions{}, true);
  const cv::Rect rect(40, 150, 60, 120);
  const std::vector<cv::Point2f> tracks = {{60, 170}, {70, 200}, {80, 240}, {90, 260}};
  keep_near_the_band(objects, rect, tracks);
  LeftBand band(BandSegmenterConfig{}, BandCarryOptions{}, 150, calibration());
  FrameRegions regions;
  regions.clear();
  DetectorResult r = moved_frame(tracks, {-20, 0}, 1);  // one dynamic track, band_carry.min_dynamic is 2
  band.carry(objects, regions, r);
  EXPECT_TRUE(band.carried().empty());
  EXPECT_EQ(cv::countNonZero(r.mask.instances), 0);
  // Off: nothing carried either.
  BandCarryOptions off;
  off.max_frames = 0;
  LeftBand off_band(BandSegmenterConfig{}, off, 150, calibration());
  DetectorResult r2 = moved_frame(tracks, {-20, 0}, 4);
  off_band.carry(objects, regions, r2);
  EXPECT_TRUE(off_band.carried().empty());
}

TEST(LeftBand, CarriedPixelsJoinTheRegionContinuingTheObject) {
  ObjectTracker objects(ObjectTrackerOptions{}, true);
  const cv::Rect rect(40, 150, 60, 120);
  const std::vector<cv::Point2f> tracks = {{60, 170}, {70, 200}, {80, 240}, {90, 260}};
  keep_near_the_band(objects, rect, tracks);
  LeftBand band(BandSegmenterConfig{}, BandCarryOptions{}, 150, calibration());
  DetectorResult r = moved_frame(tracks, {-20, 0}, 4);
  // This frame's outline of object 7 ends where stereo does (x = 32).
  FrameRegions regions;
  regions.clear();
  RoiSegmentation seg;
  seg.roi = cv::Rect(32, 150, 48, 120);
  seg.object_id = 7;
  seg.outline = cv::Mat(seg.roi.size(), CV_8UC1, cv::Scalar(255));
  seg.outline_stats.median_disparity_px = 30;
  regions.keep_outline(seg, seg.roi, false, StackingRule{}, true, r.mask);
  band.carry(objects, regions, r);
  ASSERT_EQ(band.carried().size(), 1u);
  EXPECT_FALSE(band.carried().front().band_only);
  EXPECT_EQ(band.carried().front().instance, 1);
  // One region, grown over the band part.
  ASSERT_EQ(r.mask.regions.size(), 1u);
  EXPECT_EQ(r.mask.regions[0], cv::Rect(20, 150, 60, 120));
  EXPECT_EQ(cv::countNonZero(r.mask.instances == 1), 60 * 120);
}

TEST(LeftBand, CarryOptionsAreValidatedUnderTheirSection) {
  BandCarryOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.min_tracks = 0;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "band_carry.min_tracks");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
