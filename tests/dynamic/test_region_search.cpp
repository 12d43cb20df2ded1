// Search from dynamic points to the first occlusion boundary (paper 004, III.B) on constructed label images.
#include <gtest/gtest.h>

#include "agvslam/dynamic/region_search.h"

namespace agvslam::dynamic {
namespace {

// A 100x80 ROI at origin (50, 40) tiled by 10x10 superpixels (label = row * 10 + col). The "object" is the
// block of superpixels with cols 3..6 and rows 2..5 (ROI pixels x 30..69, y 20..59). Planes: object d = 20,
// everything else d = 8. Boundaries are labelled from the planes.
struct Grid {
  cv::Mat labels = cv::Mat(80, 100, CV_32SC1);
  cv::Point origin{50, 40};
  std::vector<DisparityPlane> planes;
  SuperpixelGraph graph;
  static bool in_object(int label) {
    const int r = label / 10, c = label % 10;
    return r >= 2 && r <= 5 && c >= 3 && c <= 6;
  }
  Grid() {
    for (int y = 0; y < 80; ++y) {
      for (int x = 0; x < 100; ++x) labels.at<int32_t>(y, x) = (y / 10) * 10 + x / 10;
    }
    planes.resize(80);
    for (int k = 0; k < 80; ++k) {
      planes[static_cast<std::size_t>(k)].valid = true;
      planes[static_cast<std::size_t>(k)].c = in_object(k) ? 20.0 : 8.0;
    }
    graph.build(labels, 80, origin);
    label_boundaries(graph, planes, BoundaryConfig{});
  }
};

TEST(RegionSearch, BoundaryTypesOfTheConstructedGrid) {
  const Grid g;
  for (const auto& b : g.graph.boundaries()) {
    const bool oi = Grid::in_object(b.i), oj = Grid::in_object(b.j);
    if (oi == oj) {
      EXPECT_EQ(b.type, BoundaryType::kCoplanar) << b.i << "-" << b.j;
    } else {
      EXPECT_EQ(b.type, oi ? BoundaryType::kLeftOcclusion : BoundaryType::kRightOcclusion) << b.i << "-" << b.j;
    }
  }
}

TEST(RegionSearch, StopsAtTheFirstOcclusionBoundary) {
  const Grid g;
  const auto stops = search_to_occlusion(g.labels, g.graph, cv::Point(45, 33), false);
  EXPECT_EQ(stops[0], cv::Point(69, 33));  // +x: last object pixel
  EXPECT_EQ(stops[1], cv::Point(30, 33));  // -x
  EXPECT_EQ(stops[2], cv::Point(45, 59));  // +y
  EXPECT_EQ(stops[3], cv::Point(45, 20));  // -y
  // From the background, the search stops at the object (an occluder) or runs to the ROI edge.
  const auto bg = search_to_occlusion(g.labels, g.graph, cv::Point(10, 33), false);
  EXPECT_EQ(bg[0], cv::Point(29, 33));
  EXPECT_EQ(bg[1], cv::Point(0, 33));
  EXPECT_EQ(bg[2], cv::Point(10, 79));
  EXPECT_EQ(bg[3], cv::Point(10, 0));
}

TEST(RegionSearch, RectangleOfAGroupIsTheObject) {
  const Grid g;
  // Three dynamic points inside the object (full-image coordinates), disparity 20.
  const std::vector<cv::Point2f> pts = {{50.f + 35, 40.f + 25}, {50.f + 62, 40.f + 50}, {50.f + 44, 40.f + 41}};
  const std::vector<float> d = {20.f, 20.2f, 19.8f};
  for (bool band : {false, true}) {
    RegionSearchConfig cfg;
    cfg.disparity_band = band;
    const DynamicRegion r = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, cfg);
    EXPECT_EQ(r.started_points, 3);
    EXPECT_EQ(r.rectangle, cv::Rect(50 + 30, 40 + 20, 40, 40));
    EXPECT_EQ(r.stop_points.size(), 12u);
    EXPECT_EQ(r.superpixels.size(), 16u);  // the flood covers exactly the object's 4x4 superpixels
    for (int k : r.superpixels) EXPECT_TRUE(Grid::in_object(k));
    cv::Mat mask(200, 200, CV_8UC1, cv::Scalar(0));
    paint_region(r, g.labels, g.origin, MaskMode::kSuperpixels, mask);
    EXPECT_EQ(cv::countNonZero(mask), 1600);
    EXPECT_EQ(cv::countNonZero(mask(r.rectangle)), 1600);
  }
}

TEST(RegionSearch, StartSuperpixelMustAgreeWithThePointDisparity) {
  const Grid g;
  RegionSearchConfig cfg;
  // On the object's left edge, a point whose own pixel is background (x = 29 in the ROI) but whose disparity
  // is the object's: the object superpixel 1 px away is chosen.
  EXPECT_EQ(choose_start_superpixel(g.labels, g.origin, g.planes, cv::Point2f(50.f + 29, 40.f + 33), 20.f, cfg), 33);
  EXPECT_EQ(choose_start_superpixel(g.labels, g.origin, g.planes, cv::Point2f(50.f + 29, 40.f + 33), 8.f, cfg), 32);
  // A disparity that matches nothing nearby: no start.
  EXPECT_EQ(choose_start_superpixel(g.labels, g.origin, g.planes, cv::Point2f(50.f + 45, 40.f + 33), 14.f, cfg), -1);
  EXPECT_EQ(choose_start_superpixel(g.labels, g.origin, g.planes, cv::Point2f(50.f + 45, 40.f + 33), 0.f, cfg), -1);
  const DynamicRegion none =
      find_dynamic_region(g.labels, g.origin, g.graph, g.planes, {cv::Point2f(95, 73)}, std::vector<float>{14.f}, cfg);
  EXPECT_EQ(none.started_points, 0);
  EXPECT_TRUE(none.rectangle.empty());
}

TEST(RegionSearch, DisparityBandHandlesAMissedOcclusionAndPlanelessSuperpixels) {
  Grid g;
  // The object's right neighbour column (col 7) has no plane (e.g. half-occluded), and the boundary between
  // object and col 8 would then be reached through "unknown" boundaries.
  for (int r = 0; r < 8; ++r) g.planes[static_cast<std::size_t>(r * 10 + 7)].valid = false;
  label_boundaries(g.graph, g.planes, BoundaryConfig{});
  const std::vector<cv::Point2f> pts = {{50.f + 45, 40.f + 33}};
  const std::vector<float> d = {20.f};
  RegionSearchConfig paper;
  paper.disparity_band = false;
  const DynamicRegion leaky = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, paper);
  EXPECT_EQ(leaky.rectangle.br().x, 50 + 100);  // crosses unknown and the coplanar background to the ROI edge
  RegionSearchConfig banded;
  const DynamicRegion tight = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, banded);
  EXPECT_EQ(tight.rectangle, cv::Rect(50 + 30, 40 + 20, 40, 40));
  // Stopping at unknown boundaries (the paper's other reading) also gives the object here.
  RegionSearchConfig stop;
  stop.disparity_band = false;
  stop.stop_at_unknown = true;
  EXPECT_EQ(find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, stop).rectangle,
            cv::Rect(50 + 30, 40 + 20, 40, 40));
}

TEST(RegionSearch, GroundVetoKeepsTheFloorUnderTheObjectOut) {
  Grid g;
  // Floor below the object (rows 6..7, full-image y 100..119): d = 0.5 y - 32.5, which is the object's
  // disparity (20) at its contact row y = 105, as for a person standing on it.
  DisparityPlane ground;
  ground.valid = true;
  ground.b = 0.5;
  ground.c = 20.0 - 0.5 * 105.0;
  for (int r = 6; r <= 7; ++r) {
    for (int c = 0; c < 10; ++c) g.planes[static_cast<std::size_t>(r * 10 + c)] = ground;
  }
  label_boundaries(g.graph, g.planes, BoundaryConfig{});
  // Points on the object and one on the floor at the contact (a foot's sole), all with d ~ 20.
  const std::vector<cv::Point2f> pts = {{50.f + 45, 40.f + 33}, {50.f + 35, 40.f + 55}, {50.f + 45, 40.f + 65}};
  const std::vector<float> d = {20.f, 20.f, 20.f};
  RegionSearchConfig no_veto;
  no_veto.ground_veto = false;
  const DynamicRegion leaky =
      find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, no_veto, {}, {}, &ground);
  EXPECT_GT(leaky.rectangle.br().y, 40 + 60);  // the floor row in the band joins
  RegionSearchConfig veto;
  const DynamicRegion tight = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, veto, {}, {}, &ground);
  EXPECT_EQ(tight.started_points, 2);  // the point on the floor cannot start
  EXPECT_EQ(tight.rectangle, cv::Rect(50 + 30, 40 + 20, 40, 40));
  EXPECT_EQ(tight.superpixels.size(), 16u);
  // A fronto-parallel plane at the floor's disparity is not floor (slope test).
  DisparityPlane upright;
  upright.valid = true;
  upright.c = 20.0;
  EXPECT_FALSE(is_ground_like(upright, ground, 80, 105, 1.0, 0.05, 0.75));
  EXPECT_TRUE(is_ground_like(ground, ground, 80, 105, 1.0, 0.05, 0.75));
}

TEST(RegionSearch, GroundPlaneFromStaticPointsWithOutliers) {
  std::vector<cv::Point2f> pts;
  std::vector<float> d;
  for (int i = 0; i < 60; ++i) {  // floor points below the horizon (y > 240): d = 0.24 (y - 240)
    const float x = 20.f + static_cast<float>((i * 137) % 700), y = 250.f + 3.f * static_cast<float>(i);
    pts.emplace_back(x, y);
    d.push_back(0.24f * (y - 240.f));
  }
  for (int i = 0; i < 25; ++i) {  // 30 % outliers: shelves at d = 6
    pts.emplace_back(30.f * static_cast<float>(i), 300.f + static_cast<float>(i));
    d.push_back(6.f);
  }
  pts.emplace_back(100.f, 100.f);  // above the horizon: ignored
  d.push_back(40.f);
  const DisparityPlane ground = fit_ground_plane(pts, d, 240.0);
  ASSERT_TRUE(ground.valid);
  EXPECT_NEAR(ground.b, 0.24, 0.01);
  EXPECT_NEAR(ground.disparity_at(300, 400), 0.24 * 160, 0.3);
  // A fronto-parallel wall only: no ground.
  std::vector<float> wall(pts.size(), 8.f);
  EXPECT_FALSE(fit_ground_plane(pts, wall, 240.0).valid);
}

TEST(RegionSearch, RegionObjectsSplitSideBySideAndKeepStackedPieces) {
  cv::Mat region(100, 120, CV_8UC1, cv::Scalar(0));
  region(cv::Rect(10, 5, 20, 40)).setTo(255);   // person A torso
  region(cv::Rect(12, 55, 18, 40)).setTo(255);  // person A legs (gap below the torso)
  region(cv::Rect(70, 10, 25, 80)).setTo(255);  // person B, side by side
  region(cv::Rect(50, 90, 2, 2)).setTo(255);    // a crumb: joins the largest
  cv::Mat instances(100, 120, CV_8UC1, cv::Scalar(0));
  EXPECT_EQ(label_region_objects(region, true, 3, instances), 5);
  EXPECT_EQ(instances.at<uint8_t>(20, 20), instances.at<uint8_t>(70, 20));  // torso and legs: one object
  EXPECT_NE(instances.at<uint8_t>(20, 20), instances.at<uint8_t>(50, 80));  // A and B: two
  EXPECT_EQ(instances.at<uint8_t>(90, 50), instances.at<uint8_t>(50, 80));  // crumb joins B (the largest)
  EXPECT_EQ(instances.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(cv::countNonZero(instances), cv::countNonZero(region));
  instances.setTo(0);
  EXPECT_EQ(label_region_objects(region, false, 3, instances), 4);
  EXPECT_EQ(instances.at<uint8_t>(20, 20), 3);
  EXPECT_EQ(instances.at<uint8_t>(50, 80), 3);
}

TEST(RegionSearch, StaticVetoKeepsStaticSuperpixelsOut) {
  Grid g;
  // A shelf at the object's depth right of it (cols 7..8, rows 2..5): no occlusion boundary separates them.
  for (int r = 2; r <= 5; ++r) {
    for (int c = 7; c <= 8; ++c) g.planes[static_cast<std::size_t>(r * 10 + c)].c = 20.0;
  }
  label_boundaries(g.graph, g.planes, BoundaryConfig{});
  const std::vector<cv::Point2f> pts = {{50.f + 45, 40.f + 33}};
  const std::vector<float> d = {20.f};
  RegionSearchConfig cfg;
  const DynamicRegion merged = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, cfg);
  EXPECT_EQ(merged.rectangle.br().x, 50 + 90);  // object and shelf together
  // Static tracked points on the shelf's superpixels (one per column of the shelf, rows 2..5).
  std::vector<cv::Point2f> statics;
  std::vector<float> static_d;
  for (int r = 2; r <= 5; ++r) {
    for (int c = 7; c <= 8; ++c) {
      statics.emplace_back(50.f + 10.f * static_cast<float>(c) + 5.f, 40.f + 10.f * static_cast<float>(r) + 5.f);
      static_d.push_back(20.f);
    }
  }
  const DynamicRegion split =
      find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, cfg, statics, static_d);
  EXPECT_EQ(split.vetoed_superpixels.size(), 8u);
  EXPECT_EQ(split.rectangle, cv::Rect(50 + 30, 40 + 20, 40, 40));
  for (int k : split.superpixels) EXPECT_TRUE(Grid::in_object(k));
  // A static point whose disparity does not fit its superpixel's plane vetoes nothing.
  const DynamicRegion ignored =
      find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, cfg, statics, std::vector<float>(8, 9.f));
  EXPECT_TRUE(ignored.vetoed_superpixels.empty());
  cfg.static_veto = false;
  EXPECT_EQ(find_dynamic_region(g.labels, g.origin, g.graph, g.planes, pts, d, cfg, statics, static_d).rectangle,
            merged.rectangle);
}

TEST(RegionSearch, RectangleModePaintsTheRectangle) {
  const Grid g;
  const DynamicRegion r = find_dynamic_region(g.labels, g.origin, g.graph, g.planes, {cv::Point2f(95, 73)},
                                              std::vector<float>{20.f}, RegionSearchConfig{});
  cv::Mat mask(200, 200, CV_8UC1, cv::Scalar(0));
  paint_region(r, g.labels, g.origin, MaskMode::kRectangle, mask);
  EXPECT_EQ(cv::countNonZero(mask), r.rectangle.area());
  EXPECT_EQ(r.rectangle, cv::Rect(80, 60, 40, 40));
}

}  // namespace
}  // namespace agvslam::dynamic
