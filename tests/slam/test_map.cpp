// Map, keyframes and map points: covisibility, spanning tree, culling, replacement, and that removed objects are
// freed.
#include <gtest/gtest.h>

#include "agvslam/slam/map.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

// Keyframes on a path with one map point per world point (created at its first sighting, observed by every
// keyframe that sees it).
struct SmallMap {
  Map map;
  FrameGeometryPtr geometry = test::test_geometry();
  test::World world = test::make_world(600, 21);
  std::vector<KeyFramePtr> kfs;
  std::vector<MapPointPtr> point_of_world;

  explicit SmallMap(int n_keyframes, int step = 2) {
    point_of_world.resize(world.points_w.size());
    std::lock_guard<std::mutex> lock(map.mutex());
    for (int k = 0; k < n_keyframes; ++k) {
      Frame f;
      std::vector<int> pok;
      test::make_frame(world, test::path_pose(k * step), geometry, static_cast<uint64_t>(k), 0.0,
                       1u + static_cast<uint32_t>(k), f, pok);
      auto kf = std::make_shared<KeyFrame>(map.new_keyframe_id(), f);
      map.add_keyframe(kf);
      for (std::size_t i = 0; i < pok.size(); ++i) {
        MapPointPtr& p = point_of_world[static_cast<std::size_t>(pok[i])];
        if (!p) {
          p = std::make_shared<MapPoint>(map.new_map_point_id(), world.points_w[static_cast<std::size_t>(pok[i])],
                                         kf.get(), f.id);
          map.add_map_point(p);
        }
        kf->add_map_point(p, i);
        p->add_observation(kf.get(), static_cast<int>(i));
      }
      for (std::size_t i = 0; i < pok.size(); ++i) {
        const MapPointPtr& p = point_of_world[static_cast<std::size_t>(pok[i])];
        p->compute_distinctive_descriptor();
        p->update_normal_and_depth();
      }
      kf->update_connections();
      kfs.push_back(kf);
    }
  }
  int shared(const KeyFrame& a, const KeyFrame& b) const {
    int n = 0;
    for (const MapPointPtr& p : a.map_points()) {
      if (p && !p->bad() && p->is_in(&b)) ++n;
    }
    return n;
  }
};

TEST(Map, CovisibilityWeightsAreSharedPointCounts) {
  SmallMap m(4);
  std::lock_guard<std::mutex> lock(m.map.mutex());
  for (const auto& a : m.kfs) {
    for (const auto& b : m.kfs) {
      if (a == b) continue;
      const int shared = m.shared(*a, *b);
      if (shared >= 15) {
        EXPECT_EQ(a->weight(b.get()), shared) << a->id << "-" << b->id;
      }
    }
    // Best first.
    const auto& cov = a->covisibles();
    for (std::size_t k = 1; k < cov.size(); ++k) EXPECT_GE(a->weight(cov[k - 1]), a->weight(cov[k]));
  }
  EXPECT_EQ(m.map.keyframe_count(), 4u);
  EXPECT_EQ(m.map.origin_keyframe_id(), m.kfs[0]->id);
  EXPECT_TRUE(m.kfs[0]->is_origin());
}

TEST(Map, SpanningTreeParentIsTheStrongestEarlierNeighbour) {
  SmallMap m(4);
  std::lock_guard<std::mutex> lock(m.map.mutex());
  EXPECT_EQ(m.kfs[0]->parent(), nullptr);
  for (std::size_t k = 1; k < m.kfs.size(); ++k) {
    ASSERT_NE(m.kfs[k]->parent(), nullptr);
    EXPECT_LT(m.kfs[k]->parent()->id, m.kfs[k]->id);
    const auto& ch = m.kfs[k]->parent()->children();
    EXPECT_NE(std::find(ch.begin(), ch.end(), m.kfs[k].get()), ch.end());
  }
}

TEST(Map, KeyframeCullingReattachesChildrenAndFreesTheKeyframe) {
  SmallMap m(5, 1);
  std::weak_ptr<KeyFrame> weak;
  {
    std::lock_guard<std::mutex> lock(m.map.mutex());
    KeyFrame* victim = m.kfs[2].get();
    weak = m.kfs[2];
    const std::size_t points_before = m.map.map_point_count();
    std::vector<MapPointPtr> seen_by_victim;
    for (const MapPointPtr& p : victim->map_points()) {
      if (p) seen_by_victim.push_back(p);
    }
    victim->set_bad(m.map);
    EXPECT_TRUE(victim->bad());
    EXPECT_EQ(m.map.keyframe_count(), 4u);
    for (const auto& kf : m.kfs) {
      if (kf.get() == victim) continue;
      EXPECT_NE(kf->parent(), victim);
      EXPECT_EQ(kf->weight(victim), 0);
      if (!kf->is_origin()) {
        EXPECT_NE(kf->parent(), nullptr);
      }
      for (const MapPointPtr& p : kf->map_points()) {
        if (p) {
          EXPECT_FALSE(p->is_in(victim));
        }
      }
    }
    // Points seen only by the victim and one other stereo keyframe (4 views -> 2) went bad and left the map.
    int gone = 0;
    for (const MapPointPtr& p : seen_by_victim) {
      EXPECT_FALSE(p->is_in(victim));
      if (p->bad()) {
        ++gone;
        EXPECT_EQ(m.map.map_point(p->id), nullptr);
      } else {
        EXPECT_GT(p->observation_count(), 2);
      }
    }
    EXPECT_EQ(m.map.map_point_count(), points_before - static_cast<std::size_t>(gone));
    // The origin cannot be culled.
    m.kfs[0]->set_bad(m.map);
    EXPECT_FALSE(m.kfs[0]->bad());
  }
  m.kfs[2].reset();
  EXPECT_TRUE(weak.expired()) << "a culled keyframe must be freed once nothing holds it";
}

TEST(Map, MapPointBadWhenTwoViewsOrFewerRemain) {
  SmallMap m(2, 1);
  std::lock_guard<std::mutex> lock(m.map.mutex());
  // A point seen by both keyframes with stereo: 4 views.
  MapPointPtr p;
  for (const MapPointPtr& q : m.kfs[1]->map_points()) {
    if (q && q->observations().size() == 2) {
      p = q;
      break;
    }
  }
  ASSERT_TRUE(p);
  EXPECT_EQ(p->observation_count(), 4);
  const std::size_t before = m.map.map_point_count();
  p->erase_observation(m.kfs[1].get(), m.map);
  EXPECT_TRUE(p->bad());
  EXPECT_EQ(m.map.map_point_count(), before - 1);
  EXPECT_FALSE(p->is_in(m.kfs[0].get()));
  for (const MapPointPtr& q : m.kfs[0]->map_points()) EXPECT_NE(q, p);
}

TEST(Map, ReplaceMovesObservationsToTheSurvivor) {
  SmallMap m(3, 1);
  std::lock_guard<std::mutex> lock(m.map.mutex());
  // Duplicate a point seen in keyframe 2 by a new point observed only there, then fuse it back.
  std::size_t idx = 0;
  MapPointPtr original;
  for (std::size_t i = 0; i < m.kfs[2]->size(); ++i) {
    const MapPointPtr& q = m.kfs[2]->map_point(i);
    if (q && q->observations().size() == 3) {
      idx = i;
      original = q;
      break;
    }
  }
  ASSERT_TRUE(original);
  original->erase_observation(m.kfs[2].get(), m.map);
  ASSERT_FALSE(original->bad());
  auto dup = std::make_shared<MapPoint>(m.map.new_map_point_id(), original->p_w, m.kfs[2].get(), 2);
  m.map.add_map_point(dup);
  m.kfs[2]->add_map_point(dup, idx);
  dup->add_observation(m.kfs[2].get(), static_cast<int>(idx));
  dup->replace(original, m.map);
  EXPECT_TRUE(dup->bad());
  EXPECT_EQ(dup->replaced(), original);
  EXPECT_EQ(m.kfs[2]->map_point(idx), original);
  EXPECT_EQ(original->index_in(m.kfs[2].get()), static_cast<int>(idx));
  EXPECT_EQ(m.map.map_point(dup->id), nullptr);
}

TEST(Map, DistinctiveDescriptorIsTheMedianOne) {
  SmallMap m(3, 1);
  std::lock_guard<std::mutex> lock(m.map.mutex());
  for (const MapPointPtr& p : m.map.map_points()) {
    // All observations of a synthetic point carry the same descriptor.
    const Observation& o = p->observations().front();
    EXPECT_EQ(hamming_distance(p->descriptor.data(), o.keyframe->descriptor(static_cast<std::size_t>(o.index))), 0);
    EXPECT_GT(p->max_distance_m, p->min_distance_m);
    EXPECT_NEAR(p->normal_w.norm(), 1.0, 1e-9);
  }
}

TEST(Map, ClearFreesEverything) {
  std::vector<std::weak_ptr<KeyFrame>> kfs;
  std::vector<std::weak_ptr<MapPoint>> points;
  {
    SmallMap m(4);
    for (const auto& kf : m.kfs) kfs.push_back(kf);
    for (const auto& p : m.point_of_world) {
      if (p) points.push_back(p);
    }
    m.kfs.clear();
    m.point_of_world.clear();
    std::lock_guard<std::mutex> lock(m.map.mutex());
    EXPECT_GT(m.map.counts().memory_bytes, 0u);
    m.map.clear();
    EXPECT_EQ(m.map.keyframe_count(), 0u);
    EXPECT_EQ(m.map.map_point_count(), 0u);
  }
  for (const auto& w : kfs) EXPECT_TRUE(w.expired());
  for (const auto& w : points) EXPECT_TRUE(w.expired());
}

TEST(FeatureGrid, FindsExactlyThePointsInTheSquare) {
  const FrameGeometryPtr g = test::test_geometry();
  const test::World world = test::make_world(800, 5);
  Frame f;
  std::vector<int> pok;
  test::make_frame(world, SE3d::Identity(), g, 0, 0.0, 1, f, pok);
  std::vector<int> found;
  for (float r : {3.f, 15.f, 60.f}) {
    for (const cv::Point2f c : {cv::Point2f(10, 10), cv::Point2f(376, 240), cv::Point2f(740, 470)}) {
      f.grid.features_in_area(f.keypoints, *g, c.x, c.y, r, 0, -1, found);
      std::size_t expected = 0;
      for (const auto& kp : f.keypoints) {
        if (std::fabs(kp.pt.x - c.x) < r && std::fabs(kp.pt.y - c.y) < r) ++expected;
      }
      EXPECT_EQ(found.size(), expected) << "r " << r << " at " << c;
    }
  }
}

TEST(FrameGeometry, PredictScaleLevel) {
  const FrameGeometryPtr g = test::test_geometry();
  EXPECT_EQ(g->predict_scale_level(10.0, 10.0), 0);
  EXPECT_EQ(g->predict_scale_level(10.0 / 1.2, 10.0), 1);
  EXPECT_EQ(g->predict_scale_level(0.01, 10.0), 7);
  EXPECT_EQ(g->predict_scale_level(100.0, 10.0), 0);
  EXPECT_NEAR(g->close_depth_m, 40 * 0.12, 1e-12);
}

}  // namespace
}  // namespace agvslam::slam
