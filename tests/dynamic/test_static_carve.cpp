// Static carving on its own: the Voronoi split between an object's dynamic points and the clearly static tracks of a
// surface its outline flooded.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/static_carve.h"

namespace agvslam::dynamic {
namespace {

// A ROI at (100, 50) whose outline holds a person (a 40 x 120 px block, dynamic points down its middle) and, right of
// it, a 60 x 120 px rack face at its depth.
struct FloodedOutline {
  const cv::Point roi_origin{100, 50};
  const cv::Rect person{10, 10, 40, 120}, rack{50, 10, 60, 120};  // ROI coordinates, side by side
  cv::Mat outline = cv::Mat::zeros(140, 120, CV_8UC1);
  std::vector<cv::Point2f> object_px;
  FloodedOutline() {
    outline(person).setTo(255);
    outline(rack).setTo(255);
    for (int y = 30; y <= 110; y += 20) object_px.emplace_back(at(30, y));
  }
  cv::Point2f at(int x, int y) const {
    return {static_cast<float>(roi_origin.x + x), static_cast<float>(roi_origin.y + y)};
  }
};

TrackedPoint static_track(cv::Point2f px, double offset_px, double multiframe_px) {
  TrackedPoint p;
  p.prev_px = p.cur_px = px;
  p.tracked = true;
  p.reprojection_px = offset_px;
  p.multiframe_px = multiframe_px;
  return p;
}

TEST(StaticCarve, CellsOfTheStaticTracksAreCarved) {
  // The boundary lies halfway between the two sets of points: the person stays whole, the rack face beyond the
  // halfway line goes.
  FloodedOutline f;
  const std::vector<cv::Point2f> static_px = {f.at(90, 40), f.at(90, 100)};
  const int kept = carve_static_cells(f.outline, f.roi_origin, f.object_px, static_px);
  EXPECT_EQ(kept, cv::countNonZero(f.outline));
  EXPECT_EQ(cv::countNonZero(f.outline(f.person)), f.person.area());
  // Columns x >= 80 (ROI) lie within 10 columns and 30 rows of a static track (squared distance <= 1000) and 50
  // columns from the object's points (>= 2500): all carved. Columns 50-54 lie 20-24 columns and <= 20 rows from an
  // object point (<= 976) and >= 36 columns from the static tracks (>= 1296): all kept.
  EXPECT_EQ(cv::countNonZero(f.outline(cv::Rect(80, 0, f.outline.cols - 80, f.outline.rows))), 0);
  EXPECT_EQ(cv::countNonZero(f.outline(cv::Rect(50, 10, 5, 120))), 5 * 120);
  EXPECT_LT(kept, f.person.area() + f.rack.area() / 2);
  // Without static tracks (or without object points) nothing is carved.
  cv::Mat untouched = cv::Mat::zeros(140, 120, CV_8UC1);
  untouched(f.rack).setTo(255);
  EXPECT_EQ(carve_static_cells(untouched, f.roi_origin, f.object_px, {}), f.rack.area());
  EXPECT_EQ(carve_static_cells(untouched, f.roi_origin, {}, static_px), f.rack.area());
}

TEST(StaticCarve, NeedsEnoughClearlyStaticTracksAwayFromTheObject) {
  const StaticCarveOptions options;
  std::vector<cv::Point2f> found;
  // One clearly static track on the rack, one that moved too much, one beside the object's points: not enough.
  FloodedOutline f;
  std::vector<TrackedPoint> points = {static_track(f.at(90, 40), 0.1, 0.4), static_track(f.at(90, 100), 0.6, 0.4),
                                      static_track(f.at(36, 50), 0.1, 0.4)};
  const int before = cv::countNonZero(f.outline);
  EXPECT_EQ(carve_static_tracks(options, points, f.object_px, f.roi_origin, f.outline, found), -1);
  EXPECT_EQ(found.size(), 1u);
  EXPECT_EQ(cv::countNonZero(f.outline), before);
  // A second clearly static track on the rack: carved. Untested tracks (multi-frame -1) never count.
  points.push_back(static_track(f.at(90, 100), 0.1, -1));
  EXPECT_EQ(carve_static_tracks(options, points, f.object_px, f.roi_origin, f.outline, found), -1);
  points.push_back(static_track(f.at(95, 110), 0.1, 0.8));
  const int kept = carve_static_tracks(options, points, f.object_px, f.roi_origin, f.outline, found);
  EXPECT_EQ(found.size(), 2u);
  EXPECT_EQ(kept, cv::countNonZero(f.outline));
  EXPECT_LT(kept, before);
  EXPECT_EQ(cv::countNonZero(f.outline(f.person)), f.person.area());
}

TEST(StaticCarve, OptionsAreValidatedUnderTheirSection) {
  StaticCarveOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.max_offset_px = -1;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "static_carve.max_offset_px");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
