#include "agvslam/sim/scenario.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "agvslam/core/error.h"
#include "agvslam/sim/random.h"
#include "scenario_builder.h"

namespace agvslam::sim {

using namespace scenario_detail;

// ---- Catalogue ------------------------------------------------------------------------------------------------

const std::vector<ScenarioInfo>& scenario_catalogue() {
  static const std::vector<ScenarioInfo> catalogue = {
      {"static", "the 6.4 m x 8.8 m loop without people (control)", 35.0},
      {"scene1",
       "AGV stationary; one person walks in from the left ~2 m in front, turns, stands, walks back (~1.4 m) and "
       "leaves",
       20.0},
      {"scene2", "AGV drives a 13.6 m straight aisle; one person crosses 1.6-2.4 m ahead", 20.0},
      {"scene3",
       "13.6 m straight aisle; one person crosses 1.6-2.4 m ahead, one stands then walks 1.5-2.5 m ahead, one crosses "
       "beyond them; a forklift parked then crossing",
       20.0},
      {"scene4", "6.4 m x 8.8 m loop back to the start; one person crosses 1.6-2.4 m ahead; a parked forklift", 35.0},
      {"scene5",
       "the loop; a person walks 1.5-2.4 m ahead all the way, one crosses beyond them, one stands then leaves; an AGV "
       "parked then driving",
       35.0},
      {"scene6",
       "AGV waits at a cross-aisle while a forklift crosses 1.6-2.4 m ahead, stopping in front of it (it fills most "
       "of the view), then drives the aisle; a person crosses ahead",
       24.0},
      {"follow",
       "AGV follows a tugger train or a loaded forklift 2.6-3.3 m ahead down the main aisle, keeping right; both stop "
       "at its end",
       34.0},
      {"crowd",
       "AGV stops 2 m before a crossing while a group of 5-7 people crosses 1.6-2.4 m ahead, then a forklift 1.7-2.9 m "
       "ahead; then it drives on",
       38.0},
      {"pallet",
       "AGV stands at the staging area; a forklift picks up a staged pallet 2.8 m ahead and carries it away, then "
       "brings another and sets it down",
       58.0},
      {"oncoming",
       "AGV drives down the main aisle keeping right; a loaded forklift, then a tugger train or an AGV come towards it "
       "in the other lane and pass it",
       33.0},
  };
  return catalogue;
}

const ScenarioInfo& find_scenario(const std::string& name) {
  std::string names;
  for (const auto& s : scenario_catalogue()) {
    if (s.name == name) return s;
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw InputError("--scenario", "'" + name + "'", "unknown scenario; expected one of: " + names);
}

void ScenarioOptions::validate(const WarehouseLayout& layout) const {
  find_scenario(name);
  if (frames < 0) throw InputError("--frames", std::to_string(frames), "expected a number of frames > 0");
  if (squeeze_to_frames < 0)
    throw InputError("--squeeze-to", std::to_string(squeeze_to_frames), "expected a number of frames > 0");
  if (!std::isfinite(start_offset_m))
    throw InputError("--start-offset", std::to_string(start_offset_m), "expected a finite distance in metres");
  const bool line = name == "scene2" || name == "scene3";
  if (line && (start_offset_m < 0 || start_offset_m > layout.line_max_start_offset_m))
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a distance in [0, " + std::to_string(layout.line_max_start_offset_m) +
                         "] m along the aisle for " + name);
  if (name == "scene6" && (start_offset_m < -2.0 || start_offset_m > 0.0))
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a distance in [-2, 0] m (further back from the cross-aisle) for scene6");
  if (name == "scene1" && std::fabs(start_offset_m) > 2.0)
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a sideways shift in [-2, 2] m of the stationary AGV for scene1");
  if ((name == "follow" || name == "oncoming") && (start_offset_m < 0 || start_offset_m > 2.0))
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a distance in [0, 2] m along the aisle for " + name);
  if (name == "crowd" && (start_offset_m < -1.0 || start_offset_m > 0.0))
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a distance in [-1, 0] m (further back from the crossing) for crowd");
  if (name == "pallet" && (start_offset_m < 0 || start_offset_m > 1.0))
    throw InputError("--start-offset", std::to_string(start_offset_m),
                     "expected a shift in [0, 1] m to the right of the stationary AGV for pallet");
}

// ---- Route and speed profile ----------------------------------------------------------------------------------

void RoutePath::add_line(double x0, double y0, double x1, double y1) {
  Piece p{};
  p.arc = false;
  p.x0 = x0;
  p.y0 = y0;
  p.x1 = x1;
  p.y1 = y1;
  p.s0 = length_;
  p.len = std::hypot(x1 - x0, y1 - y0);
  length_ += p.len;
  pieces_.push_back(p);
}

void RoutePath::add_arc(double cx, double cy, double radius, double a0_rad, double sweep_rad) {
  Piece p{};
  p.arc = true;
  p.cx = cx;
  p.cy = cy;
  p.r = radius;
  p.a0 = a0_rad;
  p.sweep = sweep_rad;
  p.s0 = length_;
  p.len = std::fabs(sweep_rad) * radius;
  length_ += p.len;
  pieces_.push_back(p);
}

void RoutePath::sample(double s, double& x, double& y, double& heading) const {
  if (pieces_.empty()) {
    x = y = heading = 0;
    return;
  }
  if (closed_ && length_ > 0) {
    s = std::fmod(s, length_);
    if (s < 0) s += length_;
  } else {
    s = std::clamp(s, 0.0, length_);
  }
  std::size_t i = 0;
  while (i + 1 < pieces_.size() && s > pieces_[i].s0 + pieces_[i].len) ++i;
  const Piece& p = pieces_[i];
  const double f = p.len > 0 ? std::clamp((s - p.s0) / p.len, 0.0, 1.0) : 0.0;
  if (!p.arc) {
    x = p.x0 + (p.x1 - p.x0) * f;
    y = p.y0 + (p.y1 - p.y0) * f;
    heading = std::atan2(p.y1 - p.y0, p.x1 - p.x0);
  } else {
    const double a = p.a0 + p.sweep * f;
    x = p.cx + p.r * std::cos(a);
    y = p.cy + p.r * std::sin(a);
    heading = wrap_angle(a + (p.sweep > 0 ? 0.5 * kPi : -0.5 * kPi));
  }
}

double SpeedProfile::stop_begin_s() const {
  if (stop_at_m < 0 || cruise_mps <= 0) return hold_start_s;
  return hold_start_s + stop_at_m / cruise_mps + cruise_mps / accel_mps2;
}

void SpeedProfile::solve() {
  if (stop_at_m >= 0) {
    // Two trapezoids of the same cruise speed v: (distance / v + 2 v / a) seconds of motion in all.
    const double t_move = std::max(1e-3, duration_s - hold_start_s - hold_end_s - stop_s);
    const double disc = t_move * t_move - 8.0 * distance_m / accel_mps2;
    if (disc < 0) accel_mps2 = 8.0 * distance_m / (t_move * t_move);
    cruise_mps = 0.25 * accel_mps2 * (t_move - std::sqrt(std::max(0.0, disc)));
    return;
  }
  const double t_move = std::max(1e-3, duration_s - hold_start_s - hold_end_s);
  double a = accel_mps2;
  if (t_move * t_move < 4.0 * distance_m / a) a = 4.0 * distance_m / (t_move * t_move);  // triangular
  accel_mps2 = a;
  const double disc = std::max(0.0, t_move * t_move - 4.0 * distance_m / a);
  cruise_mps = 0.5 * a * (t_move - std::sqrt(disc));
}

double SpeedProfile::distance_at(double t) const {
  if (stop_at_m >= 0) {
    if (cruise_mps <= 0) return 0;
    if (t < stop_end_s()) return trapezoid_distance(t - hold_start_s, stop_at_m, cruise_mps, accel_mps2);
    return stop_at_m + trapezoid_distance(t - stop_end_s(), distance_m - stop_at_m, cruise_mps, accel_mps2);
  }
  const double t_move = std::max(1e-3, duration_s - hold_start_s - hold_end_s);
  const double tau = std::clamp(t - hold_start_s, 0.0, t_move);
  if (cruise_mps <= 0) return 0;
  const double t_acc = cruise_mps / accel_mps2;
  if (tau < t_acc) return 0.5 * accel_mps2 * tau * tau;
  if (tau > t_move - t_acc) {
    const double rem = t_move - tau;
    return distance_m - 0.5 * accel_mps2 * rem * rem;
  }
  return 0.5 * accel_mps2 * t_acc * t_acc + cruise_mps * (tau - t_acc);
}

double SpeedProfile::speed_at(double t) const {
  if (stop_at_m >= 0) {
    if (cruise_mps <= 0) return 0;
    if (t < stop_end_s()) return trapezoid_speed(t - hold_start_s, stop_at_m, cruise_mps, accel_mps2);
    return trapezoid_speed(t - stop_end_s(), distance_m - stop_at_m, cruise_mps, accel_mps2);
  }
  const double t_move = std::max(1e-3, duration_s - hold_start_s - hold_end_s);
  const double tau = t - hold_start_s;
  if (tau <= 0 || tau >= t_move || cruise_mps <= 0) return 0;
  return std::min(cruise_mps, accel_mps2 * std::min(tau, t_move - tau));
}

void AgvMotion::planar_pose(double t_s, double& x_out, double& y_out, double& yaw_out, double& s_out) const {
  if (stationary) {
    x_out = x;
    y_out = y;
    yaw_out = yaw_rad;
    s_out = 0;
    return;
  }
  s_out = profile.distance_at(t_s);
  route.sample(s_start + s_out, x_out, y_out, yaw_out);
}

std::vector<Circle> actor_footprint(const Actor& a, const ActorState& st) {
  const double c = std::cos(st.yaw_rad), s = std::sin(st.yaw_rad);
  auto at = [&](double fwd, double r) { return Circle{st.x + c * fwd, st.y + s * fwd, r}; };
  std::vector<Circle> circles;
  switch (a.cls) {
    case ActorClass::kPerson:
      circles = {at(0.0, 0.3)};
      break;
    case ActorClass::kForklift:
      circles = {at(-0.5, 0.75), at(0.45, 0.75), at(1.5, 0.7)};
      break;
    case ActorClass::kAgv:
      circles = a.vehicle.tugger_carts > 0 ? std::vector<Circle>{at(-0.1, 0.6)}
                                           : std::vector<Circle>{at(-0.3, 0.45), at(0.3, 0.45)};
      break;
    case ActorClass::kPallet:
      circles = {at(-0.3, 0.5), at(0.3, 0.5)};
      break;
  }
  for (int k = 0; k < trailer_count(a); ++k) {  // a cart: 1.6 m x 1.2 m
    double x, y, heading;
    actor_track_point(a, st.distance_m - trailer_offset_m(k), x, y, heading);
    for (double fwd : {-0.45, 0.45}) circles.push_back({x + std::cos(heading) * fwd, y + std::sin(heading) * fwd, 0.6});
  }
  return circles;
}

bool carries(const Actor& a, const Actor& b) { return a.carrier_id == b.id || b.carrier_id == a.id; }

// ---- Scenario construction --------------------------------------------------------------------------------------

namespace scenario_detail {

namespace {

// Albedos of common colours as the grey camera sees them (the luma of the colour times a fabric's or a paint's
// reflectance), darkest first.
constexpr float kClothShades[] = {0.04f, 0.08f, 0.14f, 0.2f, 0.26f, 0.3f, 0.38f, 0.48f, 0.58f, 0.7f, 0.8f, 0.86f};
constexpr float kTrouserShades[] = {0.05f, 0.09f, 0.16f, 0.2f, 0.24f, 0.32f, 0.42f};
constexpr float kHiVisShades[] = {0.58f, 0.86f};  // orange, yellow
constexpr float kForkliftShades[] = {0.72f, 0.55f, 0.32f, 0.28f, 0.38f, 0.5f, 0.8f, 0.15f};
constexpr float kAgvShades[] = {0.58f, 0.75f, 0.55f, 0.7f, 0.3f, 0.2f};

template <std::size_t N>
float pick(const float (&shades)[N], double u) {
  return shades[std::min(N - 1, static_cast<std::size_t>(u * static_cast<double>(N)))];
}
// A second colour that stands out against `shade`.
float contrasting(float shade, Rng& a) {
  return static_cast<float>(shade < 0.45f ? shade + a.uniform(0.3, 0.55) : shade - a.uniform(0.3, 0.5));
}

// Clothing, build and what the hands hold: the colours and the pattern from u in [0, 1), the rest from the
// actor's appearance stream.
void dress(PersonLook& look, double colour_u, double pattern_u, double trousers_u, Rng& a) {
  using P = PersonLook;
  const double top = a.uniform();
  look.top = top < 0.22   ? P::Top::kTshirt
             : top < 0.44 ? P::Top::kLongSleeve
             : top < 0.64 ? P::Top::kJacket
             : top < 0.76 ? P::Top::kHoodie
             : top < 0.92 ? P::Top::kHiVisVest
                          : P::Top::kOveralls;
  look.shirt_shade = std::clamp(pick(kClothShades, colour_u) + static_cast<float>(a.uniform(-0.03, 0.03)), 0.03f, 0.9f);
  look.inner_shade = pick(kClothShades, a.uniform());
  if (look.top == P::Top::kHiVisVest) look.shirt_shade = pick(kHiVisShades, a.uniform());
  look.pattern = pattern_u < 0.3    ? P::Pattern::kPlain
                 : pattern_u < 0.47 ? P::Pattern::kStripes
                 : pattern_u < 0.6  ? P::Pattern::kChecks
                 : pattern_u < 0.75 ? P::Pattern::kPlaid
                 : pattern_u < 0.88 ? P::Pattern::kBlotches
                                    : P::Pattern::kDots;
  look.pattern_shade = contrasting(look.shirt_shade, a);
  look.pattern_period_m = static_cast<float>(a.uniform(0.05, 0.15));
  look.prints = 0;
  if (a.chance(0.5)) look.prints |= P::kChestLogo;
  if (a.chance(0.45)) look.prints |= P::kBackPrint;
  if ((look.top == P::Top::kTshirt || look.top == P::Top::kHoodie) && a.chance(0.35)) look.prints |= P::kFrontGraphic;
  if (a.chance(0.2)) look.prints |= P::kNameBadge;
  look.pockets = a.chance(0.75);
  look.folds = a.chance(0.9);
  const double bottom = a.uniform();
  look.bottom = bottom < 0.4   ? P::Bottom::kWork
                : bottom < 0.7 ? P::Bottom::kJeans
                : bottom < 0.9 ? P::Bottom::kCargo
                               : P::Bottom::kHiVis;
  look.trousers_shade =
      look.bottom == P::Bottom::kHiVis ? pick(kHiVisShades, trousers_u) : pick(kTrouserShades, trousers_u);
  if (look.top == P::Top::kOveralls) look.trousers_shade = look.shirt_shade;
  look.shoe_shade = static_cast<float>(a.uniform(0.04, 0.2));
  const double carry = a.uniform();
  look.carry = carry < 0.7    ? P::Carry::kNothing
               : carry < 0.82 ? P::Carry::kBox
               : carry < 0.94 ? P::Carry::kScanner
                              : P::Carry::kPhone;
  look.arm_swing = static_cast<float>(a.uniform(0.6, 1.25));
  look.build = static_cast<float>(a.uniform(0.9, 1.12));
  look.girth = static_cast<float>(a.uniform(0.9, 1.2));
}

// A forklift driver: everything from the appearance stream, hands on the wheel.
PersonLook driver_look(Rng& a) {
  PersonLook look;
  look.height_m = static_cast<float>(a.uniform(1.6, 1.92));
  look.skin_shade = static_cast<float>(a.uniform(0.35, 0.75));
  look.hair_shade = static_cast<float>(a.uniform(0.05, 0.4));
  look.helmet = a.chance(0.3);
  const double colour_u = a.uniform(), pattern_u = a.uniform(), trousers_u = a.uniform();
  dress(look, colour_u, pattern_u, trousers_u, a);
  look.carry = PersonLook::Carry::kNothing;
  return look;
}

}  // namespace

PersonLook random_look(Rng& rng, uint32_t actor_seed) {
  // Seven draws from the scenario's stream, as many as ever (every later actor's path depends on them); the rest
  // of the clothing from the actor's own stream.
  PersonLook look;
  look.height_m = static_cast<float>(rng.uniform(1.6, 1.92));
  const double colour_u = rng.uniform(), pattern_u = rng.uniform(), trousers_u = rng.uniform();
  look.skin_shade = static_cast<float>(rng.uniform(0.35, 0.75));
  look.hair_shade = static_cast<float>(rng.uniform(0.05, 0.4));
  look.helmet = rng.chance(0.3);
  Rng a(actor_seed, RngStream::kAppearance);
  dress(look, colour_u, pattern_u, trousers_u, a);
  return look;
}

Actor make_actor(int id, ActorClass cls, const std::string& role, std::vector<Waypoint> path, Rng& rng) {
  Actor a;
  a.id = id;
  a.cls = cls;
  a.role = role;
  a.path = std::move(path);
  a.seed = rng.next_u32();
  if (cls == ActorClass::kPerson) a.look = random_look(rng, a.seed);
  Rng appearance(a.seed, RngStream::kAppearance);
  if (cls == ActorClass::kForklift) {
    if ((a.seed & 1U) != 0) a.vehicle.load = {Load::Kind::kWrapped, 0.9f};
    a.vehicle.body_shade =
        pick(kForkliftShades, appearance.uniform()) + static_cast<float>(appearance.uniform(-0.03, 0.03));
    a.look = driver_look(appearance);
  }
  if (cls == ActorClass::kAgv)
    a.vehicle.body_shade = pick(kAgvShades, appearance.uniform()) + static_cast<float>(appearance.uniform(-0.03, 0.03));
  // Facing the first direction of travel until then.
  a.initial_yaw_rad = 0;
  for (std::size_t i = 0; i + 1 < a.path.size(); ++i) {
    const double dx = a.path[i + 1].x - a.path[i].x, dy = a.path[i + 1].y - a.path[i].y;
    if (std::hypot(dx, dy) > 1e-3) {
      a.initial_yaw_rad = std::atan2(dy, dx);
      break;
    }
  }
  prepare_actor(a);
  return a;
}
}  // namespace scenario_detail

Scenario make_scenario(const ScenarioOptions& options, const Warehouse& warehouse, double rate_hz) {
  options.validate(warehouse.layout);
  const ScenarioInfo& info = find_scenario(options.name);
  Scenario sc;
  sc.name = info.name;
  sc.description = info.description;
  sc.seed = options.seed;
  sc.layout_seed = options.effective_layout_seed();
  sc.start_offset_m = options.start_offset_m;
  sc.rate_hz = rate_hz;
  sc.nominal_duration_s = info.nominal_duration_s;
  sc.timeline_frames = options.squeeze_to_frames > 0
                           ? options.squeeze_to_frames
                           : std::max(1, static_cast<int>(std::lround(info.nominal_duration_s * rate_hz)));
  sc.frames = options.frames > 0 ? options.frames : sc.timeline_frames;
  sc.time_scale = (sc.timeline_frames / rate_hz) / sc.nominal_duration_s;

  const WarehouseLayout& L = warehouse.layout;
  ScenarioBuilder b(sc, warehouse);
  Rng& rng = b.rng();
  const double T = sc.nominal_duration_s;
  const std::string& name = sc.name;

  if (name == "scene1") {
    // As in the paper's scene 1: the person walks in from the left close in front of the camera (1.5-3 m), turns
    // right of the centre, stands, then walks back past the centre (closest, ~1.5 m) and leaves to the left.
    const double x_agv = L.stage_x + options.start_offset_m;
    b.agv_stationary(x_agv, L.stage_y, 0.5 * kPi);
    Rng r = rng.fork(1);
    // Half width of the view at depth d (fx / (width / 2) = 460 / 376 for the nominal camera), plus a body.
    auto edge_x = [&](double depth) { return x_agv - depth * (376.0 / 460.0) - 0.15; };
    const double depth_in = r.uniform(1.9, 2.3);
    const double depth_turn = r.uniform(1.5, 1.8);
    const double depth_mid = r.uniform(1.4, 1.5);
    const double depth_out = r.uniform(2.0, 2.5);
    const double t_enter = T * (0.25 + r.uniform(-0.015, 0.015));
    const double t_turn = T * (0.45 + r.uniform(-0.015, 0.015));
    const double t_back = t_turn + r.uniform(2.5, 3.5);
    const double t_leave = T * (0.85 + r.uniform(-0.015, 0.015));
    const double x_enter = edge_x(depth_in), y_in = L.stage_y + depth_in;
    const double x_turn = x_agv + r.uniform(0.6, 1.0), y_turn = L.stage_y + depth_turn;
    const double x_mid = x_agv + r.uniform(-0.6, 0.0), y_mid = L.stage_y + depth_mid;
    const double x_exit = edge_x(depth_out), y_out = L.stage_y + depth_out;
    // Comes from further left and back (out of view: the left edge of the view recedes faster), leaves that way.
    std::vector<Waypoint> path;
    const double in_len = std::hypot(x_turn - x_enter, y_turn - y_in);
    const double in_speed = in_len / (t_turn - t_enter);
    const double x_from = x_enter - 1.6, y_from = y_in + 0.6;
    path.push_back({t_enter - std::hypot(x_enter - x_from, y_in - y_from) / in_speed, x_from, y_from});
    path.push_back({t_enter, x_enter, y_in});
    path.push_back({t_turn, x_turn, y_turn});
    path.push_back({t_back, x_turn, y_turn});
    const double back_a = std::hypot(x_mid - x_turn, y_mid - y_turn),
                 back_b = std::hypot(x_exit - x_mid, y_out - y_mid);
    const double back_speed = (back_a + back_b) / (t_leave - t_back);
    path.push_back({t_back + back_a / back_speed, x_mid, y_mid});
    path.push_back({t_leave, x_exit, y_out});
    const double x_to = x_exit - 1.6, y_to = y_out + 0.6;
    path.push_back({t_leave + std::hypot(x_to - x_exit, y_to - y_out) / back_speed, x_to, y_to});
    sc.actors.push_back(
        make_actor(1, ActorClass::kPerson, "walks in from the left close ahead, stands, walks back", path, r));
  } else if (name == "scene2" || name == "scene3") {
    b.agv_line(options.start_offset_m);
    const double x_start = L.line_x_start + options.start_offset_m;
    const double x_end = x_start + L.line_length_m;
    // Cross-aisles that the AGV passes (it has driven >= 1 m before a crossing 1.7 m ahead of it).
    std::vector<double> gaps;
    for (double g : L.line_cross_aisles_x)
      if (g - x_start >= 2.7 && g < x_end + 1.0) gaps.push_back(g);
    if (gaps.empty()) gaps.push_back(L.line_cross_aisles_x.back());
    auto crossing_time = [&](double gap_x, double ahead_m) { return b.time_at_distance(gap_x - ahead_m - x_start); };
    // Close crossing: 1.6-2.4 m ahead (later candidates further), never before the AGV has driven 1 m.
    auto close_ahead = [&](double gap_x, int i, Rng& ri) {
      return std::min(1.6 + 0.1 * i + ri.uniform(0.0, 0.8), std::max(1.6, gap_x - x_start - 1.0) + 0.1 * i);
    };
    if (name == "scene2") {
      Rng r = rng.fork(2);
      const double gap_x = gaps[gaps.size() / 2];
      const bool north_to_south = r.chance(0.5);
      b.add_best(16, [&](int i) {
        Rng ri = r.fork(static_cast<uint64_t>(i));
        return b.line_crossing_person(1, gap_x, north_to_south, crossing_time(gap_x, close_ahead(gap_x, i, ri)), ri);
      });
    } else {
      {  // Person 1 crosses the first cross-aisle close ahead.
        Rng r = rng.fork(4);
        const bool north_to_south = r.chance(0.5);
        b.add_best(24, [&](int i) {
          Rng ri = r.fork(static_cast<uint64_t>(i));
          return b.line_crossing_person(1, gaps.front(), north_to_south,
                                        crossing_time(gaps.front(), close_ahead(gaps.front(), i, ri)), ri, +1);
        });
      }
      {  // Person 2 stands in the aisle beyond the first cross-aisle; when the AGV comes within ~2 m it walks
         // ahead of it, 1.5-2.5 m in front, and walks on when the AGV stops.
        Rng r = rng.fork(3);
        b.add_best(12, [&](int i) {
          Rng ri = r.fork(static_cast<uint64_t>(i));
          const double y = L.line_y + ri.uniform(0.3, 0.6);
          double x0 = gaps.front() + 1.9 + 0.3 * i + ri.uniform(0.0, 0.8);
          for (double g : gaps)
            if (std::fabs(x0 - g) < 1.9) x0 = g + 1.9;
          const double gap0 = ri.uniform(1.7, 1.9), amp = ri.uniform(0.15, 0.3), period = ri.uniform(6.0, 10.0);
          const double phase = ri.uniform(0.0, 2 * kPi);
          const double walk_on_speed = ri.uniform(0.8, 1.0);
          // Walks on by itself once the AGV starts braking.
          const SpeedProfile& prof = sc.agv.profile;
          const double t_release = prof.duration_s - prof.hold_end_s - prof.cruise_mps / prof.accel_mps2;
          std::vector<Waypoint> path;
          double x = x0;
          for (double t = 0; t <= T + 1e-9; t += 0.1) {
            double cx, cy, cyaw, cs;
            sc.agv.planar_pose(t, cx, cy, cyaw, cs);
            if (t < t_release)
              x = std::max(x, cx + gap0 + amp * std::sin(2 * kPi * t / period + phase));
            else if (!path.empty())
              x += walk_on_speed * 0.1;
            path.push_back({t, x, y});
          }
          return make_actor(2, ActorClass::kPerson, "stands in the aisle, then walks ahead of the AGV", path, ri);
        });
      }
      {  // Person 3 crosses beyond person 2 (3.3-4 m ahead of the AGV): the second cross-aisle when there is one.
        Rng r = rng.fork(5);
        const double gap_x = gaps.size() > 1 ? gaps[1] : gaps.front();
        const bool north_to_south = r.chance(0.5);
        b.add_best(64, [&](int i) {
          Rng ri = r.fork(static_cast<uint64_t>(i));
          const double ahead = 3.3 + 0.2 * (i / 2) + ri.uniform(0.0, 0.6);
          return b.line_crossing_person(3, gap_x, (i % 2 == 0) == north_to_south, crossing_time(gap_x, ahead), ri, -1);
        });
      }
      {  // Forklift: parked facing the aisle beyond the racks, then drives across it and away.
        Rng r = rng.fork(6);
        b.add_best(20, [&](int i) {
          Rng ri = r.fork(static_cast<uint64_t>(i));
          const double x = L.line_exit_x + ri.uniform(-0.3, 0.3);
          // Forks first (south); it stops in the gap of the south row with the fork tips short of the wall.
          PathBuilder pb(x, 7.9);
          pb.pts.front().t_s = T * (0.3 + 0.025 * i) + ri.uniform(0.0, 0.5);
          pb.walk_to(x, 2.45, ri.uniform(1.2, 1.6));
          return make_actor(4, ActorClass::kForklift, "parked, drives across the aisle ahead, parks", pb.pts, ri);
        });
      }
    }
  } else if (name == "scene6") {
    // The AGV waits 2.0-2.6 m before the first cross-aisle (its stop line) while a forklift crosses the main aisle
    // through it, close enough to fill most of the view, stopping 2-3.5 s in the middle of the aisle (a parked-then-
    // moving object: what a plain SLAM maps and then follows); when it has gone the AGV drives on along the aisle
    // and a person crosses the second cross-aisle ahead of it.
    std::vector<double> gaps;
    for (double g : L.line_cross_aisles_x)
      if (g - L.line_x_start >= 2.6) gaps.push_back(g);
    if (gaps.empty()) gaps.push_back(L.line_cross_aisles_x.back());
    Rng r = rng.fork(12);
    const double gap_x = gaps.front();
    const double wait_s = r.uniform(11.0, 12.0);
    const double x0 = gap_x - r.uniform(2.0, 2.6) + options.start_offset_m;
    b.agv_line_from(x0, std::min(L.line_length_m, L.line_exit_x - 1.5 - x0), wait_s);
    const bool north_to_south = r.chance(0.5);
    b.add_best(16, [&](int i) {
      Rng ri = r.fork(static_cast<uint64_t>(i));
      const double speed = ri.uniform(1.1, 1.5);
      const double x = gap_x + ri.uniform(-0.2, 0.2);
      const double y_from = north_to_south ? L.north_corridor_y - 0.4 : L.south_corridor_y + 0.4;
      const double y_to = north_to_south ? L.south_corridor_y + 0.4 : L.north_corridor_y - 0.4;
      PathBuilder pb(x, y_from);
      const std::size_t mid = pb.walk_to(x, L.line_y, speed);
      pb.wait(ri.uniform(2.0, 3.5));  // stops in the aisle (the driver looks both ways), then drives on
      pb.walk_to(x, y_to, speed);
      // In the aisle 4.5-5.5 s into the wait (it comes into view after ~2.5 s), then away along the corridor.
      pb.align(mid, ri.uniform(4.5, 5.5) + 0.3 * i);
      pb.walk_to(x - 6.0, y_to, speed);  // back along the corridor, away from the later crossing
      return make_actor(1, ActorClass::kForklift, "crosses the aisle close ahead while the AGV waits", pb.pts, ri);
    });
    if (gaps.size() > 1) {
      Rng rp = rng.fork(13);
      const bool ns = rp.chance(0.5);
      b.add_best(16, [&](int i) {
        Rng ri = rp.fork(static_cast<uint64_t>(i));
        const double ahead = 2.4 + 0.1 * i + ri.uniform(0.0, 0.6);
        return b.line_crossing_person(2, gaps[1], ns, b.time_at_distance(gaps[1] - ahead - x0), ri);
      });
    }
  } else if (name == "follow") {
    build_follow(b, options);
  } else if (name == "crowd") {
    build_crowd(b, options);
  } else if (name == "pallet") {
    build_pallet(b, options);
  } else if (name == "oncoming") {
    build_oncoming(b, options);
  } else {  // loops
    b.agv_loop(options.start_offset_m);
    if (name == "scene4" || name == "scene5") {
      const double len = sc.agv.route.length();
      const double d_south = b.distance_ahead(b.loop_s_south_crossing());
      const double d_north = b.distance_ahead(b.loop_s_north_crossing());
      struct Crossing {
        double distance;
        double leg_y;
        bool heading_east;
      };
      std::vector<Crossing> crossings = {{d_south, L.loop_y0, true}, {d_north, L.loop_y1, false}};
      // Prefer crossings reached between 20 % and 85 % of the lap.
      std::vector<Crossing> good;
      for (const auto& c : crossings)
        if (c.distance > 0.2 * len && c.distance < 0.85 * len) good.push_back(c);
      if (good.empty()) good = crossings;
      Rng r = rng.fork(7);
      const Crossing chosen = good[static_cast<std::size_t>(r.uniform_int(0, static_cast<int>(good.size()) - 1))];

      if (name == "scene5") {
        // Person 1 walks ahead of the AGV along the loop for the whole lap, 1.5-2.4 m in front of it.
        Rng ra = rng.fork(8);
        const double lateral = ra.uniform(0.2, 0.4);
        const double gap0 = ra.uniform(1.7, 1.9), amp = ra.uniform(0.15, 0.3), period = ra.uniform(9.0, 14.0);
        const double phase = ra.uniform(0.0, 2 * kPi);
        std::vector<Waypoint> path;
        double s_person = 0;  // route position of the person relative to the AGV's start
        for (double t = 0; t <= T + 1e-9; t += 0.1) {
          double x, y, yaw, s;
          sc.agv.planar_pose(t, x, y, yaw, s);
          // Closer behind a corner so that the person stays in view while the AGV turns after them.
          double hx, hy, h_now, h_ahead;
          sc.agv.route.sample(sc.agv.s_start + s, hx, hy, h_now);
          sc.agv.route.sample(sc.agv.s_start + s + 3.0, hx, hy, h_ahead);
          const double corner = std::min(1.0, std::fabs(wrap_angle(h_ahead - h_now)) / (0.5 * kPi));
          // Along the route; further where the route bends (a chord is shorter than its arc) so that the person
          // stays >= 1.5 m from the camera, and never walking backwards.
          double gap = std::max(1.5, (gap0 + amp * std::sin(2 * kPi * t / period + phase)) * (1.0 - 0.1 * corner));
          double px = 0, py = 0;
          auto place = [&](double g) {
            double rx, ry, heading;
            sc.agv.route.sample(sc.agv.s_start + s + g, rx, ry, heading);
            px = rx - lateral * std::sin(heading);
            py = ry + lateral * std::cos(heading);
          };
          gap = std::max(gap, s_person - s);
          place(gap);
          while (std::hypot(px - x, py - y) < 1.5 && gap < 4.0) place(gap += 0.02);
          s_person = s + gap;
          path.push_back({t, px, py});
        }
        sc.actors.push_back(make_actor(1, ActorClass::kPerson, "walks ahead of the AGV around the loop", path, ra));
      }
      // A person crossing through the loop's cross-aisle in front of the AGV: close (1.6-2.4 m) in scene4, beyond
      // the leading person (3.3-4.1 m) in scene5.
      {
        const int id = name == "scene5" ? 2 : 1;
        const bool north_to_south = r.chance(0.5);
        b.add_best(24, [&](int i) {
          Rng ri = r.fork(static_cast<uint64_t>(i));
          const double ahead =
              name == "scene5" ? 3.3 + 0.2 * i + ri.uniform(0.0, 0.8) : 1.6 + 0.1 * i + ri.uniform(0.0, 0.8);
          return b.loop_crossing_person(id, north_to_south, chosen.leg_y, b.time_at_distance(chosen.distance - ahead),
                                        ri);
        });
      }
      if (name == "scene4") {  // a forklift parked in the east lane (never moves)
        Rng rf = rng.fork(9);
        std::vector<Waypoint> path = {{0.0, L.east_lane_x + rf.uniform(-0.1, 0.1), 11.3 + rf.uniform(0.0, 1.0)}};
        Actor a = make_actor(2, ActorClass::kForklift, "parked (never moves)", path, rf);
        a.initial_yaw_rad = 0.5 * kPi;
        sc.actors.push_back(a);
      } else {
        // Person 3: stands picking at the pallets along the east wall, then walks away north and west.
        Rng rp = rng.fork(10);
        b.add_best(20, [&](int i) {
          Rng ri = rp.fork(static_cast<uint64_t>(i));
          const double y = ri.uniform(13.5, 18.5);
          PathBuilder pb(37.85, y);
          pb.pts.front().t_s = T * (0.45 + 0.02 * i) + ri.uniform(0.0, 1.0);
          const double speed = ri.uniform(1.1, 1.3);
          pb.walk_to(37.85, L.loop_north_area_y + 0.3, speed);
          pb.walk_to(27.5 + ri.uniform(0.0, 2.0), L.loop_north_area_y + 0.3, speed);
          Actor a = make_actor(3, ActorClass::kPerson, "stands picking, then walks away", pb.pts, ri);
          a.initial_yaw_rad = 0.0;  // facing the pallets at the east wall while standing
          return a;
        });
        // Another AGV: parked at the south end of the east lane, drives north, parks again.
        Rng rv = rng.fork(11);
        b.add_best(24, [&](int i) {
          Rng ri = rv.fork(static_cast<uint64_t>(i));
          PathBuilder pb(36.55, 9.6);
          pb.pts.front().t_s = T * (0.1 + 0.03 * i) + ri.uniform(0.0, 1.0);
          pb.walk_to(36.55, L.loop_north_area_y - 0.2, ri.uniform(0.9, 1.1));
          return make_actor(4, ActorClass::kAgv, "parked, drives north along the east lane, parks", pb.pts, ri);
        });
      }
    }
  }
  b.finalize_clearances();
  return sc;
}

}  // namespace agvslam::sim
