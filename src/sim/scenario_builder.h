#pragma once
// Internal to the simulator: what the scenario definitions build the AGV's motion and the actors with
// (scenario.cpp: static, scene1..scene6; scenario_operations.cpp: follow, crowd, pallet, oncoming).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "agvslam/sim/random.h"
#include "agvslam/sim/scenario.h"

namespace agvslam::sim::scenario_detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPersonCameraClearanceM = 1.0;   // person's surface to the camera (they come close, as in the paper)
constexpr double kVehicleCameraClearanceM = 1.5;  // vehicle's surface to the camera
constexpr double kActorClearanceM = 0.5;          // between actors
constexpr double kCheckStepS = 0.05;

inline double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// Distance and speed tau seconds into a trapezoid over distance_m (from standstill to standstill) at cruise speed v
// and acceleration a (distance_m >= v^2 / a).
inline double trapezoid_distance(double tau, double distance_m, double v, double a) {
  const double t_acc = v / a, total = distance_m / v + t_acc;
  tau = std::clamp(tau, 0.0, total);
  if (tau < t_acc) return 0.5 * a * tau * tau;
  if (tau > total - t_acc) return distance_m - 0.5 * a * (total - tau) * (total - tau);
  return 0.5 * a * t_acc * t_acc + v * (tau - t_acc);
}
inline double trapezoid_speed(double tau, double distance_m, double v, double a) {
  const double total = distance_m / v + v / a;
  if (tau <= 0 || tau >= total) return 0;
  return std::min(v, a * std::min(tau, total - tau));
}

struct PathBuilder {
  std::vector<Waypoint> pts;
  PathBuilder(double x, double y) { pts.push_back({0.0, x, y}); }
  double t() const { return pts.back().t_s; }
  std::size_t walk_to(double x, double y, double speed) {
    const Waypoint& last = pts.back();
    const double d = std::hypot(x - last.x, y - last.y);
    pts.push_back({last.t_s + d / speed, x, y});
    return pts.size() - 1;
  }
  void wait(double dt) {
    const Waypoint last = pts.back();
    pts.push_back({last.t_s + dt, last.x, last.y});
  }
  // Shifts the timeline so that waypoint i is reached at t_s.
  void align(std::size_t i, double t_s) {
    const double d = t_s - pts[i].t_s;
    for (auto& p : pts) p.t_s += d;
  }
};

// Appearance of a person: body from the scenario's actor stream, clothing from the actor's appearance stream
// (RngStream::kAppearance seeded with its texture seed).
PersonLook random_look(Rng& rng, uint32_t actor_seed);
// An actor with its texture seed (and a person's look) drawn from `rng`, facing its first direction of travel.
Actor make_actor(int id, ActorClass cls, const std::string& role, std::vector<Waypoint> path, Rng& rng);

class ScenarioBuilder {
 public:
  ScenarioBuilder(Scenario& sc, const Warehouse& w) : sc_(sc), w_(w), L_(w.layout), rng_(sc.seed, RngStream::kActors) {}

  Rng& rng() { return rng_; }
  Scenario& scenario() { return sc_; }
  const WarehouseLayout& layout() const { return L_; }

  void agv_stationary(double x, double y, double yaw) {
    sc_.agv.stationary = true;
    sc_.agv.x = x;
    sc_.agv.y = y;
    sc_.agv.yaw_rad = yaw;
  }

  void agv_line(double offset) { agv_line_from(L_.line_x_start + offset, L_.line_length_m, 0.5); }

  // Along the aisle at y from x0 (+x) for length_m: standing for hold_start_s first and hold_end_s at the end,
  // stopping for stop_s at stop_at_m on the way when stop_at_m >= 0.
  void agv_lane(double y, double x0, double length_m, double hold_start_s, double hold_end_s, double stop_at_m = -1,
                double stop_s = 0) {
    AgvMotion& m = sc_.agv;
    m.stationary = false;
    m.route.add_line(x0, y, x0 + length_m, y);
    m.s_start = 0;
    SpeedProfile& p = m.profile;
    p.distance_m = length_m;
    p.duration_s = sc_.nominal_duration_s;
    p.hold_start_s = hold_start_s;
    p.hold_end_s = hold_end_s;
    p.accel_mps2 = 0.4;
    p.stop_at_m = stop_at_m;
    p.stop_s = stop_s;
    p.solve();
  }

  // Along the main aisle from x0 for length_m, standing still for the first hold_start_s.
  void agv_line_from(double x0, double length_m, double hold_start_s) {
    AgvMotion& m = sc_.agv;
    m.stationary = false;
    m.route.add_line(x0, L_.line_y, x0 + length_m, L_.line_y);
    m.s_start = 0;
    m.profile.distance_m = length_m;
    finish_profile(hold_start_s);
  }

  // Counter-clockwise rounded rectangle, starting 1 m into the south leg (+ offset), one full lap.
  void agv_loop(double offset) {
    AgvMotion& m = sc_.agv;
    m.stationary = false;
    const double x0 = L_.loop_x0, y0 = L_.loop_y0, x1 = L_.loop_x1, y1 = L_.loop_y1, r = L_.loop_corner_radius_m;
    RoutePath& p = m.route;
    p.add_line(x0 + r, y0, x1 - r, y0);
    p.add_arc(x1 - r, y0 + r, r, -0.5 * kPi, 0.5 * kPi);
    p.add_line(x1, y0 + r, x1, y1 - r);
    p.add_arc(x1 - r, y1 - r, r, 0.0, 0.5 * kPi);
    p.add_line(x1 - r, y1, x0 + r, y1);
    p.add_arc(x0 + r, y1 - r, r, 0.5 * kPi, 0.5 * kPi);
    p.add_line(x0, y1 - r, x0, y0 + r);
    p.add_arc(x0 + r, y0 + r, r, kPi, 0.5 * kPi);
    p.set_closed(true);
    m.s_start = std::fmod(1.0 + offset, p.length());
    if (m.s_start < 0) m.s_start += p.length();
    m.profile.distance_m = p.length();
    finish_profile();
  }

  // Arc length along the loop route of the points where the cross-aisle crosses the south and north legs.
  double loop_s_south_crossing() const { return L_.loop_cross_x - (L_.loop_x0 + L_.loop_corner_radius_m); }
  double loop_s_north_crossing() const {
    const double r = L_.loop_corner_radius_m;
    return (L_.loop_x1 - L_.loop_x0 - 2 * r) + 0.5 * kPi * r + (L_.loop_y1 - L_.loop_y0 - 2 * r) + 0.5 * kPi * r +
           (L_.loop_x1 - r - L_.loop_cross_x);
  }

  // Scenario time at which the AGV has travelled `distance` from its start (clamped to the motion).
  double time_at_distance(double distance) const {
    const SpeedProfile& p = sc_.agv.profile;
    if (distance <= 0) return p.hold_start_s;
    if (distance >= p.distance_m) return p.duration_s - p.hold_end_s;
    double lo = 0, hi = p.duration_s;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (p.distance_at(mid) < distance ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  // Distance along the route from the AGV's start to arc length s_target (ahead, wrapped on the loop).
  double distance_ahead(double s_target) const {
    const RoutePath& r = sc_.agv.route;
    double d = s_target - sc_.agv.s_start;
    if (r.closed()) {
      d = std::fmod(d, r.length());
      if (d < 0) d += r.length();
    }
    return d;
  }

  // Worst clearance margin of `cand` against the camera and the actors placed so far (>= 0: acceptable).
  double margin(const Actor& cand) const {
    double worst = 1e9;
    for (double t = 0; t <= sc_.nominal_duration_s + 1e-9; t += kCheckStepS) {
      const ActorState st = actor_state(cand, t);
      const std::vector<Circle> circles = actor_footprint(cand, st);
      double cx, cy, cyaw, cs;
      sc_.agv.planar_pose(t, cx, cy, cyaw, cs);
      const double camera_clearance =
          cand.cls == ActorClass::kPerson ? kPersonCameraClearanceM : kVehicleCameraClearanceM;
      for (const Circle& c : circles) {
        worst = std::min(worst, std::hypot(c.x - cx, c.y - cy) - c.r - camera_clearance);
        for (const Actor& other : sc_.actors) {
          if (carries(cand, other)) continue;
          const ActorState so = actor_state(other, t);
          for (const Circle& o : actor_footprint(other, so))
            worst = std::min(worst, std::hypot(c.x - o.x, c.y - o.y) - c.r - o.r - kActorClearanceM);
        }
      }
    }
    return worst;
  }

  // Tries candidates 0..n-1 (make(i) builds one) and keeps the first with a non-negative margin, else the best.
  void add_best(int n, const std::function<Actor(int)>& make) {
    Actor best;
    double best_margin = -1e18;
    for (int i = 0; i < n; ++i) {
      Actor a = make(i);
      const double m = margin(a);
      if (m > best_margin) {
        best_margin = m;
        best = a;
      }
      if (m >= 0) break;
    }
    if (best_margin < 0)
      spdlog::warn("scenario {}: actor {} ({}) comes {:.2f} m closer than the clearance it should keep", sc_.name,
                   best.id, best.role, -best_margin);
    sc_.actors.push_back(best);
  }

  // Person crossing the main aisle through the cross-aisle at gap_x, at the aisle centre at t_cross.
  // side: +1 / -1 = comes from and leaves towards +x / -x along the service corridors (0: random).
  Actor line_crossing_person(int id, double gap_x, bool north_to_south, double t_cross, Rng& r, int side = 0) {
    const double speed = r.uniform(1.0, 1.3);
    const double j = r.uniform(-0.5, 0.5);
    const double a = (side != 0 ? side : (r.chance(0.5) ? 1 : -1)) * r.uniform(2.0, 4.0);
    const double b = (side != 0 ? side : (r.chance(0.5) ? 1 : -1)) * r.uniform(2.0, 4.0);
    const double y_from = north_to_south ? L_.north_corridor_y : L_.south_corridor_y;
    const double y_to = north_to_south ? L_.south_corridor_y : L_.north_corridor_y;
    PathBuilder pb(gap_x + j + a, y_from);
    pb.walk_to(gap_x + j, y_from, speed);
    const std::size_t mid = pb.walk_to(gap_x + j, L_.line_y, speed);
    pb.walk_to(gap_x + j, y_to, speed);
    pb.walk_to(gap_x + j + b, y_to, speed);
    pb.align(mid, t_cross);
    return make_actor(id, ActorClass::kPerson,
                      north_to_south ? "crosses the aisle southwards" : "crosses the aisle northwards", pb.pts, r);
  }

  // Person walking through the loop's cross-aisle (crossing both legs); at leg_y at t_cross.
  Actor loop_crossing_person(int id, bool north_to_south, double leg_y, double t_cross, Rng& r) {
    const double speed = r.uniform(1.0, 1.3);
    const double xc = L_.loop_cross_x + r.uniform(-0.25, 0.25);
    const double a = (r.chance(0.5) ? 1 : -1) * r.uniform(1.5, 3.5);
    const double b = (r.chance(0.5) ? 1 : -1) * r.uniform(1.5, 3.5);
    const double y_n = L_.loop_north_area_y, y_s = L_.north_corridor_y;
    const double y_from = north_to_south ? y_n : y_s, y_to = north_to_south ? y_s : y_n;
    PathBuilder pb(xc + a, y_from);
    pb.walk_to(xc, y_from, speed);
    const std::size_t mid = pb.walk_to(xc, leg_y, speed);
    pb.walk_to(xc, y_to, speed);
    pb.walk_to(xc + b, y_to, speed);
    pb.align(mid, t_cross);
    return make_actor(id, ActorClass::kPerson, "crosses the loop through the cross-aisle", pb.pts, r);
  }

  void finalize_clearances() {
    double cam = 1e9, act = 1e9;
    for (double t = 0; t <= sc_.nominal_duration_s + 1e-9; t += kCheckStepS) {
      double cx, cy, cyaw, cs;
      sc_.agv.planar_pose(t, cx, cy, cyaw, cs);
      std::vector<std::vector<Circle>> fp;
      for (const Actor& a : sc_.actors) fp.push_back(actor_footprint(a, actor_state(a, t)));
      for (std::size_t i = 0; i < fp.size(); ++i)
        for (const Circle& c : fp[i]) {
          cam = std::min(cam, std::hypot(c.x - cx, c.y - cy) - c.r);
          for (std::size_t j = i + 1; j < fp.size(); ++j) {
            if (carries(sc_.actors[i], sc_.actors[j])) continue;
            for (const Circle& o : fp[j]) act = std::min(act, std::hypot(c.x - o.x, c.y - o.y) - c.r - o.r);
          }
        }
    }
    sc_.min_camera_clearance_m = cam;
    sc_.min_actor_clearance_m = act;
  }

 private:
  void finish_profile(double hold_start_s = 0.5) {
    SpeedProfile& p = sc_.agv.profile;
    p.duration_s = sc_.nominal_duration_s;
    p.hold_start_s = hold_start_s;
    p.hold_end_s = 0.5;
    p.accel_mps2 = 0.4;
    p.solve();
  }

  Scenario& sc_;
  const Warehouse& w_;
  const WarehouseLayout& L_;
  Rng rng_;
};

// The scenarios of scenario_operations.cpp (the AGV's motion and the actors, into the builder's scenario).
void build_follow(ScenarioBuilder& b, const ScenarioOptions& options);
void build_crowd(ScenarioBuilder& b, const ScenarioOptions& options);
void build_pallet(ScenarioBuilder& b, const ScenarioOptions& options);
void build_oncoming(ScenarioBuilder& b, const ScenarioOptions& options);

}  // namespace agvslam::sim::scenario_detail
