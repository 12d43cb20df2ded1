// Boundary labelling (paper 004, eqs. 9-11) on constructed superpixel pairs with synthetic disparity.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/boundary.h"

namespace agvslam::dynamic {
namespace {

// Two superpixels side by side in a 40x20 ROI at `origin`: label 0 = x < 20, label 1 = x >= 20 (or swapped).
struct Pair {
  cv::Mat labels = cv::Mat(20, 40, CV_32SC1, cv::Scalar(0));
  cv::Mat disparity = cv::Mat(20, 40, CV_32FC1, cv::Scalar(0));
  cv::Point origin{200, 100};
  explicit Pair(bool swap = false) {
    labels(cv::Rect(20, 0, 20, 20)).setTo(1);
    if (swap) labels = 1 - labels;
  }
  template <typename F>
  void fill(F disparity_of_global_xy) {
    for (int y = 0; y < 20; ++y) {
      for (int x = 0; x < 40; ++x)
        disparity.at<float>(y, x) = static_cast<float>(disparity_of_global_xy(x + origin.x, y + origin.y, x < 20));
    }
  }
  SuperpixelBoundary label() const {
    std::vector<DisparityPlane> planes;
    fit_superpixel_planes(labels, 2, disparity, origin, PlaneFitConfig{}, planes);
    SuperpixelGraph g;
    g.build(labels, 2, origin);
    label_boundaries(g, planes, BoundaryConfig{});
    EXPECT_EQ(g.boundaries().size(), 1u);
    EXPECT_EQ(g.boundaries()[0].length, 20);
    return g.boundaries()[0];
  }
};

TEST(BoundaryLabel, SamePlaneIsCoplanar) {
  Pair p;
  p.fill([](double x, double y, bool) { return 30.0 - 0.05 * x + 0.02 * y; });
  EXPECT_EQ(p.label().type, BoundaryType::kCoplanar);
}

TEST(BoundaryLabel, TwoPlanesMeetingAtTheBoundaryAreAHinge) {
  // A crease at global x = 219.5 (the boundary between columns 19 and 20 of the ROI): slopes +0.4 / -0.4.
  Pair p;
  p.fill([](double x, double, bool left) { return left ? 20.0 + 0.4 * (x - 219.5) : 20.0 - 0.4 * (x - 219.5); });
  const SuperpixelBoundary b = p.label();
  EXPECT_EQ(b.type, BoundaryType::kHinge);
  EXPECT_LT(b.energy[1], b.energy[0]);  // hinge beats coplanar
  EXPECT_NEAR(b.energy[1], BoundaryConfig{}.lambda_hinge, 1e-3);
}

TEST(BoundaryLabel, NearerPlaneOccludesAccordingToTheIndexOrder) {
  // Label 0 (left) front-parallel at d = 25, label 1 (right) at d = 10: the small index is in front -> lo.
  Pair p;
  p.fill([](double, double, bool left) { return left ? 25.0 : 10.0; });
  SuperpixelBoundary b = p.label();
  EXPECT_EQ(b.type, BoundaryType::kLeftOcclusion);
  EXPECT_NEAR(b.energy[2], BoundaryConfig{}.lambda_occ, 1e-9);
  EXPECT_NEAR(b.energy[3], BoundaryConfig{}.lambda_occ + BoundaryConfig{}.lambda_pen, 1e-9);
  EXPECT_NEAR(b.energy[0], 225.0, 1e-3);  // (25 - 10)^2
  // The same geometry with the labels swapped (label 1 now on the left, in front) -> ro.
  Pair q(true);
  q.fill([](double, double, bool left) { return left ? 25.0 : 10.0; });
  EXPECT_EQ(q.label().type, BoundaryType::kRightOcclusion);
  // Background on the left, front on the right, labels as first: label 1 in front -> ro.
  Pair r;
  r.fill([](double, double, bool left) { return left ? 10.0 : 25.0; });
  EXPECT_EQ(r.label().type, BoundaryType::kRightOcclusion);
}

TEST(BoundaryLabel, SmallStepIsNotAnOcclusion) {
  // A 0.5 px step is below sqrt(lambda_occ): coplanar (0.25 + 0) beats occlusion (2.0).
  Pair p;
  p.fill([](double, double, bool left) { return left ? 15.5 : 15.0; });
  EXPECT_EQ(p.label().type, BoundaryType::kCoplanar);
}

TEST(BoundaryLabel, MissingPlaneIsUnknown) {
  Pair p;
  p.fill([](double, double, bool left) { return left ? 20.0 : 0.0; });  // right half without disparity
  EXPECT_EQ(p.label().type, BoundaryType::kUnknown);
}

TEST(BoundaryEnergy, MatchesTheDefinitionsOnExplicitSets) {
  DisparityPlane pi, pj;
  pi.a = 0.1;
  pi.b = -0.2;
  pi.c = 12;
  pi.valid = true;
  pj.a = -0.05;
  pj.b = 0.1;
  pj.c = 9;
  pj.valid = true;
  PixelMoments boundary, uni;
  double sum_b = 0, sq_b = 0, sq_u = 0;
  std::vector<cv::Point2d> bpts, upts;
  for (int i = 0; i < 15; ++i) bpts.emplace_back(30.5, 10.0 + i);
  for (int y = 10; y < 25; ++y) {
    for (int x = 20; x < 40; ++x) upts.emplace_back(x, y);
  }
  for (const auto& p : bpts) {
    boundary.add(p.x, p.y);
    const double diff = pi.disparity_at(p.x, p.y) - pj.disparity_at(p.x, p.y);
    sum_b += diff;
    sq_b += diff * diff;
  }
  for (const auto& p : upts) {
    uni.add(p.x, p.y);
    const double diff = pi.disparity_at(p.x, p.y) - pj.disparity_at(p.x, p.y);
    sq_u += diff * diff;
  }
  const BoundaryConfig cfg;
  EXPECT_NEAR(boundary_energy(BoundaryType::kCoplanar, pi, pj, boundary, uni, cfg),
              sq_u / static_cast<double>(upts.size()), 1e-9);
  EXPECT_NEAR(boundary_energy(BoundaryType::kHinge, pi, pj, boundary, uni, cfg),
              sq_b / static_cast<double>(bpts.size()) + cfg.lambda_hinge, 1e-9);
  ASSERT_NE(sum_b, 0.0);
  const double lo = boundary_energy(BoundaryType::kLeftOcclusion, pi, pj, boundary, uni, cfg);
  const double ro = boundary_energy(BoundaryType::kRightOcclusion, pi, pj, boundary, uni, cfg);
  EXPECT_DOUBLE_EQ(lo, cfg.lambda_occ + (sum_b < 0 ? cfg.lambda_pen : 0.0));
  EXPECT_DOUBLE_EQ(ro, cfg.lambda_occ + (sum_b > 0 ? cfg.lambda_pen : 0.0));
}

TEST(BoundaryConfig, LambdaOrderIsEnforced) {
  BoundaryConfig c;
  c.lambda_occ = 0.3;  // below lambda_hinge
  try {
    c.validate("p.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "boundaries.lambda_occ");
  }
}

TEST(SuperpixelGraph, AdjacencyAndMoments) {
  // 3x3 grid of 10x10 superpixels at origin (5, 7).
  cv::Mat labels(30, 30, CV_32SC1);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 30; ++x) labels.at<int32_t>(y, x) = (y / 10) * 3 + x / 10;
  }
  SuperpixelGraph g;
  g.build(labels, 9, cv::Point(5, 7));
  EXPECT_EQ(g.count(), 9);
  EXPECT_EQ(g.boundaries().size(), 12u);  // 4-adjacency of a 3x3 grid
  EXPECT_GE(g.find(0, 1), 0);
  EXPECT_EQ(g.find(1, 0), g.find(0, 1));
  EXPECT_EQ(g.find(0, 4), -1);  // diagonal: not 4-adjacent
  EXPECT_EQ(g.neighbours(4).size(), 4u);
  EXPECT_EQ(g.region(4).n, 100);
  EXPECT_NEAR(g.region(4).centroid().x, 5 + 14.5, 1e-9);
  EXPECT_NEAR(g.region(4).centroid().y, 7 + 14.5, 1e-9);
  EXPECT_EQ(g.bounding_box(4), cv::Rect(15, 17, 10, 10));
  const int b01 = g.find(0, 1);
  EXPECT_EQ(g.boundaries()[static_cast<std::size_t>(b01)].length, 10);
  EXPECT_NEAR(g.boundary_points(b01).centroid().x, 5 + 9.5, 1e-9);  // midpoints between columns 9 and 10
}

}  // namespace
}  // namespace agvslam::dynamic
