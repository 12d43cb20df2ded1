// The scenarios from warehouse operation (issue 37): follow, crowd, pallet, oncoming (see scenario.h). Speeds,
// distances and timings are those of a warehouse floor, not tuned to any result: AGVs at ~0.9 m/s keeping right,
// forklifts at 1.5-2.2 m/s turning on the spot, groups walking at 1.0-1.2 m/s.
#include <cmath>
#include <limits>

#include "scenario_builder.h"

namespace agvslam::sim::scenario_detail {
namespace {

constexpr double kSampleS = 0.1;          // spacing of sampled waypoints, s
constexpr double kVehicleAccel = 1.0;     // m/s^2: forklifts and tuggers accelerating and braking
constexpr double kWalkAccel = 1.0;        // m/s^2: people setting off and stopping
constexpr double kForkForwardM = 1.6;     // a pallet on the forks: its centre ahead of the forklift's origin, m
constexpr double kForkTravelZ = 0.12;     // the forks' height above the floor at lift 0 (actors.cpp), m
constexpr double kForksInPalletM = 0.06;  // the forks' underside above the base of the pallet they carry, m
constexpr double kForksLowered = -0.06;   // lift of forks sliding into a pallet standing on the floor, m
constexpr double kForkliftPivotM = 0.55;  // a forklift turns on the spot about its drive axle, this far ahead, m

// Lanes of the main aisle for vehicles keeping right: the AGV's (driving +x) and the oncoming traffic's. Between
// the rack faces (3.2 m apart) a 0.8 m AGV and a 1.2 m forklift pass with ~0.4 m between them.
double ego_lane_y(const WarehouseLayout& L) { return L.line_y - 0.65; }
double oncoming_lane_y(const WarehouseLayout& L) { return L.line_y + 0.75; }

Waypoint waypoint(double t_s, double x, double y, double yaw_rad = std::numeric_limits<double>::quiet_NaN(),
                  double lift_m = 0) {
  Waypoint w;
  w.t_s = t_s;
  w.x = x;
  w.y = y;
  w.yaw_rad = yaw_rad;
  w.lift_m = lift_m;
  return w;
}

// The point `lateral` metres left of `track` at arc length s.
void track_point(const RoutePath& track, double s, double lateral, double& x, double& y) {
  double heading;
  track.sample(s, x, y, heading);
  x -= lateral * std::sin(heading);
  y += lateral * std::cos(heading);
}

// Waypoints every kSampleS over [0, t_end] of someone going along `track` from arc length s0 to s1, `lateral`
// metres left of it: standing until t_start, accelerating to `speed`, braking to a stop at s1, standing there.
std::vector<Waypoint> along_track(const RoutePath& track, double s0, double s1, double t_start, double speed,
                                  double accel, double lateral, double t_end) {
  std::vector<Waypoint> pts;
  const double d = std::max(0.0, s1 - s0);
  const double v = std::min(speed, std::sqrt(std::max(1e-9, d * accel)));  // a short trip never reaches `speed`
  const int n = static_cast<int>(std::ceil(t_end / kSampleS));
  for (int k = 0; k <= n; ++k) {
    const double t = k * kSampleS;
    const double s = s0 + (d > 0 ? trapezoid_distance(t - t_start, d, v, accel) : 0.0);
    double x, y;
    track_point(track, s, lateral, x, y);
    pts.push_back(waypoint(t, x, y));
  }
  return pts;
}

// A vehicle's motion with its heading and lift given at every waypoint, so that it can reverse, turn on the spot
// and raise its forks; sampled every kSampleS.
class VehiclePlan {
 public:
  VehiclePlan(double t_s, double x, double y, double yaw_rad, double lift_m)
      : t_(t_s), x_(x), y_(y), yaw_(yaw_rad), lift_(lift_m) {
    if (t_s > 0) push(0.0);
    push(t_s);
  }
  double t() const { return t_; }
  double x() const { return x_; }
  double y() const { return y_; }
  double yaw() const { return yaw_; }
  const std::vector<Waypoint>& points() const { return pts_; }

  // Straight ahead (backwards when `reverse`) by distance_m, from standstill to standstill at `speed`; the lift
  // changes linearly to lift_end on the way.
  void drive(double distance_m, double speed, bool reverse, double lift_end) {
    const double dir = reverse ? yaw_ + kPi : yaw_;
    const double v = std::min(speed, std::sqrt(distance_m * kVehicleAccel));
    const double duration = distance_m / v + v / kVehicleAccel;
    const double x0 = x_, y0 = y_, t0 = t_, lift0 = lift_;
    const int n = std::max(1, static_cast<int>(std::ceil(duration / kSampleS)));
    for (int k = 1; k <= n; ++k) {
      const double tau = std::min(duration, k * kSampleS);
      const double s = trapezoid_distance(tau, distance_m, v, kVehicleAccel);
      x_ = x0 + s * std::cos(dir);
      y_ = y0 + s * std::sin(dir);
      lift_ = lift0 + (lift_end - lift0) * s / distance_m;
      push(t0 + tau);
    }
  }
  void drive(double distance_m, double speed, bool reverse = false) { drive(distance_m, speed, reverse, lift_); }
  // Turns on the spot to yaw_to about the point pivot_fwd_m ahead of the origin, at rate_rps.
  void turn(double yaw_to, double pivot_fwd_m, double rate_rps) {
    const double delta = wrap_angle(yaw_to - yaw_);
    const double px = x_ + pivot_fwd_m * std::cos(yaw_), py = y_ + pivot_fwd_m * std::sin(yaw_);
    const double yaw0 = yaw_, t0 = t_, duration = std::fabs(delta) / rate_rps;
    const int n = std::max(1, static_cast<int>(std::ceil(duration / kSampleS)));
    for (int k = 1; k <= n; ++k) {
      const double f = std::min(1.0, k * kSampleS / duration);
      yaw_ = yaw0 + delta * f;
      x_ = px - pivot_fwd_m * std::cos(yaw_);
      y_ = py - pivot_fwd_m * std::sin(yaw_);
      push(t0 + f * duration);
    }
  }
  void lift_to(double lift_m, double rate_mps) {
    const double duration = std::fabs(lift_m - lift_) / rate_mps;
    lift_ = lift_m;
    push(t_ + duration);
  }
  void wait(double dt) { push(t_ + dt); }

 private:
  void push(double t_s) {
    t_ = t_s;
    pts_.push_back(waypoint(t_s, x_, y_, yaw_, lift_));
  }
  double t_, x_, y_, yaw_, lift_;
  std::vector<Waypoint> pts_;
};

// Where a pallet on the forks of `forklift` is at t_s (its base rides kForksInPalletM below the forks' underside;
// at most on the floor).
Waypoint pallet_on_forks(const Actor& forklift, double t_s) {
  const ActorState st = actor_state(forklift, t_s);
  return waypoint(t_s, st.x + kForkForwardM * std::cos(st.yaw_rad), st.y + kForkForwardM * std::sin(st.yaw_rad),
                  st.yaw_rad, std::max(0.0, kForkTravelZ + st.lift_m - kForksInPalletM));
}
// Its waypoints every kSampleS / 2 over [t0, t1].
void ride_on_forks(const Actor& forklift, double t0, double t1, std::vector<Waypoint>& path) {
  const int n = std::max(1, static_cast<int>(std::ceil((t1 - t0) / (0.5 * kSampleS))));
  for (int k = 0; k <= n; ++k) path.push_back(pallet_on_forks(forklift, std::min(t1, t0 + k * 0.5 * kSampleS)));
}

Load random_load(Rng& r, float min_height_m, float max_height_m) {
  Load load;
  const double kind = r.uniform();
  load.kind = kind < 0.45 ? Load::Kind::kCartons : (kind < 0.75 ? Load::Kind::kWrapped : Load::Kind::kCrates);
  load.height_m = static_cast<float>(r.uniform(min_height_m, max_height_m));
  return load;
}

}  // namespace

// The AGV follows a tugger train or a loaded forklift down the main aisle, keeping right. The leader drives with
// a time headway of 0.7-1.1 s plus 2.0-2.3 m at standstill (2.6-3.3 m apart while cruising, as an AGV's safety
// field keeps it), its speed wandering a little; it stops at the end of the aisle and the AGV queues behind it.
void build_follow(ScenarioBuilder& b, const ScenarioOptions& options) {
  Scenario& sc = b.scenario();
  const WarehouseLayout& L = b.layout();
  Rng r = b.rng().fork(20);
  const double y = ego_lane_y(L);
  const double x0 = L.line_x_start + options.start_offset_m;
  const double x_stop = 27.0;  // the leader (at most 6 m long) stops short of the aisle's east end
  b.agv_lane(y, x0, x_stop - x0, 2.5, 3.0);
  const SpeedProfile& ego = sc.agv.profile;
  const bool tugger = r.chance(0.5);
  const double standstill_gap = r.uniform(2.0, 2.3), headway_s = r.uniform(0.7, 1.1);
  const double wobble_m = r.uniform(0.15, 0.3), wobble_period_s = r.uniform(8.0, 12.0);
  const double wobble_phase = r.uniform(0.0, 2 * kPi);
  // The leader's rear behind its origin: a forklift's counterweight, a tugger's last cart.
  const int carts = 2;
  const double rear_m = tugger ? trailer_offset_m(carts - 1) + 0.8 : 1.18;
  std::vector<Waypoint> path;
  double s_prev = 0;
  const int n = static_cast<int>(std::ceil(sc.nominal_duration_s / kSampleS));
  for (int k = 0; k <= n; ++k) {
    const double t = k * kSampleS;
    const double lead = std::min(1.0, ego.speed_at(t + headway_s) / ego.cruise_mps);
    double s_rear = ego.distance_at(t + headway_s) + standstill_gap +
                    wobble_m * lead * std::sin(2 * kPi * t / wobble_period_s + wobble_phase);
    s_rear = std::max(s_rear, k == 0 ? s_rear : s_prev);  // never backwards
    s_prev = s_rear;
    path.push_back(waypoint(t, x0 + s_rear + rear_m, y));
  }
  Actor leader = make_actor(
      1, tugger ? ActorClass::kAgv : ActorClass::kForklift,
      tugger ? "tugger train the AGV follows down the aisle" : "loaded forklift the AGV follows down the aisle", path,
      r);
  if (tugger) {
    leader.vehicle.tugger_carts = carts;
    leader.vehicle.load = random_load(r, 1.1f, 1.5f);
  } else {
    leader.vehicle.load = random_load(r, 0.8f, 1.3f);
  }
  sc.actors.push_back(leader);
}

// The AGV drives to a crossing of the main aisle, stops 2 m before the cross-aisle with the zebra crossing, waits
// while a group of five to seven people (a shift walking together, two abreast) crosses 1.6-2.4 m in front of it
// and then a forklift crosses the other way 1.7-2.9 m in front, then drives on.
void build_crowd(ScenarioBuilder& b, const ScenarioOptions& options) {
  Scenario& sc = b.scenario();
  const WarehouseLayout& L = b.layout();
  Rng r = b.rng().fork(21);
  const double T = sc.nominal_duration_s;
  const double gx = L.line_cross_aisles_x[1];
  const double x0 = gx - 8.0 + options.start_offset_m;
  const double stop_at = (gx - 2.0) - x0;
  b.agv_lane(L.line_y, x0, stop_at + 8.0, 1.0, 1.5, stop_at, r.uniform(14.5, 16.0));
  const SpeedProfile& ego = sc.agv.profile;
  const double t_stop = ego.stop_begin_s();

  // The group's track: from the west along the north service corridor, right into the cross-aisle, across the
  // main aisle southwards, right again along the south corridor back west (out of sight behind the racks).
  const double radius = 1.0, yn = L.north_corridor_y, ys = L.south_corridor_y;
  RoutePath track;
  track.add_line(0.8, yn, gx - radius, yn);
  track.add_arc(gx - radius, yn - radius, radius, 0.5 * kPi, -0.5 * kPi);
  track.add_line(gx, yn - radius, gx, ys + radius);
  track.add_arc(gx - radius, ys + radius, radius, 0.0, -0.5 * kPi);
  track.add_line(gx - radius, ys, 0.8, ys);
  // Arc length where the track meets the north face of the main aisle's racks.
  const double s_north_face = (gx - radius - 0.8) + 0.5 * kPi * radius + (yn - radius - (L.line_y + 1.6));
  const int people = r.uniform_int(5, 7);
  const int rows = (people + 1) / 2;
  const double spacing = r.uniform(0.95, 1.2), speed = r.uniform(1.0, 1.2);
  const double t_enter = t_stop + r.uniform(1.0, 2.0);  // the first row reaches the aisle
  // The formation waits in the corridor (its last row at the track's start) and reaches the aisle at t_enter.
  const double s_lead0 = rows * spacing + 0.2;
  const double t_walk = t_enter - (s_north_face - s_lead0) / speed - 0.5 * speed / kWalkAccel;
  double t_clear = 0;  // when the last of them has left the main aisle
  for (int i = 0; i < people; ++i) {
    Rng ri = r.fork(static_cast<uint64_t>(i));
    const int row = i / 2;
    const double along = -row * spacing + ri.uniform(-0.12, 0.12);
    const double lateral = (i % 2 == 0 ? 0.36 : -0.36) + ri.uniform(-0.05, 0.05);
    const double s0 = s_lead0 + along, s1 = track.length() - 0.5 + along;
    const double t_start = t_walk + ri.uniform(-0.1, 0.1);
    sc.actors.push_back(make_actor(1 + i, ActorClass::kPerson, "walks across the aisle in a group",
                                   along_track(track, s0, s1, t_start, speed, kWalkAccel, lateral, T), ri));
    // Leaves the aisle's south rack face 3.2 m + its place in the formation after the lead reaches the north one.
    t_clear = std::max(t_clear, t_start + 0.5 * speed / kWalkAccel + (s_north_face - s0 + 3.2 + 0.4) / speed);
  }
  // The forklift: from the east along the south corridor, right into the cross-aisle 0.35 m east of its centre,
  // across northwards, right along the north corridor to the east.
  const double fx = gx + 0.35, fr = 1.4, fy_s = ys + 0.05;
  RoutePath ftrack;
  ftrack.add_line(gx + 12.0, fy_s, fx + fr, fy_s);
  ftrack.add_arc(fx + fr, fy_s + fr, fr, -0.5 * kPi, -0.5 * kPi);
  ftrack.add_line(fx, fy_s + fr, fx, yn - fr);
  ftrack.add_arc(fx + fr, yn - fr, fr, kPi, -0.5 * kPi);
  ftrack.add_line(fx + fr, yn, gx + 12.0, yn);
  // Arc length where its fork tips (2.1 m ahead of its origin) reach the aisle's south rack face.
  const double s_south_face = (gx + 12.0 - fx - fr) + 0.5 * kPi * fr + ((L.line_y - 1.6) - (fy_s + fr)) - 2.1;
  Rng rf = r.fork(100);
  const double f_speed = rf.uniform(1.4, 1.7);
  b.add_best(16, [&](int i) {
    Rng ri = rf.fork(static_cast<uint64_t>(i));
    const double t_front = t_clear + 0.3 + 0.35 * i + ri.uniform(0.0, 0.3);
    const double t_start = t_front - s_south_face / f_speed - 0.5 * f_speed / kVehicleAccel;
    Actor a = make_actor(people + 1, ActorClass::kForklift, "crosses the aisle after the group while the AGV waits",
                         along_track(ftrack, 0.0, ftrack.length(), t_start, f_speed, kVehicleAccel, 0.0, T), ri);
    a.vehicle.load = ri.chance(0.5) ? random_load(ri, 0.6f, 1.2f) : Load{};
    return a;
  });
}

// The AGV stands at the outbound staging area facing three pallet slots 2.8 m ahead, two of them with loaded
// pallets. A forklift drives in, turns on the spot to face the AGV, slides its forks into one of the pallets
// (seen standing for ~15 s), lifts it, reverses out, turns and carries it away out of sight; it comes back
// reversing with another pallet, sets it down in the free slot and leaves. The carried pallets are actors of
// class pallet: the first is static, then moving; the second moving, then static.
void build_pallet(ScenarioBuilder& b, const ScenarioOptions& options) {
  Scenario& sc = b.scenario();
  const WarehouseLayout& L = b.layout();
  Rng r = b.rng().fork(22);
  const double sx = L.stage_x, cam_x = sx + options.start_offset_m, cam_y = L.stage_y;
  b.agv_stationary(cam_x, cam_y, 0.5 * kPi);
  const double y_row = cam_y + 2.8;   // slot centres (pallets 1.2 m deep along y, fork side north)
  const double y_lane = y_row + 3.3;  // where the forklift drives across, forks clear of the row
  const double slots[3] = {sx - 1.1, sx, sx + 1.1};
  const int free_slot = r.uniform_int(0, 2);
  const int picked_slot = (free_slot + r.uniform_int(1, 2)) % 3;
  const int other_slot = 3 - free_slot - picked_slot;
  // Out of sight to the left (outside the 78 degree view): where the forklift waits facing east (its fork tips
  // 5.8 m left of the camera) and where it swaps pallets facing west (its load clear of the west wall).
  const double x_start = cam_x - 7.9;
  const double x_away = std::max(2.3, cam_x - 7.2);
  const double facing_south = -0.5 * kPi;
  const double drive_speed = r.uniform(1.8, 2.2), reverse_speed = r.uniform(1.1, 1.4), approach_speed = 0.7;
  const double turn_rate = r.uniform(0.9, 1.1);  // rad/s
  const double lift_rate = 0.15;                 // m/s
  const double carry_lift = 0.15;                // forks 0.27 m above the floor while carrying
  const double approach_m = (y_lane + kForkliftPivotM) - (y_row + kForkForwardM);

  // The forklift (id 1), empty, waiting out of sight facing east.
  VehiclePlan f(r.uniform(2.5, 3.5), x_start, y_lane, 0.0, 0.0);
  f.drive(slots[picked_slot] - kForkliftPivotM - x_start, drive_speed);
  f.turn(facing_south, kForkliftPivotM, turn_rate);
  f.drive(approach_m, approach_speed, false, kForksLowered);  // lowers the forks on the way in
  const double t_pick = f.t();
  f.lift_to(carry_lift, lift_rate);
  f.drive(approach_m, approach_speed, true);
  f.turn(kPi, kForkliftPivotM, turn_rate);
  f.drive(f.x() - x_away, drive_speed);
  const double t_swap = f.t() + 1.5;  // out of sight: it puts the pallet down and takes another
  f.wait(3.0);
  f.drive(slots[free_slot] + kForkliftPivotM - f.x(), reverse_speed, true);
  f.turn(facing_south, kForkliftPivotM, turn_rate);
  f.drive(approach_m, approach_speed);
  f.lift_to(kForksLowered, lift_rate);
  const double t_set_down = f.t();
  f.drive(approach_m, approach_speed, true);  // the forks slide out low
  f.lift_to(0.0, lift_rate);
  f.turn(kPi, kForkliftPivotM, turn_rate);
  f.drive(f.x() - x_away, drive_speed);
  Actor forklift = make_actor(1, ActorClass::kForklift, "picks up a staged pallet, brings another", f.points(), r);
  forklift.vehicle.load = Load{};
  prepare_actor(forklift);
  sc.actors.push_back(forklift);

  // Where pallets wait while off stage: behind the camera, never in view.
  const double off_y = cam_y - 3.0;
  auto pallet = [&](int id, const std::string& role, std::vector<Waypoint> path) {
    Rng rp = r.fork(static_cast<uint64_t>(id));
    Actor a = make_actor(id, ActorClass::kPallet, role, std::move(path), rp);
    a.vehicle.load = random_load(rp, 0.7f, 1.5f);
    a.carrier_id = forklift.id;
    prepare_actor(a);
    sc.actors.push_back(a);
  };
  {  // Picked up: standing, lifted and carried away; off stage from the swap on.
    std::vector<Waypoint> path = {waypoint(0.0, slots[picked_slot], y_row, facing_south)};
    ride_on_forks(forklift, t_pick, t_swap, path);
    path.push_back(waypoint(t_swap, cam_x - 1.5, off_y, facing_south));
    pallet(2, "staged, picked up and carried away", path);
  }
  pallet(3, "staged (stays)", {waypoint(0.0, slots[other_slot], y_row, facing_south)});
  {  // Brought in on the forks from the swap on, set down in the free slot.
    std::vector<Waypoint> path = {waypoint(0.0, cam_x + 1.5, off_y, facing_south),
                                  waypoint(t_swap, cam_x + 1.5, off_y, facing_south)};
    ride_on_forks(forklift, t_swap, t_set_down, path);
    pallet(4, "brought in and set down in the free slot", path);
  }
}

// The AGV drives down the main aisle keeping right while a loaded forklift (1.7-2.2 m/s) and then a tugger train
// or a cart AGV (1.0-1.2 m/s) come towards it in the other lane from the aisle's far end and pass it.
void build_oncoming(ScenarioBuilder& b, const ScenarioOptions& options) {
  Scenario& sc = b.scenario();
  const WarehouseLayout& L = b.layout();
  Rng r = b.rng().fork(23);
  const double T = sc.nominal_duration_s;
  const double x0 = L.line_x_start + options.start_offset_m;
  b.agv_lane(ego_lane_y(L), x0, 29.0 - x0, 1.5, 1.5);
  const double x_end = 36.6;  // the aisle's far end (the racks stop at 34.4 m)
  RoutePath west;
  west.add_line(x_end, oncoming_lane_y(L), 1.5, oncoming_lane_y(L));
  // Drives in from the far end at `speed` so that it passes the camera when the AGV has driven meet_m.
  auto oncoming = [&](double speed, double meet_m) {
    const double t_meet = b.time_at_distance(meet_m);
    const double s_meet = x_end - (x0 + meet_m);
    const double lag = 0.5 * speed / kVehicleAccel;  // time lost accelerating
    double s0 = 0, t_start = t_meet - s_meet / speed - lag;
    if (t_start < 0.5) {  // too far to come from the end in time: it starts nearer
      t_start = 0.5;
      s0 = s_meet - speed * (t_meet - t_start - lag);
    }
    return along_track(west, s0, west.length(), t_start, speed, kVehicleAccel, 0.0, T);
  };
  {
    Rng rf = r.fork(1);
    Actor a = make_actor(1, ActorClass::kForklift, "loaded forklift coming towards the AGV, passing it",
                         oncoming(rf.uniform(1.7, 2.2), rf.uniform(6.0, 9.0)), rf);
    a.vehicle.load = random_load(rf, 0.7f, 1.3f);
    sc.actors.push_back(a);
  }
  {
    Rng ra = r.fork(2);
    const bool tugger = ra.chance(0.6);
    Actor a = make_actor(
        2, ActorClass::kAgv,
        tugger ? "tugger train coming towards the AGV, passing it" : "cart AGV coming towards the AGV, passing it",
        oncoming(ra.uniform(1.0, 1.2), ra.uniform(16.0, 19.0)), ra);
    if (tugger) {
      a.vehicle.tugger_carts = static_cast<uint8_t>(ra.uniform_int(1, 2));
      a.vehicle.load = random_load(ra, 0.9f, 1.4f);
    }
    sc.actors.push_back(a);
  }
}

}  // namespace agvslam::sim::scenario_detail
