#pragma once
// Small float geometry for the ray caster: 3-vectors, rays and ray/primitive intersection.
//
// Rays are r(t) = origin + t * dir with a NON-normalised dir: the renderer builds dir = R_m_c * (x, y, 1) for a
// pixel, so the ray parameter t of a hit is directly the depth along the optical axis (z in the camera frame).
// All tests return the smallest t in (t_min, t_max) or nothing.

#include <algorithm>
#include <cmath>
#include <limits>

namespace agvslam::sim {

struct V3 {
  float x = 0, y = 0, z = 0;
  constexpr V3() = default;
  constexpr V3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator-(const V3& a) { return {-a.x, -a.y, -a.z}; }
inline V3 operator*(const V3& a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline V3 operator*(float s, const V3& a) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const V3& a) { return std::sqrt(dot(a, a)); }
inline V3 normalized(const V3& a) {
  const float n = length(a);
  return n > 0 ? a * (1.0f / n) : a;
}
inline V3 vmin(const V3& a, const V3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline V3 vmax(const V3& a, const V3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Stand-in for 1/0 in slab tests (avoids inf * 0 = NaN when an origin lies on a slab plane).
constexpr float kHugeInverse = 1e30f;

struct Ray {
  V3 origin;
  V3 dir;      // not normalised (see above)
  V3 inv_dir;  // 1 / dir per component, +-kHugeInverse for a zero component

  Ray() = default;
  Ray(const V3& o, const V3& d) : origin(o), dir(d) {
    inv_dir = {d.x != 0 ? 1.0f / d.x : std::copysign(kHugeInverse, d.x),
               d.y != 0 ? 1.0f / d.y : std::copysign(kHugeInverse, d.y),
               d.z != 0 ? 1.0f / d.z : std::copysign(kHugeInverse, d.z)};
  }
  V3 at(float t) const { return origin + dir * t; }
};

// Ray against the axis-aligned box [lo, hi]. On a hit with entry t in (t_min, t_max), sets t_hit and the entry
// face axis (0 x, 1 y, 2 z). Rays starting inside the box report no hit (the camera is never inside one).
inline bool intersect_aabb(const Ray& ray, const V3& lo, const V3& hi, float t_min, float t_max, float& t_hit,
                           int& face_axis) {
  float tx0 = (lo.x - ray.origin.x) * ray.inv_dir.x, tx1 = (hi.x - ray.origin.x) * ray.inv_dir.x;
  if (tx0 > tx1) std::swap(tx0, tx1);
  float ty0 = (lo.y - ray.origin.y) * ray.inv_dir.y, ty1 = (hi.y - ray.origin.y) * ray.inv_dir.y;
  if (ty0 > ty1) std::swap(ty0, ty1);
  float tz0 = (lo.z - ray.origin.z) * ray.inv_dir.z, tz1 = (hi.z - ray.origin.z) * ray.inv_dir.z;
  if (tz0 > tz1) std::swap(tz0, tz1);
  float t_near = tx0;
  int axis = 0;
  if (ty0 > t_near) {
    t_near = ty0;
    axis = 1;
  }
  if (tz0 > t_near) {
    t_near = tz0;
    axis = 2;
  }
  const float t_far = std::min(tx1, std::min(ty1, tz1));
  if (t_near > t_far || t_near <= t_min || t_near >= t_max) return false;
  t_hit = t_near;
  face_axis = axis;
  return true;
}

// Entry/exit of a ray through a box, for culling (true if [t_near, t_far] overlaps [t_min, t_max]).
inline bool ray_overlaps_aabb(const Ray& ray, const V3& lo, const V3& hi, float t_min, float t_max) {
  float tx0 = (lo.x - ray.origin.x) * ray.inv_dir.x, tx1 = (hi.x - ray.origin.x) * ray.inv_dir.x;
  if (tx0 > tx1) std::swap(tx0, tx1);
  float ty0 = (lo.y - ray.origin.y) * ray.inv_dir.y, ty1 = (hi.y - ray.origin.y) * ray.inv_dir.y;
  if (ty0 > ty1) std::swap(ty0, ty1);
  float tz0 = (lo.z - ray.origin.z) * ray.inv_dir.z, tz1 = (hi.z - ray.origin.z) * ray.inv_dir.z;
  if (tz0 > tz1) std::swap(tz0, tz1);
  const float t_near = std::max(t_min, std::max(tx0, std::max(ty0, tz0)));
  const float t_far = std::min(t_max, std::min(tx1, std::min(ty1, tz1)));
  return t_near <= t_far;
}

// Sphere |p - c| = r; outward normal at the hit.
inline bool intersect_sphere(const Ray& ray, const V3& center, float radius, float t_min, float t_max, float& t_hit,
                             V3& normal) {
  const V3 oc = ray.origin - center;
  const float a = dot(ray.dir, ray.dir);
  const float half_b = dot(ray.dir, oc);
  const float c = dot(oc, oc) - radius * radius;
  const float disc = half_b * half_b - a * c;
  if (disc < 0) return false;
  const float t = (-half_b - std::sqrt(disc)) / a;
  if (t <= t_min || t >= t_max) return false;
  t_hit = t;
  normal = (ray.at(t) - center) * (1.0f / radius);
  return true;
}

// Capsule: the points within `radius` of the segment a-b. Outward normal at the hit; `axis_param` is the hit's
// position along the segment in [0, 1] (clamped on the caps).
inline bool intersect_capsule(const Ray& ray, const V3& a, const V3& b, float radius, float t_min, float t_max,
                              float& t_hit, V3& normal, float& axis_param) {
  const V3 ba = b - a;
  const V3 oa = ray.origin - a;
  const float baba = dot(ba, ba), bard = dot(ba, ray.dir), baoa = dot(ba, oa);
  const float rdoa = dot(ray.dir, oa), oaoa = dot(oa, oa), dd = dot(ray.dir, ray.dir);
  const float k2 = baba * dd - bard * bard;
  const float k1 = baba * rdoa - baoa * bard;
  const float k0 = baba * oaoa - baoa * baoa - radius * radius * baba;
  const float h = k1 * k1 - k2 * k0;
  if (h < 0) return false;
  float t = (-k1 - std::sqrt(h)) / k2;
  const float y = baoa + t * bard;
  if (y > 0 && y < baba && k2 > 1e-12f) {  // body
    if (t <= t_min || t >= t_max) return false;
    t_hit = t;
    axis_param = y / baba;
    const V3 p = ray.at(t);
    normal = (p - (a + ba * axis_param)) * (1.0f / radius);
    return true;
  }
  // Cap sphere on the side the cylinder hit fell to.
  const V3 center = y <= 0 ? a : b;
  const V3 oc = ray.origin - center;
  const float half_b = dot(ray.dir, oc);
  const float c = dot(oc, oc) - radius * radius;
  const float disc = half_b * half_b - dd * c;
  if (disc < 0) return false;
  t = (-half_b - std::sqrt(disc)) / dd;
  if (t <= t_min || t >= t_max) return false;
  t_hit = t;
  axis_param = y <= 0 ? 0.0f : 1.0f;
  normal = (ray.at(t) - center) * (1.0f / radius);
  return true;
}

}  // namespace agvslam::sim
