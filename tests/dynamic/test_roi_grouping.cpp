// Dynamic point grouping into ROIs (paper 004, eq. 4).
#include <gtest/gtest.h>

#include "agvslam/dynamic/roi_grouping.h"

namespace agvslam::dynamic {
namespace {

RoiGroupingConfig paper_config() {
  RoiGroupingConfig c;
  c.a_s_px = 30;
  c.b_s = 1.0;
  c.t_disp_px = 2.0;
  c.t_disp_rel = 0.0;  // the paper's constant T_disp
  c.margin_px = 10;
  c.margin_disparity_factor = 0.0;
  return c;
}

TEST(RoiGrouping, TwoSeparatedClustersGiveTwoRois) {
  std::vector<cv::Point2f> p;
  std::vector<float> d;
  for (int i = 0; i < 6; ++i) {  // cluster A around (100, 100), d = 10: spacing 20 px < T_s = 40
    p.emplace_back(100.f + 20.f * static_cast<float>(i % 3), 100.f + 20.f * static_cast<float>(i / 3));
    d.push_back(10.f);
  }
  for (int i = 0; i < 7; ++i) {  // cluster B around (500, 300), d = 20
    p.emplace_back(500.f + 25.f * static_cast<float>(i % 4), 300.f + 25.f * static_cast<float>(i / 4));
    d.push_back(20.f + 0.2f * static_cast<float>(i));
  }
  const auto groups = group_dynamic_points(p, d, cv::Size(752, 480), paper_config());
  ASSERT_EQ(groups.size(), 2u);
  // Largest first.
  EXPECT_EQ(groups[0].members.size(), 7u);
  EXPECT_EQ(groups[1].members.size(), 6u);
  EXPECT_EQ(groups[1].bounds, cv::Rect(100, 100, 41, 21));
  EXPECT_EQ(groups[1].roi, cv::Rect(90, 90, 61, 41));
  EXPECT_EQ(groups[0].bounds, cv::Rect(500, 300, 76, 26));
  EXPECT_NEAR(groups[1].mean_disparity_px, 10.0, 1e-9);
}

TEST(RoiGrouping, StackedPartsOfOneUprightObjectMergeSideBySideObjectsDoNot) {
  // Torso (3 points) and feet (3 points) of one person at d = 10, 55 px apart vertically (> T_s = 40): their
  // ROIs (margin 10) are 35 px apart, within T_s, in overlapping columns.
  std::vector<cv::Point2f> p = {{100, 100}, {115, 110}, {105, 120}, {95, 175}, {110, 180}, {120, 178}};
  std::vector<float> d(6, 10.f);
  RoiGroupingConfig cfg = paper_config();
  auto groups = group_dynamic_points(p, d, cv::Size(752, 480), cfg);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].members.size(), 6u);
  EXPECT_EQ(groups[0].bounds, cv::Rect(95, 100, 26, 81));
  cfg.merge_overlapping = false;  // the paper: two groups of three, no ROI
  EXPECT_TRUE(group_dynamic_points(p, d, cv::Size(752, 480), cfg).empty());
  // The same two groups side by side (two people walking abreast): not merged.
  cfg.merge_overlapping = true;
  std::vector<cv::Point2f> q = {{100, 100}, {110, 115}, {120, 130}, {175, 100}, {185, 115}, {195, 130}};
  std::vector<float> e(6, 10.f);
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg).empty());
  // Different depth: not merged even when stacked.
  d = {10, 10, 10, 16, 16, 16};
  EXPECT_TRUE(group_dynamic_points(p, d, cv::Size(752, 480), cfg).empty());
}

TEST(RoiGrouping, SideBySidePartsWithinTheGapMergeWhenTheBaselineIsGiven) {
  // The two groups of three side by side, ROIs (margin 10) 34 px apart at d = 10 px: with a 0.12 m baseline one
  // pixel of gap is 0.012 m at that depth, so 34 px = 0.41 m <= merge_side_gap_m (0.45): one ROI (a striding
  // person's legs); without the baseline (or with the gap set to 0) two groups of three, no ROI.
  RoiGroupingConfig cfg = paper_config();
  cfg.merge_side_gap_m = 0.45;
  std::vector<cv::Point2f> q = {{100, 100}, {110, 115}, {120, 130}, {175, 100}, {185, 115}, {195, 130}};
  std::vector<float> e(6, 10.f);
  const auto merged = group_dynamic_points(q, e, cv::Size(752, 480), cfg, 0.12);
  ASSERT_EQ(merged.size(), 1u);
  EXPECT_EQ(merged[0].members.size(), 6u);
  EXPECT_EQ(merged[0].bounds, cv::Rect(100, 100, 96, 31));
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg).empty());
  cfg.merge_side_gap_m = 0.0;
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg, 0.12).empty());
  cfg.merge_side_gap_m = 0.45;
  // 20 px further apart: 54 px = 0.65 m, two people.
  for (std::size_t i = 3; i < 6; ++i) q[i].x += 20.f;
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg, 0.12).empty());
  // Close, but at other depths (d 10 and 16): not one object.
  for (std::size_t i = 3; i < 6; ++i) q[i].x -= 20.f;
  e = {10, 10, 10, 16, 16, 16};
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg, 0.12).empty());
  // Rows not overlapping (one group well above the other, columns apart): not side by side.
  e.assign(6, 10.f);
  for (std::size_t i = 3; i < 6; ++i) q[i].y += 120.f;
  EXPECT_TRUE(group_dynamic_points(q, e, cv::Size(752, 480), cfg, 0.12).empty());
}

TEST(RoiGrouping, FourPointsAreNotAnObject) {
  std::vector<cv::Point2f> p = {{100, 100}, {110, 100}, {100, 110}, {110, 110}};
  std::vector<float> d(4, 15.f);
  EXPECT_TRUE(group_dynamic_points(p, d, cv::Size(752, 480), paper_config()).empty());
  p.emplace_back(105.f, 105.f);  // the fifth point makes it one
  d.push_back(15.f);
  EXPECT_EQ(group_dynamic_points(p, d, cv::Size(752, 480), paper_config()).size(), 1u);
}

TEST(RoiGrouping, DistanceThresholdGrowsWithDisparityAndChainsTransitively) {
  // A chain of 5 points 45 px apart: T_s = 30 + d; linked at d = 20 (T_s 50), not at d = 10 (T_s 40).
  std::vector<cv::Point2f> p;
  for (int i = 0; i < 5; ++i) p.emplace_back(100.f + 45.f * static_cast<float>(i), 200.f);
  EXPECT_EQ(group_dynamic_points(p, std::vector<float>(5, 20.f), cv::Size(752, 480), paper_config()).size(), 1u);
  EXPECT_TRUE(group_dynamic_points(p, std::vector<float>(5, 10.f), cv::Size(752, 480), paper_config()).empty());
}

TEST(RoiGrouping, DisparityGapSeparatesOverlappingObjects) {
  // Same image area, two depths: 5 points at d = 10 and 5 at d = 25 -> two groups.
  std::vector<cv::Point2f> p;
  std::vector<float> d;
  for (int i = 0; i < 10; ++i) {
    p.emplace_back(300.f + 10.f * static_cast<float>(i), 200.f + 5.f * static_cast<float>(i % 2));
    d.push_back(i % 2 ? 25.f : 10.f);
  }
  const auto groups = group_dynamic_points(p, d, cv::Size(752, 480), paper_config());
  ASSERT_EQ(groups.size(), 2u);
  for (const auto& g : groups) {
    for (int m : g.members) EXPECT_EQ(d[static_cast<std::size_t>(m)], d[static_cast<std::size_t>(g.members[0])]);
  }
  // Points without a disparity are never grouped.
  std::vector<float> none(10, 0.f);
  EXPECT_TRUE(group_dynamic_points(p, none, cv::Size(752, 480), paper_config()).empty());
}

TEST(RoiGrouping, RoiIsClippedToTheImage) {
  std::vector<cv::Point2f> p = {{2, 2}, {10, 3}, {5, 12}, {12, 12}, {3, 8}};
  std::vector<float> d(5, 30.f);
  RoiGroupingConfig c = paper_config();
  c.margin_disparity_factor = 0.5;  // margin 10 + 15
  const auto groups = group_dynamic_points(p, d, cv::Size(752, 480), c);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].roi, cv::Rect(0, 0, 13 + 25, 13 + 25));
}

}  // namespace
}  // namespace agvslam::dynamic
