// Matcher on synthetic frames with known correspondences: last-frame projection, local map projection, brute
// force against a keyframe, fusion of duplicates.
#include <gtest/gtest.h>

#include "agvslam/slam/map.h"
#include "agvslam/slam/matcher.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

struct TwoFrames {
  FrameGeometryPtr g = test::test_geometry();
  test::World world = test::make_world(2000, 31, 1.5, 15.0);
  Map map;
  Frame f0, f1;
  std::vector<int> p0, p1;
  std::vector<MapPointPtr> points;  // per world point
  explicit TwoFrames(int step = 1) {
    test::make_frame(world, test::path_pose(0), g, 0, 0.3, 1, f0, p0);
    test::make_frame(world, test::path_pose(step), g, 1, 0.3, 2, f1, p1);
    for (std::size_t i = 0; i < world.points_w.size(); ++i) {
      auto p = std::make_shared<MapPoint>(i, world.points_w[i], nullptr, 0);
      p->descriptor = world.descriptors[i];
      const double d = (world.points_w[i] - f0.center_w()).norm();
      p->normal_w = (world.points_w[i] - f0.center_w()) / d;
      p->max_distance_m = static_cast<float>(d);
      p->min_distance_m = static_cast<float>(d / 3.6);
      points.push_back(p);
    }
    for (std::size_t k = 0; k < f0.size(); ++k) f0.map_points[k] = points[static_cast<std::size_t>(p0[k])];
  }
  int correct_in_f1() const {
    int n = 0;
    for (std::size_t k = 0; k < f1.size(); ++k) {
      if (f1.map_points[k] && f1.map_points[k]->id == static_cast<uint64_t>(p1[k])) ++n;
    }
    return n;
  }
  int matched_in_f1() const {
    int n = 0;
    for (const auto& p : f1.map_points) n += p ? 1 : 0;
    return n;
  }
};

TEST(Matcher, LastFrameProjectionWithTheTruePose) {
  TwoFrames s;
  Matcher m;
  std::lock_guard<std::mutex> lock(s.map.mutex());
  const int n = m.search_last_frame(s.f1, s.f0, 7.0f, true);
  EXPECT_EQ(n, s.matched_in_f1());
  EXPECT_GT(n, static_cast<int>(s.f1.size()) * 8 / 10);
  EXPECT_EQ(s.correct_in_f1(), n);
}

TEST(Matcher, LastFrameProjectionMissesAnUnmodelledTurnUnlessTheWindowIsWide) {
  TwoFrames s;
  // The predicted pose is off by 2.5 degrees of yaw (about 20 px): the 7 px window finds few matches, a 28 px window
  // with the ratio test finds them again.
  const SE3d truth = s.f1.T_c_w();
  s.f1.set_pose(
      make_se3(Eigen::AngleAxisd(0.044, Eigen::Vector3d::UnitY()).toRotationMatrix(), Eigen::Vector3d::Zero()) * truth);
  Matcher m;
  std::lock_guard<std::mutex> lock(s.map.mutex());
  const int narrow = m.search_last_frame(s.f1, s.f0, 7.0f, true);
  std::fill(s.f1.map_points.begin(), s.f1.map_points.end(), nullptr);
  const int wide = m.search_last_frame(s.f1, s.f0, 28.0f, true, 0.8f);
  EXPECT_LT(narrow, static_cast<int>(s.f1.size()) / 10);
  EXPECT_GT(wide, static_cast<int>(s.f1.size()) / 2);
  EXPECT_GT(s.correct_in_f1(), wide * 95 / 100);
}

TEST(Matcher, LocalMapProjection) {
  TwoFrames s;
  Matcher m;
  std::lock_guard<std::mutex> lock(s.map.mutex());
  std::vector<MapPoint*> local;
  for (const auto& p : s.points) {
    if (s.f1.is_in_frustum(*p, 0.5)) local.push_back(p.get());
  }
  const int n = m.search_local_points(s.f1, local, 1.0f);
  EXPECT_GT(n, static_cast<int>(s.f1.size()) * 8 / 10);
  EXPECT_EQ(s.correct_in_f1(), n);
}

TEST(Matcher, BruteForceAgainstAKeyframeNeedsNoPose) {
  TwoFrames s(4);
  KeyFrame kf(0, s.f0);
  Matcher m;
  std::vector<MapPointPtr> matches;
  std::lock_guard<std::mutex> lock(s.map.mutex());
  const int n = m.search_keyframe_brute_force(kf, s.f1, 0.7f, matches);
  ASSERT_EQ(matches.size(), s.f1.size());
  int correct = 0;
  for (std::size_t k = 0; k < matches.size(); ++k)
    correct += matches[k] && matches[k]->id == static_cast<uint64_t>(s.p1[k]) ? 1 : 0;
  EXPECT_GT(n, static_cast<int>(std::min(s.f0.size(), s.f1.size())) * 7 / 10);
  EXPECT_EQ(correct, n);
}

TEST(Matcher, FuseReplacesADuplicateAndAddsMissingObservations) {
  TwoFrames s;
  std::lock_guard<std::mutex> lock(s.map.mutex());
  auto kf = std::make_shared<KeyFrame>(s.map.new_keyframe_id(), s.f1);
  s.map.add_keyframe(kf);
  // Keypoint 0 of the keyframe holds a duplicate of its true point (same descriptor, a little off); keypoints 1.. hold
  // nothing. Fusing the true points must replace the duplicate and attach the rest.
  const std::size_t k0 = 0;
  const MapPointPtr truth0 = s.points[static_cast<std::size_t>(s.p1[k0])];
  auto dup = std::make_shared<MapPoint>(100000, truth0->p_w + Eigen::Vector3d(0.01, 0, 0), kf.get(), 1);
  dup->descriptor = truth0->descriptor;
  s.map.add_map_point(dup);
  kf->add_map_point(dup, k0);
  dup->add_observation(kf.get(), static_cast<int>(k0));
  dup->normal_w = truth0->normal_w;
  dup->max_distance_m = truth0->max_distance_m;
  dup->min_distance_m = truth0->min_distance_m;
  for (std::size_t k = 0; k < 3; ++k) s.map.add_map_point(s.points[static_cast<std::size_t>(s.p1[k])]);
  std::vector<MapPointPtr> candidates{truth0, s.points[static_cast<std::size_t>(s.p1[1])],
                                      s.points[static_cast<std::size_t>(s.p1[2])]};
  Matcher m;
  const int fused = m.fuse(*kf, candidates, 3.0f, s.map);
  EXPECT_EQ(fused, 3);
  EXPECT_EQ(kf->map_point(1), candidates[1]);
  EXPECT_EQ(kf->map_point(2), candidates[2]);
  EXPECT_EQ(candidates[1]->index_in(kf.get()), 1);
  // The duplicate has the keyframe's view, the candidate none: the duplicate survives at keypoint 0 (the point with
  // more views wins), the candidate is replaced by it.
  const MapPointPtr survivor = kf->map_point(k0);
  ASSERT_TRUE(survivor);
  EXPECT_EQ(survivor, dup);
  EXPECT_TRUE(truth0->bad());
  EXPECT_EQ(truth0->replaced(), dup);
}

}  // namespace
}  // namespace agvslam::slam
