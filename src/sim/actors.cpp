#include "agvslam/sim/actors.h"

#include <algorithm>
#include <cmath>

#include "agvslam/sim/random.h"

namespace agvslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMovingSpeed = 0.05;      // m/s
constexpr double kMovingTurnRate = 0.052;  // rad/s (3 degrees/s)
constexpr double kMovingLiftRate = 0.02;   // m/s

double wrap_angle(double a) { return std::atan2(std::sin(a), std::cos(a)); }
double lerp_angle(double a, double b, double t) { return a + wrap_angle(b - a) * t; }
// Both waypoints of a stretch give the heading.
bool explicit_yaw(const Waypoint& p, const Waypoint& q) { return std::isfinite(p.yaw_rad) && std::isfinite(q.yaw_rad); }
double smooth01(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

using Segment = ActorSegment;

Segment compute_segment(const Actor& a, std::size_t k) {
  const Waypoint& p = a.path[k];
  const Waypoint& q = a.path[k + 1];
  Segment s;
  s.t0 = p.t_s;
  s.t1 = q.t_s;
  s.length_m = std::hypot(q.x - p.x, q.y - p.y);
  s.dir_rad = std::atan2(q.y - p.y, q.x - p.x);
  const double dt = s.t1 - s.t0;
  s.moving = dt > 0 && s.length_m / dt > kMovingSpeed;
  if (dt > 0 && !s.moving) {
    const double turn = explicit_yaw(p, q) ? std::fabs(wrap_angle(q.yaw_rad - p.yaw_rad)) : 0.0;
    s.moving = turn / dt > kMovingTurnRate || std::fabs(q.lift_m - p.lift_m) / dt > kMovingLiftRate;
  }
  return s;
}

bool prepared(const Actor& a) { return !a.path.empty() && a.segments.size() + 1 == a.path.size(); }

// Segment k (from the prepared cache when it is up to date).
Segment segment(const Actor& a, std::size_t k) {
  if (prepared(a)) return a.segments[k];
  return compute_segment(a, k);
}

// Index k of the segment [path[k], path[k+1]] containing t, or -1 before the path / n-1 after it.
long segment_index(const Actor& a, double t) {
  if (a.path.size() < 2 || t < a.path.front().t_s) return -1;
  if (t >= a.path.back().t_s) return static_cast<long>(a.path.size()) - 1;
  const auto it =
      std::upper_bound(a.path.begin(), a.path.end(), t, [](double tt, const Waypoint& w) { return tt < w.t_s; });
  return static_cast<long>(it - a.path.begin()) - 1;
}

// Heading while standing in/around segment k: the last direction travelled, else the initial heading.
double standing_yaw(const Actor& a, long k) {
  const long n_seg = static_cast<long>(a.path.size()) - 1;
  for (long i = std::min(k, n_seg - 1); i >= 0; --i) {
    const Segment s = segment(a, static_cast<std::size_t>(i));
    if (s.moving && s.length_m > 0) return s.dir_rad;
  }
  return a.initial_yaw_rad;
}

}  // namespace

std::string to_string(ActorClass cls) {
  switch (cls) {
    case ActorClass::kPerson:
      return "person";
    case ActorClass::kForklift:
      return "forklift";
    case ActorClass::kAgv:
      return "agv";
    case ActorClass::kPallet:
      return "pallet";
  }
  return "unknown";
}

double actor_radius_m(ActorClass cls) {
  switch (cls) {
    case ActorClass::kPerson:
      return 0.35;
    case ActorClass::kForklift:
      return 1.6;
    case ActorClass::kAgv:
      return 0.75;
    case ActorClass::kPallet:
      return 0.75;
  }
  return 1.0;
}

double actor_distance_m(const Actor& a, double t) {
  const long k = segment_index(a, t);
  if (k < 0) return 0;
  const long n_seg = static_cast<long>(a.path.size()) - 1;
  if (prepared(a)) {
    if (k >= n_seg) return n_seg > 0 ? a.segments.back().distance_before_m + a.segments.back().length_m : 0.0;
    const Segment& s = a.segments[static_cast<std::size_t>(k)];
    return s.distance_before_m + (s.t1 > s.t0 ? s.length_m * (t - s.t0) / (s.t1 - s.t0) : 0.0);
  }
  double d = 0;
  for (long i = 0; i < std::min(k, n_seg); ++i) d += segment(a, static_cast<std::size_t>(i)).length_m;
  if (k < n_seg) {
    const Segment s = segment(a, static_cast<std::size_t>(k));
    if (s.t1 > s.t0) d += s.length_m * (t - s.t0) / (s.t1 - s.t0);
  }
  return d;
}

void prepare_actor(Actor& a) {
  a.segments.clear();
  if (a.path.size() < 2) return;
  double walked = 0;
  for (std::size_t k = 0; k + 1 < a.path.size(); ++k) {
    Segment s = compute_segment(a, k);
    s.distance_before_m = walked;
    walked += s.length_m;
    a.segments.push_back(s);
  }
  // Moving runs.
  std::size_t i = 0;
  while (i < a.segments.size()) {
    std::size_t j = i;
    while (j + 1 < a.segments.size() && a.segments[j + 1].moving == a.segments[i].moving) ++j;
    for (std::size_t k = i; k <= j; ++k) {
      a.segments[k].run_t0 = a.segments[i].t0;
      a.segments[k].run_t1 = a.segments[j].t1;
    }
    i = j + 1;
  }
}

namespace {

// The state with the heading along the direction of travel (the default when waypoints give none).
ActorState state_heading_along_travel(const Actor& a, double t) {
  ActorState st;
  if (a.path.empty()) return st;
  const long n_seg = static_cast<long>(a.path.size()) - 1;
  const long k = segment_index(a, t);
  if (k < 0 || k >= n_seg) {
    const Waypoint& w = k < 0 ? a.path.front() : a.path.back();
    st.x = w.x;
    st.y = w.y;
    st.yaw_rad = standing_yaw(a, k < 0 ? -1 : n_seg - 1);
    st.gait_phase_rad = 2 * kPi * actor_distance_m(a, t) / 1.4;
    return st;
  }
  const Segment s = segment(a, static_cast<std::size_t>(k));
  const Waypoint& p = a.path[static_cast<std::size_t>(k)];
  const Waypoint& q = a.path[static_cast<std::size_t>(k) + 1];
  const double f = s.t1 > s.t0 ? (t - s.t0) / (s.t1 - s.t0) : 1.0;
  st.x = p.x + (q.x - p.x) * f;
  st.y = p.y + (q.y - p.y) * f;
  st.speed_mps = s.t1 > s.t0 ? s.length_m / (s.t1 - s.t0) : 0.0;
  st.moving = s.moving;
  const double stride_m = 1.4 * (a.look.height_m / 1.75);
  st.gait_phase_rad = 2 * kPi * actor_distance_m(a, t) / stride_m;
  if (!s.moving) {
    st.yaw_rad = standing_yaw(a, k);
    st.speed_mps = 0;
    return st;
  }
  // Heading: the segment's direction, blended with the neighbours' near the waypoints. After standing, the
  // actor turns during its first 0.6 s of motion (so it never rotates while not moving).
  const double dur = s.t1 - s.t0;
  double yaw = s.dir_rad;
  const bool prev_moving = k > 0 && segment(a, static_cast<std::size_t>(k - 1)).moving;
  const bool next_moving = k + 1 < n_seg && segment(a, static_cast<std::size_t>(k + 1)).moving;
  const double blend = std::min(0.3, 0.5 * dur);
  if (prev_moving) {
    const Segment prev = segment(a, static_cast<std::size_t>(k - 1));
    const double b = std::min(blend, 0.5 * (prev.t1 - prev.t0));
    if (t - s.t0 < b) yaw = lerp_angle(prev.dir_rad, s.dir_rad, 0.5 + 0.5 * (t - s.t0) / b);
  } else {
    const double from = standing_yaw(a, k - 1);
    const double turn = std::min(0.6, dur);
    if (t - s.t0 < turn) yaw = lerp_angle(from, s.dir_rad, smooth01((t - s.t0) / turn));
  }
  if (next_moving && s.t1 - t < blend) {
    const Segment next = segment(a, static_cast<std::size_t>(k + 1));
    const double b = std::min(blend, 0.5 * (next.t1 - next.t0));
    if (s.t1 - t < b) yaw = lerp_angle(s.dir_rad, next.dir_rad, 0.5 - 0.5 * (s.t1 - t) / b);
  }
  st.yaw_rad = wrap_angle(yaw);
  // Limb swing: grows with speed, fades in/out over 0.4 s at the ends of a walk.
  double run_start = s.run_t0, run_end = s.run_t1;
  if (!prepared(a)) {
    long first = k, last = k;
    while (first > 0 && segment(a, static_cast<std::size_t>(first - 1)).moving) --first;
    while (last + 1 < n_seg && segment(a, static_cast<std::size_t>(last + 1)).moving) ++last;
    run_start = a.path[static_cast<std::size_t>(first)].t_s;
    run_end = a.path[static_cast<std::size_t>(last) + 1].t_s;
  }
  const double ramp = std::clamp(std::min(t - run_start, run_end - t) / 0.4, 0.0, 1.0);
  st.gait_amplitude = ramp * std::clamp(st.speed_mps / 1.0, 0.0, 1.0);
  return st;
}

}  // namespace

ActorState actor_state(const Actor& a, double t) {
  ActorState st = state_heading_along_travel(a, t);
  if (a.path.empty()) return st;
  st.distance_m = actor_distance_m(a, t);
  const long n_seg = static_cast<long>(a.path.size()) - 1;
  const long k = segment_index(a, t);
  if (k < 0 || k >= n_seg) {
    const Waypoint& w = k < 0 ? a.path.front() : a.path.back();
    st.lift_m = w.lift_m;
    if (std::isfinite(w.yaw_rad)) st.yaw_rad = wrap_angle(w.yaw_rad);
    return st;
  }
  const Waypoint& p = a.path[static_cast<std::size_t>(k)];
  const Waypoint& q = a.path[static_cast<std::size_t>(k) + 1];
  const double f = q.t_s > p.t_s ? (t - p.t_s) / (q.t_s - p.t_s) : 1.0;
  st.lift_m = p.lift_m + (q.lift_m - p.lift_m) * f;
  if (explicit_yaw(p, q)) st.yaw_rad = wrap_angle(lerp_angle(p.yaw_rad, q.yaw_rad, f));
  return st;
}

void actor_track_point(const Actor& a, double distance_m, double& x, double& y, double& heading_rad) {
  if (a.path.empty()) {
    x = y = heading_rad = 0;
    return;
  }
  const Waypoint& first = a.path.front();
  if (distance_m <= 0 || a.path.size() < 2) {
    const double yaw = std::isfinite(first.yaw_rad) ? first.yaw_rad : a.initial_yaw_rad;
    const double back = std::max(0.0, -distance_m);
    x = first.x - back * std::cos(yaw);
    y = first.y - back * std::sin(yaw);
    heading_rad = yaw;
    return;
  }
  for (std::size_t k = 0; k + 1 < a.path.size(); ++k) {
    const Segment s = segment(a, k);
    double before = 0;
    if (prepared(a)) {
      before = s.distance_before_m;
    } else {
      for (std::size_t i = 0; i < k; ++i) before += segment(a, i).length_m;
    }
    if (s.length_m > 0 && distance_m <= before + s.length_m) {
      const double f = (distance_m - before) / s.length_m;
      const Waypoint& p = a.path[k];
      const Waypoint& q = a.path[k + 1];
      x = p.x + (q.x - p.x) * f;
      y = p.y + (q.y - p.y) * f;
      heading_rad = s.dir_rad;
      return;
    }
  }
  const Waypoint& last = a.path.back();
  x = last.x;
  y = last.y;
  heading_rad = standing_yaw(a, static_cast<long>(a.path.size()) - 2);
}

namespace {

struct PosingContext {
  DynamicObject& obj;
  float c, s;
  V3 to_map(const V3& local) const {
    return {obj.origin.x + c * local.x - s * local.y, obj.origin.y + s * local.x + c * local.y, obj.origin.z + local.z};
  }
  void box(float x0, float x1, float y0, float y1, float z0, float z1, Material m, uint8_t part = 0) {
    DynamicPrimitive p;
    p.shape = PrimitiveShape::kBox;
    p.material = m;
    p.a = to_map({0.5f * (x0 + x1), 0.5f * (y0 + y1), 0.5f * (z0 + z1)});
    p.half = {0.5f * (x1 - x0), 0.5f * (y1 - y0), 0.5f * (z1 - z0)};
    p.part = part;
    obj.primitives.push_back(p);
  }
  void capsule(const V3& a_local, const V3& b_local, float r, Material m, uint8_t part) {
    DynamicPrimitive p;
    p.shape = PrimitiveShape::kCapsule;
    p.material = m;
    p.a = to_map(a_local);
    p.b = to_map(b_local);
    p.radius = r;
    p.part = part;
    obj.primitives.push_back(p);
  }
  void sphere(const V3& c_local, float r, Material m, uint8_t part) {
    DynamicPrimitive p;
    p.shape = PrimitiveShape::kSphere;
    p.material = m;
    p.a = to_map(c_local);
    p.radius = r;
    p.part = part;
    obj.primitives.push_back(p);
  }
};

constexpr float kForkTravelZ = 0.12f;     // forks' height above the floor while driving, m
constexpr float kPalletHeightM = 0.144f;  // a pallet's height, m

// Goods of `load` standing on [x0, x1] x [y0, y1] at height z (object frame): one stretch-wrapped block, cartons
// in layers or stacked crates (their arrangement from `seed`); body parts 10 and up.
void add_goods(PosingContext& ctx, float x0, float x1, float y0, float y1, float z, const Load& load, uint32_t seed) {
  const float top = z + load.height_m;
  switch (load.kind) {
    case Load::Kind::kNone:
      return;
    case Load::Kind::kWrapped:
      ctx.box(x0, x1, y0, y1, z, top, Material::kWrappedLoad, 10);
      return;
    case Load::Kind::kCartons: {
      const int nx = (x1 - x0) > 0.9f ? 2 : 1, ny = (y1 - y0) > 0.6f ? 2 : 1;
      const float cx = (x1 - x0) / static_cast<float>(nx), cy = (y1 - y0) / static_cast<float>(ny);
      uint8_t part = 10;
      float zz = z;
      for (uint32_t layer = 0; zz < top - 0.15f && part < 250; ++layer) {
        const float h = std::min(top - zz, 0.26f + 0.16f * unit_from_hash(hash32(seed, layer)));
        for (int i = 0; i < nx; ++i)
          for (int j = 0; j < ny; ++j) {
            const uint32_t hc = hash32(seed, layer, static_cast<uint32_t>(i * ny + j + 1));
            const float inset = 0.008f + 0.02f * unit_from_hash(hc);
            const float shift = 0.02f * (unit_from_hash(hash32(hc)) - 0.5f);
            ctx.box(x0 + cx * static_cast<float>(i) + inset + shift,
                    x0 + cx * static_cast<float>(i + 1) - inset + shift, y0 + cy * static_cast<float>(j) + inset,
                    y0 + cy * static_cast<float>(j + 1) - inset, zz, zz + h - 0.005f, Material::kCarton, part++);
          }
        zz += h;
      }
      return;
    }
    case Load::Kind::kCrates: {
      const int nx = (x1 - x0) > 0.9f ? 2 : 1, ny = (y1 - y0) > 0.6f ? 2 : 1;
      const float cx = (x1 - x0) / static_cast<float>(nx), cy = (y1 - y0) / static_cast<float>(ny);
      const float crate_h = 0.22f + 0.12f * unit_from_hash(hash32(seed, 77U));
      const int layers = std::max(1, static_cast<int>(load.height_m / crate_h));
      uint8_t part = 10;
      for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j) {
          // One column per crate stack: the crates' own texture draws the layers.
          const int n = std::max(1, layers - static_cast<int>(hash32(seed, static_cast<uint32_t>(i * ny + j)) % 2U));
          ctx.box(x0 + cx * static_cast<float>(i) + 0.01f, x0 + cx * static_cast<float>(i + 1) - 0.01f,
                  y0 + cy * static_cast<float>(j) + 0.01f, y0 + cy * static_cast<float>(j + 1) - 0.01f, z,
                  z + crate_h * static_cast<float>(n) - 0.005f, Material::kCrate, part++);
        }
      return;
    }
  }
}

// A person standing or walking (gait from the state), in the object's frame: torso (part 0), head (1), neck (2),
// upper and lower arms (3, 4), thighs and shins (5, 6), shoes (7); what the hands carry (12, 13).
void pose_person(PosingContext& ctx, const PersonLook& look, const ActorState& st) {
  const float h = look.height_m;
  const float sc = h / 1.75f;
  const float wide = sc * look.build, deep = sc * look.girth;
  const float amp = static_cast<float>(st.gait_amplitude);
  const float phase = static_cast<float>(st.gait_phase_rad);
  const float bob = 0.018f * amp * std::fabs(std::cos(phase));
  ctx.obj.origin.z = 0.0f;
  const float hip_z = 0.50f * h + bob;
  const float shoulder_z = 0.815f * h + bob;
  const float thigh = 0.245f * h, shin = 0.235f * h;
  const float upper = 0.17f * h, fore = 0.165f * h;
  for (int side = 0; side < 2; ++side) {
    const float sign_y = side == 0 ? 1.0f : -1.0f;  // 0: left (+y)
    const float ph = phase + (side == 0 ? 0.0f : 3.14159265f);
    // Legs: hip swing +-0.42 rad, knee flexes on the forward swing.
    const float hip_angle = 0.42f * amp * std::sin(ph);
    const float knee = amp * (0.15f + 0.45f * std::max(0.0f, std::cos(ph)));
    const V3 hip{0.0f, sign_y * 0.095f * wide, hip_z};
    const V3 knee_p{hip.x + thigh * std::sin(hip_angle), hip.y, hip.z - thigh * std::cos(hip_angle)};
    const float shin_angle = hip_angle - knee;
    const V3 ankle{knee_p.x + shin * std::sin(shin_angle), hip.y, knee_p.z - shin * std::cos(shin_angle)};
    ctx.capsule(hip, knee_p, 0.078f * sc, Material::kPersonTrousers, 5);
    ctx.capsule(knee_p, ankle, 0.06f * sc, Material::kPersonTrousers, 6);
    const float foot_pitch = shin_angle * 0.6f;
    const V3 toe{ankle.x + 0.17f * sc * std::cos(foot_pitch), ankle.y, ankle.z - 0.17f * sc * std::sin(foot_pitch)};
    ctx.capsule({ankle.x - 0.04f * sc, ankle.y, ankle.z}, toe, 0.045f * sc, Material::kTyre, 7);
    // Arms: the one on this side swings against the leg on this side, unless the hand holds something.
    const V3 shoulder{0.0f, sign_y * 0.215f * wide, shoulder_z - 0.05f * sc};
    V3 elbow, hand;
    const bool holds = look.carry == PersonLook::Carry::kBox ||
                       (look.carry == PersonLook::Carry::kScanner && side == 1) ||
                       (look.carry == PersonLook::Carry::kPhone && side == 0);
    if (holds && look.carry == PersonLook::Carry::kPhone) {  // elbow out, hand at the ear
      elbow = {shoulder.x + 0.06f * sc, shoulder.y + sign_y * 0.08f * sc, shoulder.z - 0.2f * sc};
      hand = {0.04f * sc, sign_y * 0.12f * sc, h - 0.13f * sc + bob};
    } else if (holds) {  // forearm forward, the hand in front of the waist
      const float a_upper = 0.3f, a_fore = 1.35f;
      elbow = {shoulder.x + upper * std::sin(a_upper), shoulder.y - sign_y * 0.01f * sc,
               shoulder.z - upper * std::cos(a_upper)};
      hand = {elbow.x + fore * std::sin(a_fore), elbow.y - sign_y * 0.02f * sc, elbow.z - fore * std::cos(a_fore)};
    } else {
      const float arm_angle = -0.38f * look.arm_swing * amp * std::sin(ph);
      elbow = {shoulder.x + upper * std::sin(arm_angle), shoulder.y + sign_y * 0.02f * sc,
               shoulder.z - upper * std::cos(arm_angle)};
      const float fore_angle = arm_angle + 0.2f + 0.35f * amp * std::max(0.0f, std::sin(-ph));
      hand = {elbow.x + fore * std::sin(fore_angle), elbow.y + sign_y * 0.01f * sc,
              elbow.z - fore * std::cos(fore_angle)};
    }
    ctx.capsule(shoulder, elbow, 0.052f * sc, Material::kPersonShirt, 3);
    ctx.capsule(elbow, hand, 0.043f * sc, Material::kPersonShirt, 4);
    if (holds && look.carry == PersonLook::Carry::kScanner)
      ctx.box(hand.x - 0.02f, hand.x + 0.12f, hand.y - 0.03f, hand.y + 0.03f, hand.z, hand.z + 0.035f,
              Material::kVehicleDark, 13);
    if (holds && look.carry == PersonLook::Carry::kPhone)
      ctx.box(hand.x - 0.04f, hand.x + 0.03f, hand.y - 0.01f, hand.y + 0.005f, hand.z - 0.04f, hand.z + 0.08f,
              Material::kVehicleDark, 13);
    if (holds && look.carry == PersonLook::Carry::kBox && side == 0)  // between the hands
      ctx.box(0.17f * deep, hand.x + 0.06f, -hand.y + 0.03f, hand.y - 0.03f, hand.z - 0.1f, hand.z + 0.22f,
              Material::kCarton, 12);
  }
  // Torso (pelvis to shoulders), neck, head.
  ctx.box(-0.115f * deep, 0.115f * deep, -0.19f * wide, 0.19f * wide, hip_z - 0.06f * sc, shoulder_z + 0.02f * sc,
          Material::kPersonShirt, 0);
  ctx.capsule({0.0f, 0.0f, shoulder_z}, {0.01f * sc, 0.0f, shoulder_z + 0.07f * sc}, 0.05f * sc, Material::kPersonSkin,
              2);
  const float head_r = 0.105f * sc;
  ctx.sphere({0.015f * sc, 0.0f, h - head_r + bob}, head_r, Material::kPersonHead, 1);
}

// A forklift's driver seated behind the dashboard, hands on the wheel (the same parts as a standing person).
void pose_driver(PosingContext& ctx, const PersonLook& look) {
  const float sc = look.height_m / 1.75f;
  const float wide = sc * look.build, deep = sc * look.girth;
  const float seat_z = 1.38f, hip_x = -0.33f;
  const float shoulder_z = seat_z + 0.5f * sc;
  ctx.box(hip_x - 0.11f * deep, hip_x + 0.11f * deep, -0.18f * wide, 0.18f * wide, seat_z, shoulder_z + 0.02f * sc,
          Material::kPersonShirt, 0);
  for (float sign_y : {1.0f, -1.0f}) {
    const V3 hip{hip_x, sign_y * 0.095f * wide, seat_z + 0.06f};
    const V3 knee{hip_x + 0.42f * sc, sign_y * 0.12f * wide, seat_z + 0.08f};
    ctx.capsule(hip, knee, 0.078f * sc, Material::kPersonTrousers, 5);
    ctx.capsule(knee, {knee.x + 0.05f, knee.y, 1.1f}, 0.06f * sc, Material::kPersonTrousers, 6);
    const V3 shoulder{hip_x, sign_y * 0.2f * wide, shoulder_z - 0.05f * sc};
    const V3 elbow{hip_x + 0.22f * sc, sign_y * 0.23f * wide, shoulder_z - 0.3f * sc};
    ctx.capsule(shoulder, elbow, 0.052f * sc, Material::kPersonShirt, 3);
    ctx.capsule(elbow, {0.22f, sign_y * 0.14f, 1.42f}, 0.043f * sc, Material::kPersonShirt, 4);
  }
  ctx.capsule({hip_x, 0.0f, shoulder_z}, {hip_x + 0.01f, 0.0f, shoulder_z + 0.07f * sc}, 0.05f * sc,
              Material::kPersonSkin, 2);
  const float head_r = 0.105f * sc;
  // The head stays under the overhead guard's roof (2.1 m).
  const float head_z = std::min(shoulder_z + 0.07f * sc + 0.9f * head_r, 2.08f - head_r);
  ctx.sphere({hip_x + 0.02f, 0.0f, head_z}, head_r, Material::kPersonHead, 1);
}

// The object's bounding box from its primitives.
void set_bounds(DynamicObject& obj) {
  const float c = obj.cos_yaw, s = obj.sin_yaw;
  V3 lo{kInfinity, kInfinity, kInfinity}, hi{-kInfinity, -kInfinity, -kInfinity};
  for (const auto& p : obj.primitives) {
    switch (p.shape) {
      case PrimitiveShape::kBox: {
        const float ex = std::fabs(c) * p.half.x + std::fabs(s) * p.half.y;
        const float ey = std::fabs(s) * p.half.x + std::fabs(c) * p.half.y;
        lo = vmin(lo, p.a - V3{ex, ey, p.half.z});
        hi = vmax(hi, p.a + V3{ex, ey, p.half.z});
        break;
      }
      case PrimitiveShape::kSphere:
        lo = vmin(lo, p.a - V3{p.radius, p.radius, p.radius});
        hi = vmax(hi, p.a + V3{p.radius, p.radius, p.radius});
        break;
      case PrimitiveShape::kCapsule: {
        const V3 r{p.radius, p.radius, p.radius};
        lo = vmin(lo, vmin(p.a, p.b) - r);
        hi = vmax(hi, vmax(p.a, p.b) + r);
        break;
      }
    }
  }
  obj.lo = lo - V3{1e-3f, 1e-3f, 1e-3f};
  obj.hi = hi + V3{1e-3f, 1e-3f, 1e-3f};
}

}  // namespace

void pose_actor(const Actor& actor, const ActorState& st, DynamicObject& obj) {
  obj.id = actor.id;
  obj.cls = actor.cls;
  obj.moving = st.moving;
  obj.look = actor.look;
  obj.vehicle = actor.vehicle;
  obj.seed = actor.seed;
  obj.walk_phase = static_cast<float>(st.gait_phase_rad);
  obj.origin = {static_cast<float>(st.x), static_cast<float>(st.y), 0.0f};
  obj.cos_yaw = static_cast<float>(std::cos(st.yaw_rad));
  obj.sin_yaw = static_cast<float>(std::sin(st.yaw_rad));
  obj.primitives.clear();
  PosingContext ctx{obj, obj.cos_yaw, obj.sin_yaw};

  if (actor.cls == ActorClass::kPerson) {
    pose_person(ctx, actor.look, st);
  } else if (actor.cls == ActorClass::kForklift) {
    ctx.box(-0.95f, 0.75f, -0.55f, 0.55f, 0.14f, 1.05f, Material::kVehicleBody, 0);    // chassis
    ctx.box(-1.18f, -0.95f, -0.52f, 0.52f, 0.16f, 1.12f, Material::kVehicleMetal, 1);  // counterweight
    ctx.box(0.35f, 0.75f, 0.42f, 0.6f, 0.0f, 0.44f, Material::kTyre, 2);               // front tyres
    ctx.box(0.35f, 0.75f, -0.6f, -0.42f, 0.0f, 0.44f, Material::kTyre, 2);
    ctx.box(-0.9f, -0.55f, 0.4f, 0.56f, 0.0f, 0.36f, Material::kTyre, 2);  // rear tyres
    ctx.box(-0.9f, -0.55f, -0.56f, -0.4f, 0.0f, 0.36f, Material::kTyre, 2);
    for (float px : {-0.62f, 0.42f})
      for (float py : {-0.5f, 0.5f})
        ctx.box(px - 0.03f, px + 0.03f, py - 0.03f, py + 0.03f, 1.05f, 2.12f, Material::kVehicleGuard, 3);
    ctx.box(-0.66f, 0.46f, -0.54f, 0.54f, 2.1f, 2.16f, Material::kVehicleGuard, 3);   // roof
    ctx.box(-0.55f, -0.15f, -0.26f, 0.26f, 1.05f, 1.38f, Material::kVehicleDark, 4);  // seat
    pose_driver(ctx, actor.look);
    ctx.box(0.28f, 0.62f, -0.42f, 0.42f, 1.05f, 1.32f, Material::kVehicleBody, 5);  // dashboard
    ctx.box(0.8f, 0.9f, 0.3f, 0.4f, 0.08f, 2.3f, Material::kVehicleMetal, 6);       // mast
    ctx.box(0.8f, 0.9f, -0.4f, -0.3f, 0.08f, 2.3f, Material::kVehicleMetal, 6);
    ctx.box(0.8f, 0.9f, -0.4f, 0.4f, 2.2f, 2.3f, Material::kVehicleMetal, 6);
    const float fork_z = kForkTravelZ + static_cast<float>(st.lift_m);
    ctx.box(0.91f, 0.97f, -0.46f, 0.46f, fork_z, fork_z + 0.62f, Material::kVehicleDark, 7);  // carriage
    ctx.box(0.97f, 2.1f, 0.2f, 0.32f, fork_z, fork_z + 0.05f, Material::kVehicleMetal, 8);    // forks
    ctx.box(0.97f, 2.1f, -0.32f, -0.2f, fork_z, fork_z + 0.05f, Material::kVehicleMetal, 8);
    if (actor.vehicle.load.kind != Load::Kind::kNone) {  // a loaded pallet resting on the forks
      ctx.box(1.0f, 2.2f, -0.4f, 0.4f, fork_z + 0.05f, fork_z + 0.194f, Material::kPallet, 9);
      add_goods(ctx, 1.03f, 2.17f, -0.38f, 0.38f, fork_z + 0.194f, actor.vehicle.load, actor.seed);
    }
  } else if (actor.cls == ActorClass::kPallet) {
    obj.origin.z = static_cast<float>(st.lift_m);
    ctx.box(-0.6f, 0.6f, -0.4f, 0.4f, 0.0f, kPalletHeightM, Material::kPallet, 9);  // a 1.2 m x 0.8 m pallet
    add_goods(ctx, -0.58f, 0.58f, -0.38f, 0.38f, kPalletHeightM, actor.vehicle.load, actor.seed);
  } else if (actor.vehicle.tugger_carts > 0) {  // automated tugger; its carts are trailers
    ctx.box(-0.7f, 0.55f, -0.34f, 0.34f, 0.07f, 0.55f, Material::kVehicleBody, 0);
    ctx.box(0.55f, 0.62f, -0.3f, 0.3f, 0.1f, 0.3f, Material::kVehicleDark, 4);  // bumper with the safety scanner
    for (float px : {-0.5f, 0.3f})
      for (float py : {-0.4f, 0.34f}) ctx.box(px - 0.1f, px + 0.1f, py, py + 0.06f, 0.0f, 0.2f, Material::kTyre, 2);
    ctx.box(-0.65f, -0.35f, -0.2f, 0.2f, 0.55f, 1.2f, Material::kVehicleBody, 5);     // control tower
    ctx.box(-0.55f, -0.45f, -0.05f, 0.05f, 1.2f, 1.32f, Material::kVehicleGuard, 3);  // beacon
    ctx.box(-0.95f, -0.7f, -0.04f, 0.04f, 0.22f, 0.28f, Material::kVehicleMetal, 6);  // tow hitch
  } else {                                                                            // AGV with a cart of crates
    ctx.box(-0.6f, 0.6f, -0.4f, 0.4f, 0.07f, 0.34f, Material::kVehicleBody, 0);
    ctx.box(-0.45f, -0.25f, 0.35f, 0.42f, 0.0f, 0.16f, Material::kTyre, 2);
    ctx.box(-0.45f, -0.25f, -0.42f, -0.35f, 0.0f, 0.16f, Material::kTyre, 2);
    ctx.box(0.25f, 0.45f, 0.35f, 0.42f, 0.0f, 0.16f, Material::kTyre, 2);
    ctx.box(0.25f, 0.45f, -0.42f, -0.35f, 0.0f, 0.16f, Material::kTyre, 2);
    ctx.box(0.48f, 0.58f, -0.06f, 0.06f, 0.34f, 0.44f, Material::kVehicleDark, 4);  // lidar
    for (float px : {-0.52f, 0.36f})
      for (float py : {-0.34f, 0.31f})
        ctx.box(px, px + 0.03f, py, py + 0.03f, 0.34f, 1.35f, Material::kVehicleMetal, 6);
    ctx.box(-0.54f, 0.41f, -0.36f, 0.36f, 0.34f, 0.38f, Material::kVehicleMetal, 6);
    ctx.box(-0.54f, 0.41f, -0.36f, 0.36f, 0.84f, 0.87f, Material::kVehicleMetal, 6);
    ctx.box(-0.5f, -0.06f, -0.32f, 0.3f, 0.38f, 0.72f, Material::kCrate, 9);
    ctx.box(-0.04f, 0.38f, -0.32f, 0.3f, 0.38f, 0.66f, Material::kCarton, 10);
    ctx.box(-0.48f, 0.36f, -0.3f, 0.28f, 0.87f, 1.2f, Material::kCarton, 11);
  }
  set_bounds(obj);
}

int trailer_count(const Actor& actor) {
  return actor.cls == ActorClass::kAgv ? static_cast<int>(actor.vehicle.tugger_carts) : 0;
}

double trailer_offset_m(int k) {
  // The tractor's hitch is 0.95 m behind its origin and a cart's drawbar reaches 1.35 m ahead of its centre,
  // its rear is 0.8 m behind it.
  return 0.95 + 1.35 + 2.15 * k;
}

void pose_trailer(const Actor& actor, const ActorState& st, int k, DynamicObject& obj) {
  double x, y, heading;
  actor_track_point(actor, st.distance_m - trailer_offset_m(k), x, y, heading);
  obj.id = actor.id;
  obj.cls = actor.cls;
  obj.moving = st.moving;
  obj.look = actor.look;
  obj.vehicle = actor.vehicle;
  obj.seed = hash32(actor.seed, static_cast<uint32_t>(k + 1));
  obj.walk_phase = 0;
  obj.origin = {static_cast<float>(x), static_cast<float>(y), 0.0f};
  obj.cos_yaw = static_cast<float>(std::cos(heading));
  obj.sin_yaw = static_cast<float>(std::sin(heading));
  obj.primitives.clear();
  PosingContext ctx{obj, obj.cos_yaw, obj.sin_yaw};
  // A 1.6 m x 1.2 m cart (a 1.2 m x 0.8 m pallet's goods fit across it).
  ctx.box(-0.8f, 0.8f, -0.6f, 0.6f, 0.26f, 0.32f, Material::kVehicleMetal, 6);  // deck
  for (float px : {-0.7f, 0.55f})
    for (float py : {-0.58f, 0.5f}) ctx.box(px, px + 0.15f, py, py + 0.08f, 0.0f, 0.2f, Material::kTyre, 2);
  ctx.box(0.8f, 1.35f, -0.03f, 0.03f, 0.24f, 0.28f, Material::kVehicleMetal, 6);  // drawbar
  for (float px : {-0.8f, 0.75f})
    for (float py : {-0.6f, 0.55f}) ctx.box(px, px + 0.05f, py, py + 0.05f, 0.32f, 1.9f, Material::kVehicleMetal, 6);
  ctx.box(-0.8f, 0.8f, 0.55f, 0.6f, 1.85f, 1.9f, Material::kVehicleMetal, 6);  // top rails
  ctx.box(-0.8f, 0.8f, -0.6f, -0.55f, 1.85f, 1.9f, Material::kVehicleMetal, 6);
  Load load = actor.vehicle.load;
  load.height_m = std::min(load.height_m, 1.5f);  // below the top rails
  add_goods(ctx, -0.72f, 0.72f, -0.52f, 0.52f, 0.32f, load, obj.seed);
  set_bounds(obj);
}

}  // namespace agvslam::sim
