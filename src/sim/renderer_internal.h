#pragma once
// Internal to the renderer (renderer*.cpp): what its translation units share. The hall-plane intersection and the
// face row spans are on the per-pixel path of several files, so they are inline here.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "agvslam/core/parallel_for.h"
#include "agvslam/sim/renderer.h"

namespace agvslam::sim::render_detail {

// Runs f(row) for every row, split over `threads` workers in blocks of 4 rows (every row is computed the same way
// whichever worker takes it); small images in the caller's thread.
template <typename F>
void for_each_row(int rows, int threads, const F& f) {
  constexpr std::size_t kBlockRows = 4;
  parallel_for(rows < 16 ? 1 : threads, static_cast<std::size_t>(std::max(rows, 0)), kBlockRows,
               [&](std::size_t begin, std::size_t end, int) {
                 for (std::size_t v = begin; v < end; ++v) f(static_cast<int>(v));
               });
}

// The hall's walls, floor and ceiling, seen from inside: a ray from o along d reaches, on each axis, the plane
// ahead of it at t = (distance to it) / d_i (never, when d_i = 0). The nearest of the three is the hit; `plane`
// numbers it axis * 2 + (d_i < 0), i.e. 0: east wall, 1: west wall, 2: north wall, 3: south wall, 4: ceiling,
// 5: floor. Ties keep x, then y. (Selections only, so that a loop over pixels vectorises.)
inline float hall_plane_t(float o_i, float d_i, float extent) {
  const float t = (d_i > 0 ? extent - o_i : -o_i) / d_i;
  return d_i != 0 ? t : kInfinity;
}
inline int nearest_hall_plane(const V3& o, const V3& d, const V3& extent, float& t) {
  const float tx = hall_plane_t(o.x, d.x, extent.x), ty = hall_plane_t(o.y, d.y, extent.y),
              tz = hall_plane_t(o.z, d.z, extent.z);
  int plane = d.x > 0 ? 0 : 1;
  t = tx;
  plane = ty < t ? (d.y > 0 ? 2 : 3) : plane;
  t = ty < t ? ty : t;
  plane = tz < t ? (d.z > 0 ? 4 : 5) : plane;
  t = tz < t ? tz : t;
  return plane;
}
// The hit on hall plane `plane` (see nearest_hall_plane) at t (+inf: nothing, for a zero direction). (Static, so
// that its table has internal linkage: the per-pixel loops then address it directly, not through the shared
// library's GOT.)
static inline void set_hall_hit(int plane, float t, RayHit& hit) {
  struct Plane {
    RayHit::Kind kind;
    uint8_t wall;  // 0 south (y = 0), 1 east (x = width), 2 north (y = depth), 3 west (x = 0)
    V3 normal;
  };
  static constexpr Plane kPlanes[6] = {{RayHit::Kind::kWall, 1, {-1, 0, 0}},    {RayHit::Kind::kWall, 3, {1, 0, 0}},
                                       {RayHit::Kind::kWall, 2, {0, -1, 0}},    {RayHit::Kind::kWall, 0, {0, 1, 0}},
                                       {RayHit::Kind::kCeiling, 0, {0, 0, -1}}, {RayHit::Kind::kFloor, 0, {0, 0, 1}}};
  const Plane& p = kPlanes[plane];
  hit.t = t;
  hit.kind = t < kInfinity ? p.kind : RayHit::Kind::kNone;
  hit.face = p.wall;
  hit.normal = p.normal;
  hit.index = -1;
}

// Span [s0, s1) of image row vv (image coordinates) inside a convex projected face; s0 > s1 when the row misses it.
inline void face_row_span(const double* fu, const double* fv, int n, double vv, double& s0, double& s1) {
  s0 = 1e30;
  s1 = -1e30;
  for (int i = 0; i < n; ++i) {
    const int j = i + 1 < n ? i + 1 : 0;
    const double va = fv[i], vb = fv[j];
    if ((va <= vv && vv < vb) || (vb <= vv && vv < va)) {
      const double uu = fu[i] + (vv - va) * (fu[j] - fu[i]) / (vb - va);
      s0 = std::min(s0, uu);
      s1 = std::max(s1, uu);
    }
  }
}

// Surface ids in the texture cache.
constexpr std::size_t kFloorSurface = 0, kCeilingSurface = 1, kFirstWallSurface = 2, kFirstBoxSurface = 6;
inline std::size_t box_surface(std::size_t box, int face) {
  return kFirstBoxSurface + box * 6 + static_cast<std::size_t>(face);
}

}  // namespace agvslam::sim::render_detail

namespace agvslam::sim {

// What the row passes of one render() share.
struct Renderer::RenderPass {
  int width = 0, height = 0;
  V3 origin, col_x, col_y, col_z;  // camera centre and the camera axes in the map frame
  float fx = 1, fy = 1, cx = 0, cy = 0, focal = 1;
  V3 hall;                          // the hall's extent
  const float* column_x = nullptr;  // normalised image x of each pixel column
  const std::vector<DynamicObject>* objects = nullptr;
  const ObjectRects* rects = nullptr;
  const std::vector<BlobShadow>* shadows = nullptr;
  const std::vector<BoxFace>* faces = nullptr;
  const std::vector<std::vector<uint32_t>>* face_buckets = nullptr;
  CameraRender* out = nullptr;
  // The ray through image point (u, v).
  Ray ray(float u, float v) const {
    const float xn = (u - cx) / fx, yn = (v - cy) / fy;
    return Ray(origin, col_x * xn + col_y * yn + col_z);
  }
};

}  // namespace agvslam::sim
