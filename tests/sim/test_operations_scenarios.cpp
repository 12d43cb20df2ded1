// The scenarios from warehouse operation (follow, crowd, pallet, oncoming): what each must contain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "agvslam/sim/semantic_classes.h"
#include "agvslam/sim/simulator.h"
#include "sim_test_util.h"

namespace agvslam::sim {
namespace {

// Quarter-size images: the tests count pixels and check geometry, not texture.
Simulator make_sim(const std::string& name, uint64_t seed) { return test::make_sim(name, seed, 0.25); }

// The camera's planar position and heading at frame k.
struct Planar {
  double x, y, yaw, s;
};
Planar camera(const Simulator& s, int k) {
  Planar p;
  s.scenario().agv.planar_pose(s.scenario().scenario_time(k), p.x, p.y, p.yaw, p.s);
  return p;
}

// The point p_map in the left camera of frame k: (forward, left) in the floor plane.
std::pair<double, double> ahead_left(const Simulator& s, int k, double x, double y) {
  const Planar c = camera(s, k);
  const double dx = x - c.x, dy = y - c.y;
  return {std::cos(c.yaw) * dx + std::sin(c.yaw) * dy, -std::sin(c.yaw) * dx + std::cos(c.yaw) * dy};
}

const Actor& actor_with_id(const Scenario& sc, int id) {
  for (const Actor& a : sc.actors)
    if (a.id == id) return a;
  throw std::runtime_error("no actor " + std::to_string(id));
}

// Share of the image covered by actor `id` (its instance pixels) in a rendered frame.
double share_of(const SimFrame& f, int id) {
  return cv::countNonZero(f.instances == id) / static_cast<double>(f.instances.total());
}

TEST(Follow, TheLeaderStaysTwoToFourMetresAheadAndFillsMuchOfTheView) {
  for (uint64_t seed : {1u, 2u, 3u, 101u, 102u, 103u}) {
    const Simulator s = make_sim("follow", seed);
    const Scenario& sc = s.scenario();
    ASSERT_EQ(sc.actors.size(), 1u);
    const Actor& leader = sc.actors[0];
    ASSERT_TRUE(leader.cls == ActorClass::kAgv || leader.cls == ActorClass::kForklift);
    // The leader's rear: a tugger's last cart, a forklift's counterweight.
    const double rear_m =
        leader.vehicle.tugger_carts > 0 ? trailer_offset_m(leader.vehicle.tugger_carts - 1) + 0.8 : 1.18;
    int both_moving = 0;
    double gap_min = 1e9, gap_max = 0, lateral_max = 0;
    for (int k = 0; k < s.frame_count(); ++k) {
      const ActorState st = actor_state(leader, sc.scenario_time(k));
      const auto [ahead, left] = ahead_left(s, k, st.x, st.y);
      const double gap = ahead - rear_m;
      gap_min = std::min(gap_min, gap);
      lateral_max = std::max(lateral_max, std::fabs(left));
      const bool agv_moving = sc.agv.profile.speed_at(sc.scenario_time(k)) > 0.3;
      if (agv_moving && st.moving) {
        ++both_moving;
        gap_max = std::max(gap_max, gap);
      }
    }
    EXPECT_GT(both_moving, 20 * 20) << "seed " << seed << ": they drive together for > 20 s";
    EXPECT_GE(gap_min, 2.0) << "seed " << seed;
    EXPECT_LE(gap_max, 4.0) << "seed " << seed;
    EXPECT_LT(lateral_max, 1e-6) << "seed " << seed << ": the same lane";
    // Rendered every 20 frames while both drive: the leader covers a large share of the view.
    SimFrame f;
    double share_sum = 0, share_min = 1;
    int rendered = 0;
    for (int k = 0; k < s.frame_count(); k += 20) {
      const double t = sc.scenario_time(k);
      if (sc.agv.profile.speed_at(t) < 0.3 || !actor_state(leader, t).moving) continue;
      s.render_frame(k, f, 2);
      const double share = share_of(f, leader.id);
      share_sum += share;
      share_min = std::min(share_min, share);
      ++rendered;
    }
    ASSERT_GT(rendered, 10);
    std::printf("follow seed %d (%s): gap %.2f-%.2f m, leader covers %.1f %% of the view on average, >= %.1f %%\n",
                static_cast<int>(seed), to_string(leader.cls).c_str(), gap_min, gap_max, 100 * share_sum / rendered,
                100 * share_min);
    EXPECT_GE(share_sum / rendered, 0.08) << "seed " << seed;
    EXPECT_GE(share_min, 0.05) << "seed " << seed;
  }
}

TEST(Crowd, FiveOrMorePeopleAndAForkliftPassCloseWhileTheAgvWaits) {
  for (uint64_t seed : {1u, 2u, 3u, 101u, 102u, 103u}) {
    const Simulator s = make_sim("crowd", seed);
    const Scenario& sc = s.scenario();
    const SpeedProfile& p = sc.agv.profile;
    int people = 0, forklifts = 0;
    for (const Actor& a : sc.actors) (a.cls == ActorClass::kPerson ? people : forklifts) += 1;
    EXPECT_GE(people, 5) << "seed " << seed;
    EXPECT_EQ(forklifts, 1) << "seed " << seed;
    EXPECT_GE(p.stop_s, 10.0);
    // Every actor passes 1-3 m in front of the camera, moving, while the AGV stands; nobody is closer than that
    // (or within 1 m of the camera's body surface) at any time; people keep 0.55 m apart.
    int frames_with_close_movers = 0;
    for (const Actor& a : sc.actors) {
      double closest = 1e9, closest_t = -1;
      for (int k = 0; k < s.frame_count(); ++k) {
        const double t = sc.scenario_time(k);
        const ActorState st = actor_state(a, t);
        for (const Circle& c : actor_footprint(a, st)) {
          const auto [ahead, left] = ahead_left(s, k, c.x, c.y);
          const double d = std::hypot(ahead, left) - (a.cls == ActorClass::kPerson ? 0.0 : c.r);
          if (d < closest) {
            closest = d;
            closest_t = t;
          }
        }
      }
      EXPECT_GE(closest, 1.0) << "seed " << seed << " actor " << a.id;
      EXPECT_LE(closest, 3.0) << "seed " << seed << " actor " << a.id;
      EXPECT_GT(closest_t, p.stop_begin_s()) << "seed " << seed << " actor " << a.id << ": while the AGV waits";
      EXPECT_LT(closest_t, p.stop_end_s()) << "seed " << seed << " actor " << a.id << ": while the AGV waits";
    }
    for (int k = 0; k < s.frame_count(); ++k) {
      const double t = sc.scenario_time(k);
      int close = 0;
      for (std::size_t i = 0; i < sc.actors.size(); ++i) {
        const ActorState si = actor_state(sc.actors[i], t);
        const auto [ahead, left] = ahead_left(s, k, si.x, si.y);
        if (si.moving && ahead > 0.5 && std::hypot(ahead, left) < 3.6) ++close;
        for (std::size_t j = i + 1; j < sc.actors.size(); ++j) {
          if (sc.actors[i].cls != ActorClass::kPerson || sc.actors[j].cls != ActorClass::kPerson) continue;
          const ActorState sj = actor_state(sc.actors[j], t);
          EXPECT_GE(std::hypot(si.x - sj.x, si.y - sj.y), 0.55) << "seed " << seed << " t " << t;
        }
      }
      if (close > 0) ++frames_with_close_movers;
    }
    EXPECT_GE(frames_with_close_movers, 8 * 20) << "seed " << seed << ": several seconds of people and forklift";
  }
}

TEST(Pallet, TheMappedPalletStandsThenMovesAndLeavesAnotherIsSetDown) {
  for (uint64_t seed : {1u, 2u, 101u}) {
    const Simulator s = make_sim("pallet", seed);
    const Scenario& sc = s.scenario();
    ASSERT_TRUE(sc.agv.stationary);
    const Actor& forklift = actor_with_id(sc, 1);
    const Actor& picked = actor_with_id(sc, 2);
    const Actor& stays = actor_with_id(sc, 3);
    const Actor& brought = actor_with_id(sc, 4);
    EXPECT_EQ(forklift.cls, ActorClass::kForklift);
    for (const Actor* a : {&picked, &stays, &brought}) {
      EXPECT_EQ(a->cls, ActorClass::kPallet);
      EXPECT_EQ(a->carrier_id, 1);
    }
    // The picked pallet stands still in view for >= 8 s, then moves (lifted, carried) and leaves the view.
    const auto picked_moving = s.moving_frames(picked);
    ASSERT_FALSE(picked_moving.empty());
    const int first_move = picked_moving.front().first;
    EXPECT_GE(first_move, 8 * 20) << "seed " << seed;
    EXPECT_TRUE(s.moving_frames(stays).empty());
    const auto brought_moving = s.moving_frames(brought);
    ASSERT_FALSE(brought_moving.empty());
    const int last_move = brought_moving.back().second;
    EXPECT_LT(last_move, s.frame_count() - 3 * 20) << "seed " << seed << ": set down >= 3 s before the end";
    // Rendered: the picked pallet is seen standing (not in the mask), then moving (in the mask), then is gone;
    // the brought one ends standing in view. Its pixels are pallet/box.
    SimFrame f;
    s.render_frame(first_move - 40, f, 2);
    EXPECT_GT(share_of(f, picked.id), 0.02) << "seed " << seed;
    EXPECT_EQ(cv::countNonZero((f.instances == picked.id) & (f.mask > 0)), 0);
    EXPECT_EQ(cv::countNonZero((f.instances == picked.id) & (f.classes != static_cast<int>(SemanticClass::kPalletBox))),
              0);
    s.render_frame(first_move + 20, f, 2);
    EXPECT_GT(cv::countNonZero((f.instances == picked.id) & (f.mask > 0)), 0) << "seed " << seed << ": lifted";
    s.render_frame(s.frame_count() - 1, f, 2);
    EXPECT_EQ(share_of(f, picked.id), 0.0) << "seed " << seed << ": carried away";
    EXPECT_GT(share_of(f, brought.id), 0.02) << "seed " << seed;
    EXPECT_EQ(cv::countNonZero(f.mask), 0) << "seed " << seed << ": everything stands at the end";
    // While it moves, the picked pallet rides on the forks: never further than 2 m from the forklift.
    for (int k = first_move; k <= picked_moving.front().second; k += 5) {
      const double t = sc.scenario_time(k);
      const ActorState p = actor_state(picked, t), fl = actor_state(forklift, t);
      EXPECT_LT(std::hypot(p.x - fl.x, p.y - fl.y), 2.0) << "seed " << seed << " frame " << k;
    }
    // The forklift is out of view at the start and at the end.
    for (int k : {0, s.frame_count() - 1}) {
      s.render_frame(k, f, 2);
      EXPECT_EQ(share_of(f, forklift.id), 0.0) << "seed " << seed << " frame " << k;
    }
  }
}

TEST(Oncoming, VehiclesComeFromFarAheadInTheOtherLaneAndPassTheAgv) {
  for (uint64_t seed : {1u, 2u, 3u, 101u, 102u, 103u}) {
    const Simulator s = make_sim("oncoming", seed);
    const Scenario& sc = s.scenario();
    ASSERT_EQ(sc.actors.size(), 2u);
    EXPECT_EQ(sc.actors[0].cls, ActorClass::kForklift);
    EXPECT_EQ(sc.actors[1].cls, ActorClass::kAgv);
    for (const Actor& a : sc.actors) {
      double ahead_first = 0, gap_min = 1e9;
      int passed_at = -1;
      bool agv_moving_when_passed = false;
      for (int k = 0; k < s.frame_count(); ++k) {
        const double t = sc.scenario_time(k);
        const ActorState st = actor_state(a, t);
        const auto [ahead, left] = ahead_left(s, k, st.x, st.y);
        if (k == 0) ahead_first = ahead;
        // The other lane: 1.4 m to the left; its side (0.6 m) clears the AGV's (0.4 m).
        EXPECT_NEAR(left, 1.4, 1e-6);
        gap_min = std::min(gap_min, left - 0.6 - 0.4);
        if (passed_at < 0 && ahead < 0) {
          passed_at = k;
          agv_moving_when_passed = sc.agv.profile.speed_at(t) > 0.3;
        }
      }
      EXPECT_GE(ahead_first, 12.0) << "seed " << seed << " actor " << a.id << ": comes from far ahead";
      EXPECT_GE(passed_at, 0) << "seed " << seed << " actor " << a.id << ": passes the camera";
      EXPECT_TRUE(agv_moving_when_passed) << "seed " << seed << " actor " << a.id;
      EXPECT_GE(gap_min, 0.35) << "seed " << seed;
      // It moves towards the camera for >= 3 s while within 12 m ahead (closing at 2-3 m/s).
      int approaching = 0;
      for (int k = 0; k < s.frame_count(); ++k) {
        const ActorState st = actor_state(a, sc.scenario_time(k));
        const double ahead = ahead_left(s, k, st.x, st.y).first;
        if (st.moving && ahead > 1.0 && ahead < 12.0) ++approaching;
      }
      EXPECT_GE(approaching, 3 * 20) << "seed " << seed << " actor " << a.id;
    }
  }
}

}  // namespace
}  // namespace agvslam::sim
