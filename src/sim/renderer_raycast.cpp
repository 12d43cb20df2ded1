// Ray casts against the scene: the hall's walls, floor and ceiling, the static boxes (grid DDA) and the actors'
// primitives.

#include <algorithm>
#include <cmath>

#include "agvslam/sim/renderer.h"
#include "agvslam/sim/texture.h"
#include "renderer_internal.h"

namespace agvslam::sim {

using namespace render_detail;

void Renderer::cast_hall(const V3& o, const V3& d, RayHit& hit) const {
  float t;
  const int plane = nearest_hall_plane(o, d, hall_extent(), t);
  set_hall_hit(plane, t, hit);
}

void Renderer::cast_static(const Ray& ray, RayHit& hit) const {
  cast_hall(ray.origin, ray.dir, hit);
  const Warehouse& w = warehouse_;
  const V3& o = ray.origin;
  const V3& d = ray.dir;
  const V3& inv = ray.inv_dir;

  // Boxes: 2-D DDA over the floor grid, testing only the height slabs the ray passes through in each cell, and
  // jumping across open floor using the cells' distance to the nearest occupied cell.
  const FloorGrid& g = w.grid;
  if (g.nx == 0) return;
  const float cell = g.cell_m;
  const float inv_cell = 1.0f / cell;
  const float inv_slab = 1.0f / g.slab_m;
  const int nz = g.nz;
  int ix = std::clamp(floor_to_int(o.x * inv_cell), 0, g.nx - 1);
  int iy = std::clamp(floor_to_int(o.y * inv_cell), 0, g.ny - 1);
  const int step_x = d.x > 0 ? 1 : -1, step_y = d.y > 0 ? 1 : -1;
  const float t_delta_x = d.x != 0 ? std::fabs(cell * inv.x) : kInfinity;
  const float t_delta_y = d.y != 0 ? std::fabs(cell * inv.y) : kInfinity;
  auto next_boundary_x = [&](int i) {
    return d.x > 0 ? (static_cast<float>(i + 1) * cell - o.x) * inv.x
                   : (d.x < 0 ? (static_cast<float>(i) * cell - o.x) * inv.x : kInfinity);
  };
  auto next_boundary_y = [&](int i) {
    return d.y > 0 ? (static_cast<float>(i + 1) * cell - o.y) * inv.y
                   : (d.y < 0 ? (static_cast<float>(i) * cell - o.y) * inv.y : kInfinity);
  };
  float t_next_x = next_boundary_x(ix), t_next_y = next_boundary_y(iy);
  // Ray parameter per metre of Chebyshev distance in the floor plane.
  const float xy_norm = std::max(std::fabs(d.x), std::fabs(d.y));
  const float t_per_m = xy_norm > 0 ? 1.0f / xy_norm : kInfinity;
  float t_enter = 0;
  const uint32_t* begin = g.slab_begin.data();
  const uint32_t* index = g.box_index.data();
  const StaticBox* boxes = w.boxes.data();
  const uint8_t* empty_radius = g.empty_radius.data();
  for (;;) {
    const std::size_t c = static_cast<std::size_t>(iy) * static_cast<std::size_t>(g.nx) + static_cast<std::size_t>(ix);
    const int radius = empty_radius[c];
    if (radius >= 3) {
      // Every cell within radius - 1 is empty: jump that far (Chebyshev) along the ray and re-seed the DDA.
      const float t_jump = t_enter + static_cast<float>(radius - 1) * cell * t_per_m;
      if (t_jump >= hit.t) break;
      const float px = o.x + d.x * t_jump, py = o.y + d.y * t_jump;
      ix = floor_to_int(px * inv_cell);
      iy = floor_to_int(py * inv_cell);
      if (ix < 0 || ix >= g.nx || iy < 0 || iy >= g.ny) break;
      t_enter = t_jump;
      t_next_x = next_boundary_x(ix);
      t_next_y = next_boundary_y(iy);
      continue;
    }
    const float t_exit = std::min(t_next_x, t_next_y);
    if (radius == 0) {
      const float t_end = std::min(t_exit, hit.t);
      const float za = o.z + d.z * t_enter, zb = o.z + d.z * t_end;
      const float z_lo = std::min(za, zb) - 1e-4f, z_hi = std::max(za, zb) + 1e-4f;
      if (z_lo <= g.cell_top_z[c] && z_hi >= 0.0f) {
        const int s0 = std::clamp(floor_to_int(z_lo * inv_slab), 0, nz - 1);
        const int s1 = std::clamp(floor_to_int(z_hi * inv_slab), 0, nz - 1);
        const uint32_t k0 = begin[c * static_cast<std::size_t>(nz) + static_cast<std::size_t>(s0)];
        const uint32_t k1 = begin[c * static_cast<std::size_t>(nz) + static_cast<std::size_t>(s1) + 1];
        for (uint32_t k = k0; k < k1; ++k) {
          const StaticBox& box = boxes[index[k]];
          if (box.lo.z > z_hi || box.hi.z < z_lo) continue;
          float t;
          int axis;
          if (intersect_aabb(ray, box.lo, box.hi, 1e-4f, hit.t, t, axis)) {
            hit.t = t;
            hit.kind = RayHit::Kind::kBox;
            hit.index = static_cast<int32_t>(index[k]);
            const bool positive = d[axis] < 0;  // the face we enter faces against the ray
            hit.face = static_cast<uint8_t>(axis * 2 + (positive ? 1 : 0));
            V3 n{0, 0, 0};
            n[axis] = positive ? 1.0f : -1.0f;
            hit.normal = n;
          }
        }
      }
    }
    if (hit.t <= t_exit) break;
    if (t_next_x < t_next_y) {
      ix += step_x;
      if (ix < 0 || ix >= g.nx) break;
      t_enter = t_next_x;
      t_next_x += t_delta_x;
    } else {
      iy += step_y;
      if (iy < 0 || iy >= g.ny) break;
      t_enter = t_next_y;
      t_next_y += t_delta_y;
    }
  }
}

void Renderer::cast_dynamic(const Ray& ray, const std::vector<DynamicObject>& objects, const ObjectRects* rects, int u,
                            int v, RayHit& hit) const {
  for (std::size_t oi = 0; oi < objects.size(); ++oi) {
    const PixelRect* prim_rects = nullptr;
    if (rects) {
      const PixelRect& r = rects->object[oi];
      if (u < r.u0 || u > r.u1 || v < r.v0 || v > r.v1) continue;
      prim_rects = rects->primitive[oi].data();
    }
    const DynamicObject& obj = objects[oi];
    if (!ray_overlaps_aabb(ray, obj.lo, obj.hi, 0.0f, hit.t)) continue;
    const float c = obj.cos_yaw, s = obj.sin_yaw;
    // Ray in the object's yaw frame (shared by all its boxes).
    const V3 d_local{c * ray.dir.x + s * ray.dir.y, -s * ray.dir.x + c * ray.dir.y, ray.dir.z};
    for (std::size_t pi = 0; pi < obj.primitives.size(); ++pi) {
      if (prim_rects) {
        const PixelRect& r = prim_rects[pi];
        if (u < r.u0 || u > r.u1 || v < r.v0 || v > r.v1) continue;
      }
      const DynamicPrimitive& prim = obj.primitives[pi];
      float t;
      V3 n;
      float axis_param = 0;
      bool ok = false;
      switch (prim.shape) {
        case PrimitiveShape::kBox: {
          const V3 rel = ray.origin - prim.a;
          const Ray local(V3{c * rel.x + s * rel.y, -s * rel.x + c * rel.y, rel.z}, d_local);
          int axis;
          if (intersect_aabb(local, -prim.half, prim.half, 1e-4f, hit.t, t, axis)) {
            V3 nl{0, 0, 0};
            nl[axis] = d_local[axis] < 0 ? 1.0f : -1.0f;
            n = {c * nl.x - s * nl.y, s * nl.x + c * nl.y, nl.z};
            ok = true;
          }
          break;
        }
        case PrimitiveShape::kSphere:
          ok = intersect_sphere(ray, prim.a, prim.radius, 1e-4f, hit.t, t, n);
          break;
        case PrimitiveShape::kCapsule:
          ok = intersect_capsule(ray, prim.a, prim.b, prim.radius, 1e-4f, hit.t, t, n, axis_param);
          break;
      }
      if (ok) {
        hit.t = t;
        hit.kind = RayHit::Kind::kDynamic;
        hit.index = static_cast<int32_t>(pi);
        hit.object = static_cast<int16_t>(oi);
        hit.normal = n;
        hit.axis_param = axis_param;
      }
    }
  }
}

RayHit Renderer::cast(const Ray& ray, const std::vector<DynamicObject>& objects) const {
  RayHit hit;
  cast_static(ray, hit);
  cast_dynamic(ray, objects, nullptr, 0, 0, hit);
  return hit;
}

}  // namespace agvslam::sim
