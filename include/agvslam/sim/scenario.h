#pragma once
// Built-in scenarios: the camera-carrying AGV's motion plus the people and vehicles around it.
//
//   static  the loop, no people (control)
// The dynamic scenes mirror the five real scenes of paper 004 (section IV.B): the people come close in front of
// the camera and fill a large part of the view while they move (at 1.5-2.5 m a person covers ~8-15 % of the
// image; the mean share while one is in view is ~4-11 % per scene, peaks 11-20 %). Even so, the unmasked SLAM
// is barely disturbed on them (tests/bench/slam_scenarios.sh, seeds 101 102: ATE 0.4-15 mm with --dynamic off,
// unlike the paper's ORB-SLAM2 at 0.46-1.0 m).
//   scene1  AGV stationary in the staging area; a person walks in from the left 1.9-2.3 m in front (~25 %),
//           turns right of the centre 1.5-1.8 m away and stands (~45 %), walks back past the centre (~1.4 m)
//           and leaves to the left (~85 %)
//   scene2  AGV drives a 13.6 m straight aisle; one person crosses 1.6-2.4 m ahead of it
//   scene3  the same aisle; three people (one crossing 1.6-2.4 m ahead early, one standing in the aisle who
//           then walks 1.5-2.5 m ahead of the AGV, one crossing beyond that person, ~3.3-4 m ahead) and a
//           forklift that is parked, then drives across the aisle far ahead
//   scene4  AGV drives a 6.4 m x 8.8 m loop (1 m corner arcs) back to its start; one person crosses 1.6-2.4 m
//           ahead; a parked forklift (never moves)
//   scene5  the same loop; a person walks 1.5-2.4 m ahead of the AGV for the whole loop, one crosses beyond
//           them (~3.3-4 m ahead), one stands picking then walks away; another AGV is parked, then drives
//   scene6  AGV waits before a cross-aisle while a forklift crosses 1.6-2.4 m ahead and stops in front of it,
//           then drives the aisle; a person crosses ahead
//
// Scenes from warehouse operation (issue 37), where a moving object dominates the view, moves with the camera
// or was static and mapped before it moved (scenario_operations.cpp). Vehicles keep right in the main aisle
// (3.2 m between the rack faces: the AGV 0.65 m right of its centre, oncoming traffic 0.75 m left of it).
//   follow    the AGV follows a tugger train (AGV class, two 1.6 m x 1.2 m carts of goods) or a loaded forklift
//             down the main aisle at ~0.9 m/s, 2.6-3.3 m behind its rear (time headway 0.7-1.1 s plus 2.0-2.3 m);
//             the leader covers ~10-12 % of the view and moves along the epipolar lines; both stop at the end
//   crowd     the AGV drives to the zebra crossing, stops 2 m before the cross-aisle and waits 14.5-16 s while a
//             group of 5-7 people (two abreast, 1.0-1.2 m/s) crosses 1.6-2.4 m ahead, then a forklift crosses
//             the other way 1.7-2.9 m ahead; then it drives on 8 m
//   pallet    the AGV stands at the staging area facing three pallet slots 2.8 m ahead, two with loaded pallets
//             (actors of class pallet). A forklift drives in, turns on the spot, slides its forks into one of
//             them (standing in view for ~15 s), lifts it, reverses, turns and carries it out of sight; it comes
//             back reversing with another pallet, sets it down in the free slot and leaves. scenario.json lists the
//             frames at which each actor moves.
//   oncoming  the AGV drives 24-26 m down the main aisle keeping right; a loaded forklift (1.7-2.2 m/s), then a
//             tugger train or a cart AGV (1.0-1.2 m/s) come from the aisle's far end in the other lane and pass
//             it with ~0.4 m between their sides
//
// Every scenario has a nominal timeline (people 0.6-1.3 m/s, the AGV ~0.8-0.9 m/s), played at its own speed:
// `--frames N` writes its first N frames. `--squeeze-to N` plays the whole timeline over N frames instead, so
// speeds scale with default_frames / N (and --frames then cuts that). Actors are generated from (seed,
// RngStream::kActors), the warehouse from the layout seed, so the layout can be kept while people change.
// In scene1-6, actor timings are chosen so that people keep >= 1 m (vehicles >= 1.5 m) from the camera and every
// actor >= 0.5 m from the others (checked on a 50 ms grid; a warning is logged if no candidate satisfies it); the
// AGV never stops for them. In the operation scenes passing vehicles come closer (by design) and the group's
// people walk 0.6-1 m apart.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/sim/actors.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

struct ScenarioInfo {
  std::string name;
  std::string description;
  double nominal_duration_s;  // default frames = round(nominal_duration_s * rate_hz)
};

// The catalogue, in order: static, scene1 .. scene6, follow, crowd, pallet, oncoming.
const std::vector<ScenarioInfo>& scenario_catalogue();
// Throws InputError("--scenario", name, "expected one of: ...") for an unknown name.
const ScenarioInfo& find_scenario(const std::string& name);

struct ScenarioOptions {
  std::string name = "scene1";
  int frames = 0;             // frames to write: the first `frames` of the timeline (0: all of it); beyond its
                              // end the AGV and the actors stand where the timeline left them
  int squeeze_to_frames = 0;  // play the whole timeline over this many frames (0: at its own speed)
  uint64_t seed = 1;          // actors (and, by default, the layout)
  std::optional<uint64_t> layout_seed;  // warehouse layout and textures (default: seed)
  double start_offset_m = 0;            // AGV start along its route (loop: any value, wraps; line: [0, 3] m)

  uint64_t effective_layout_seed() const { return layout_seed ? *layout_seed : seed; }
  // Throws InputError naming the option for negative frame counts, a bad start offset, ...
  void validate(const WarehouseLayout& layout) const;
};

// A path of straight lines and circular arcs (tangent-continuous), parameterised by arc length.
class RoutePath {
 public:
  void add_line(double x0, double y0, double x1, double y1);
  // Arc around (cx, cy) from angle a0_rad sweeping sweep_rad (positive: counter-clockwise).
  void add_arc(double cx, double cy, double radius, double a0_rad, double sweep_rad);
  void set_closed(bool closed) { closed_ = closed; }
  bool closed() const { return closed_; }
  double length() const { return length_; }
  // Position and heading (direction of travel, radians from +x) at arc length s (wrapped when closed,
  // clamped otherwise).
  void sample(double s, double& x, double& y, double& heading_rad) const;

 private:
  struct Piece {
    bool arc;
    double x0, y0, x1, y1;        // line
    double cx, cy, r, a0, sweep;  // arc
    double s0, len;
  };
  std::vector<Piece> pieces_;
  double length_ = 0;
  bool closed_ = false;
};

// Trapezoidal speed profile: rest for hold_start_s, accelerate, cruise, decelerate, rest for hold_end_s. With
// stop_at_m >= 0 it drives two such trapezoids with the same cruise speed, standing for stop_s at stop_at_m
// between them (an AGV waiting at a crossing).
struct SpeedProfile {
  double distance_m = 0;
  double duration_s = 1;
  double hold_start_s = 0.5, hold_end_s = 0.5;
  double accel_mps2 = 0.4;
  double stop_at_m = -1;  // < 0: no stop on the way
  double stop_s = 0;
  double cruise_mps = 0;  // derived by solve()
  void solve();
  double distance_at(double t_s) const;
  double speed_at(double t_s) const;
  // With a stop on the way: when the AGV arrives there and when it drives on (scenario time, s).
  double stop_begin_s() const;
  double stop_end_s() const { return stop_begin_s() + stop_s; }
};

struct AgvMotion {
  bool stationary = true;
  double x = 0, y = 0, yaw_rad = 0;  // when stationary
  RoutePath route;
  double s_start = 0;  // arc length where it starts
  SpeedProfile profile;
  // Planar pose (map frame) at scenario time t_s; s_out = arc length travelled from the start.
  void planar_pose(double t_s, double& x_out, double& y_out, double& yaw_out, double& s_out) const;
};

struct Scenario {
  std::string name, description;
  uint64_t seed = 1, layout_seed = 1;
  double start_offset_m = 0;
  int frames = 1;           // frames written
  int timeline_frames = 1;  // frames the whole timeline is played over (the scenario's own: its default)
  double rate_hz = 20;
  double nominal_duration_s = 20;  // scenario timeline length
  double time_scale = 1;           // real seconds per scenario second = timeline_frames / rate / nominal duration
  AgvMotion agv;
  std::vector<Actor> actors;
  double min_camera_clearance_m = 1e9;  // smallest actor-to-camera distance over the timeline (surface)
  double min_actor_clearance_m = 1e9;   // smallest distance between two actors

  // Scenario time of frame k.
  double scenario_time(int frame) const { return (frame / rate_hz) / time_scale; }
  // Cruise speed of the AGV in real time (m/s).
  double agv_speed_mps() const { return agv.stationary ? 0.0 : agv.profile.cruise_mps / time_scale; }
  double agv_path_length_m() const { return agv.stationary ? 0.0 : agv.profile.distance_m; }
};

// Builds a scenario (validates the options first). rate_hz: the camera rate.
Scenario make_scenario(const ScenarioOptions& options, const Warehouse& warehouse, double rate_hz);

// Clearance circles of an actor in a state (x, y, radius), for collision checks.
struct Circle {
  double x, y, r;
};
std::vector<Circle> actor_footprint(const Actor& actor, const ActorState& state);
// True when one of the two carries the other at times (their footprints overlap then by design).
bool carries(const Actor& a, const Actor& b);

}  // namespace agvslam::sim
