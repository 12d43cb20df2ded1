#include "agvslam/sim/renderer.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "agvslam/core/parallel_for.h"
#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/semantic_classes.h"
#include "agvslam/sim/texture.h"

namespace agvslam::sim {
namespace {

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

int32_t surface_key(const RayHit& hit) {
  switch (hit.kind) {
    case RayHit::Kind::kNone:
      return 0;
    case RayHit::Kind::kFloor:
      return 1;
    case RayHit::Kind::kCeiling:
      return 2;
    case RayHit::Kind::kWall:
      return 3 + hit.face;
    case RayHit::Kind::kBox:
      return 16 + hit.index * 8 + hit.face;
    case RayHit::Kind::kDynamic:
      return static_cast<int32_t>(0x40000000 + hit.object * 65536 + hit.index * 8);
  }
  return 0;
}

// Semantic class of the surface hit (see semantic_classes.h).
SemanticClass hit_class(const RayHit& hit, const std::vector<StaticBox>& boxes,
                        const std::vector<DynamicObject>& objects) {
  switch (hit.kind) {
    case RayHit::Kind::kNone:
    case RayHit::Kind::kCeiling:
      return SemanticClass::kBackground;
    case RayHit::Kind::kFloor:
      return SemanticClass::kFloor;
    case RayHit::Kind::kWall:
      return SemanticClass::kWall;
    case RayHit::Kind::kBox:
      return static_box_class(boxes[static_cast<std::size_t>(hit.index)].material);
    case RayHit::Kind::kDynamic: {
      const DynamicObject& obj = objects[static_cast<std::size_t>(hit.object)];
      return actor_part_class(obj.cls, obj.primitives[static_cast<std::size_t>(hit.index)].material);
    }
  }
  return SemanticClass::kBackground;
}

// The hit on the box face with surface key `key` (>= 16) at ray parameter t.
inline void set_box_hit(int32_t key, float t, RayHit& hit) {
  const int32_t k = key - 16;
  hit.t = t;
  hit.kind = RayHit::Kind::kBox;
  hit.index = k / 8;
  hit.face = static_cast<uint8_t>(k % 8);
  V3 n{0, 0, 0};
  n[hit.face / 2] = (hit.face & 1) ? 1.0f : -1.0f;
  hit.normal = n;
}

// Per-row scratch of the antialiasing pass (one per thread, reused): the row's silhouette pixels and, per extra
// sample, the nearest box face's depth and key there.
struct SampleScratch {
  std::vector<int> cols;
  std::vector<float> z[2];
  std::vector<int32_t> key[2];
};
SampleScratch& sample_scratch() {
  thread_local SampleScratch scratch;
  return scratch;
}

// Texture cache: level-0 texels of 1/512 m (about 2 mm: the footprint of a pixel on the floor nearest to the
// camera), tiles kept while any of the last 16 images (8 stereo frames) used them.
constexpr float kBaseTexelM = 1.0f / 512.0f;
constexpr uint32_t kKeepPasses = 16;

// Footprint of a pixel (the width it covers) on a surface hit at ray parameter t, for a ray direction of length
// dir_len whose dot product with the surface normal is n_dot_dir: the larger of the width across the ray,
// t / (focal * dir_len), and 0.6 times the (stretched) width along the slope, t / (focal * |cos|), so that
// grazing surfaces are blurred rather than aliased.
// (Plain comparisons rather than std::min/max, so that the row loop calling it vectorises.)
inline float pixel_footprint(float t, float dir_len, float n_dot_dir, float focal_px) {
  constexpr float kMinSlopeScale = 1e-4f / 0.6f;  // |cos| >= 1e-4
  const float slope_scale = std::fabs(n_dot_dir) * (1.0f / 0.6f);
  const float limited = slope_scale > kMinSlopeScale ? slope_scale : kMinSlopeScale;
  return t / (focal_px * (limited < dir_len ? limited : dir_len));
}

// Lighting of a surface with unit normal n: ambient + sky from above + sun.
inline float lighting(const RenderSettings& s, const V3& n) {
  return s.ambient + s.sky * std::max(0.0f, n.z) + s.sun * std::max(0.0f, dot(n, s.sun_dir));
}

// Haze fraction at a distance: ~ 1 - exp(-dist / haze_distance) for short distances (0 without haze: the
// distance scale is then infinite).
inline float haze_scale_m(const RenderSettings& s) { return s.haze_distance_m > 0 ? s.haze_distance_m : kInfinity; }
inline float haze_fraction(float dist, float haze_scale) { return dist / (dist + haze_scale); }
inline float hazed(const RenderSettings& s, float radiance, float dist) {
  return radiance + (s.haze_level - radiance) * haze_fraction(dist, haze_scale_m(s));
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
// The hit on hall plane `plane` (see nearest_hall_plane) at t (+inf: nothing, for a zero direction).
void set_hall_hit(int plane, float t, RayHit& hit) {
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

// Nearest hall plane of every pixel of a row (ray directions col_x * column_x[u] + row_dir).
void row_hall_hits(int width, const V3 origin, const V3 col_x, const V3 row_dir, const V3 extent,
                   const float* __restrict column_x, float* __restrict t, int32_t* __restrict plane) {
  for (int u = 0; u < width; ++u) {
    const V3 dir = col_x * column_x[u] + row_dir;
    float tu;
    plane[u] = nearest_hall_plane(origin, dir, extent, tu);
    t[u] = tu;
  }
}

// Per-row arrays of the shading passes (one set per thread, reused).
struct RowScratch {
  std::vector<RayHit> hits;
  std::vector<float> t, nx, ny, nz, footprint, light, haze, albedo;
  std::vector<int32_t> plane;
};
RowScratch& row_scratch(int width) {
  thread_local RowScratch row;
  const std::size_t n = static_cast<std::size_t>(width);
  if (row.hits.size() < n) {
    row.hits.resize(n);
    row.plane.resize(n);
    for (auto* a : {&row.t, &row.nx, &row.ny, &row.nz, &row.footprint, &row.light, &row.haze, &row.albedo})
      a->assign(n, 0.0f);
  }
  return row;
}

// Per pixel of a row (ray directions col_x * column_x[u] + row_dir, hit at ray_t[u] on a surface with normal
// (nx, ny, nz)[u]): the pixel's footprint on the surface, the lighting and the haze fraction. (Plain arrays, so
// that the loop vectorises.)
void row_footprint_light_haze(int width, const V3 col_x, const V3 row_dir, const float* __restrict column_x,
                              float focal_px, const RenderSettings& settings, const float* __restrict ray_t,
                              const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
                              float* __restrict footprint, float* __restrict light, float* __restrict haze) {
  const RenderSettings s = settings;  // a local copy: the stores cannot alias it
  const float haze_scale = haze_scale_m(s);
  for (int u = 0; u < width; ++u) {
    const V3 dir = col_x * column_x[u] + row_dir;
    const V3 n{nx[u], ny[u], nz[u]};
    const float dir_len = length(dir);
    footprint[u] = pixel_footprint(ray_t[u], dir_len, dot(n, dir), focal_px);
    light[u] = lighting(s, n);
    haze[u] = haze_fraction(ray_t[u] * dir_len, haze_scale);
  }
}

// Surface ids in the texture cache.
constexpr std::size_t kFloorSurface = 0, kCeilingSurface = 1, kFirstWallSurface = 2, kFirstBoxSurface = 6;
std::size_t box_surface(std::size_t box, int face) {
  return kFirstBoxSurface + box * 6 + static_cast<std::size_t>(face);
}

}  // namespace

Renderer::Renderer(const Warehouse& warehouse, const RenderSettings& settings)
    : warehouse_(warehouse),
      settings_(settings),
      textures_(kFirstBoxSurface + 6 * warehouse.boxes.size(), kBaseTexelM, kKeepPasses) {
  mark_nx_ = std::max(1, static_cast<int>(std::ceil(warehouse.width_m / mark_cell_m_)));
  mark_ny_ = std::max(1, static_cast<int>(std::ceil(warehouse.depth_m / mark_cell_m_)));
  mark_bins_.assign(static_cast<std::size_t>(mark_nx_ * mark_ny_), {});
  for (std::size_t i = 0; i < warehouse.floor_marks.size(); ++i) {
    const FloorMark& m = warehouse.floor_marks[i];
    const int ix0 = std::clamp(static_cast<int>(std::floor((m.x0 - 0.1f) / mark_cell_m_)), 0, mark_nx_ - 1);
    const int ix1 = std::clamp(static_cast<int>(std::floor((m.x1 + 0.1f) / mark_cell_m_)), 0, mark_nx_ - 1);
    const int iy0 = std::clamp(static_cast<int>(std::floor((m.y0 - 0.1f) / mark_cell_m_)), 0, mark_ny_ - 1);
    const int iy1 = std::clamp(static_cast<int>(std::floor((m.y1 + 0.1f) / mark_cell_m_)), 0, mark_ny_ - 1);
    for (int iy = iy0; iy <= iy1; ++iy)
      for (int ix = ix0; ix <= ix1; ++ix)
        mark_bins_[static_cast<std::size_t>(iy * mark_nx_ + ix)].push_back(static_cast<uint16_t>(i));
  }
  // Floor ambient occlusion: what stands on the floor darkens it (contact shadow), shelves above shade it a
  // little; blurred so that it is soft.
  {
    const int ax = static_cast<int>(std::ceil(warehouse.width_m / ao_cell_m_));
    const int ay = static_cast<int>(std::ceil(warehouse.depth_m / ao_cell_m_));
    cv::Mat cover(ay, ax, CV_32FC1, cv::Scalar(0));
    for (const StaticBox& b : warehouse.boxes) {
      const float weight = b.lo.z < 0.25f ? 1.0f : (b.lo.z < 2.5f ? 0.35f : 0.0f);
      if (weight <= 0) continue;
      const int x0 = std::clamp(static_cast<int>(std::floor(b.lo.x / ao_cell_m_)), 0, ax - 1);
      const int x1 = std::clamp(static_cast<int>(std::ceil(b.hi.x / ao_cell_m_)) - 1, 0, ax - 1);
      const int y0 = std::clamp(static_cast<int>(std::floor(b.lo.y / ao_cell_m_)), 0, ay - 1);
      const int y1 = std::clamp(static_cast<int>(std::ceil(b.hi.y / ao_cell_m_)) - 1, 0, ay - 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) cover.at<float>(y, x) = std::max(cover.at<float>(y, x), weight);
    }
    cv::Mat blurred;
    cv::GaussianBlur(cover, blurred, cv::Size(0, 0), 2.5);  // sigma 0.25 m
    floor_ao_ = 1.0f - 0.55f * blurred;
  }
  wall_bins_ = static_cast<int>(std::ceil(std::max(warehouse.width_m, warehouse.depth_m))) + 1;
  wall_feature_bins_.assign(static_cast<std::size_t>(4 * wall_bins_), {});
  for (std::size_t i = 0; i < warehouse.wall_features.size(); ++i) {
    const WallFeature& f = warehouse.wall_features[i];
    const int m0 = std::clamp(static_cast<int>(std::floor(f.u0 - 0.5f)), 0, wall_bins_ - 1);
    const int m1 = std::clamp(static_cast<int>(std::floor(f.u1 + 0.5f)), 0, wall_bins_ - 1);
    for (int m = m0; m <= m1; ++m)
      wall_feature_bins_[static_cast<std::size_t>(f.wall * wall_bins_ + m)].push_back(static_cast<uint16_t>(i));
  }
}

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

void Renderer::project_box_faces(const CameraIntrinsics& cam, const Eigen::Isometry3d& T_m_c,
                                 std::vector<BoxFace>& faces, std::vector<std::vector<uint32_t>>& buckets) const {
  const int width = cam.width, height = cam.height;
  const Eigen::Matrix3d R_c_m = T_m_c.linear().transpose();
  const Eigen::Vector3d o = T_m_c.translation();
  const double z_near = 1e-3;
  faces.clear();
  faces.reserve(4096);
  const double fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy;
  for (std::size_t bi = 0; bi < warehouse_.boxes.size(); ++bi) {
    const StaticBox& box = warehouse_.boxes[bi];
    const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
    Eigen::Vector3d corner_c[8];
    double z_max = -1e30;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d p_m((i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]);
      corner_c[i] = R_c_m * (p_m - o);
      z_max = std::max(z_max, corner_c[i].z());
    }
    if (z_max <= z_near) continue;  // entirely behind the camera
    for (int axis = 0; axis < 3; ++axis) {
      int side;  // 0: the face at lo[axis] (normal -axis), 1: at hi[axis]
      if (o[axis] < lo[axis])
        side = 0;
      else if (o[axis] > hi[axis])
        side = 1;
      else
        continue;  // not facing the camera
      // The face's 4 corners, in order around it.
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      const int bit_axis = 1 << axis, bit1 = 1 << a1, bit2 = 1 << a2;
      const int base = side ? bit_axis : 0;
      const int idx[4] = {base, base | bit1, base | bit1 | bit2, base | bit2};
      // Clip the polygon against z >= z_near.
      Eigen::Vector3d poly[8];
      int n = 0;
      for (int i = 0; i < 4; ++i) {
        const Eigen::Vector3d& p = corner_c[idx[i]];
        const Eigen::Vector3d& q = corner_c[idx[(i + 1) % 4]];
        const bool p_in = p.z() >= z_near, q_in = q.z() >= z_near;
        if (p_in) poly[n++] = p;
        if (p_in != q_in) poly[n++] = p + (q - p) * ((z_near - p.z()) / (q.z() - p.z()));
      }
      if (n < 3) continue;
      BoxFace f;
      f.n = n;
      double v_min = 1e30, v_max = -1e30, u_min = 1e30, u_max = -1e30;
      for (int i = 0; i < n; ++i) {
        f.u[i] = fx * poly[i].x() / poly[i].z() + cx;
        f.v[i] = fy * poly[i].y() / poly[i].z() + cy;
        v_min = std::min(v_min, f.v[i]);
        v_max = std::max(v_max, f.v[i]);
        u_min = std::min(u_min, f.u[i]);
        u_max = std::max(u_max, f.u[i]);
      }
      // Kept when it may cover a sample within half a pixel of some pixel centre.
      if (u_max < -0.5 || u_min > width - 0.5 || v_max < -0.5 || v_min > height - 0.5) continue;
      f.row0 = std::max(0, static_cast<int>(std::ceil(v_min)));
      f.row1 = std::min(height - 1, static_cast<int>(std::floor(v_max)));
      f.sample_row0 = std::max(0, static_cast<int>(std::ceil(v_min - 0.5)));
      f.sample_row1 = std::min(height - 1, static_cast<int>(std::floor(v_max + 0.5)));
      if (f.sample_row0 > f.sample_row1) continue;
      // Plane n_c . X = k in the camera frame; for the pixel ray X = z (xn, yn, 1).
      Eigen::Vector3d n_m = Eigen::Vector3d::Zero();
      n_m[axis] = side ? 1.0 : -1.0;
      const Eigen::Vector3d n_c = R_c_m * n_m;
      const double k = n_c.dot(corner_c[idx[0]]);
      f.a = static_cast<float>(n_c.x() / fx);
      f.b = static_cast<float>(n_c.y() / fy);
      f.c = static_cast<float>(n_c.z() - n_c.x() * cx / fx - n_c.y() * cy / fy);
      f.k = static_cast<float>(k);
      f.key = static_cast<int32_t>(16 + static_cast<int32_t>(bi) * 8 + axis * 2 + side);
      faces.push_back(f);
    }
  }
  // Bucket the faces by blocks of rows (ties in a row keep the face that comes first).
  const int n_buckets = (height + kFaceRowsPerBucket - 1) / kFaceRowsPerBucket;
  buckets.resize(static_cast<std::size_t>(n_buckets));
  for (auto& b : buckets) b.clear();
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int bk = faces[i].sample_row0 / kFaceRowsPerBucket; bk <= faces[i].sample_row1 / kFaceRowsPerBucket; ++bk)
      buckets[static_cast<std::size_t>(bk)].push_back(static_cast<uint32_t>(i));
}

namespace {
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
}  // namespace

void Renderer::rasterize_boxes(const CameraIntrinsics& cam, const std::vector<BoxFace>& faces,
                               const std::vector<std::vector<uint32_t>>& buckets, cv::Mat& depth, cv::Mat& key,
                               int threads) const {
  const int width = cam.width, height = cam.height;
  depth.setTo(kInfinity);
  key.setTo(-1);
  // Rows are independent: any thread count gives the same result.
  for_each_row(height, threads, [&](int v) {
    rasterize_row(width, faces, buckets[static_cast<std::size_t>(v / kFaceRowsPerBucket)], v, depth.ptr<float>(v),
                  key.ptr<int32_t>(v));
  });
}

AGVSLAM_SIM_CLONES void Renderer::rasterize_row(int width, const std::vector<BoxFace>& faces,
                                                const std::vector<uint32_t>& bucket, int v, float* zrow,
                                                int32_t* krow) {
  for (uint32_t fi : bucket) {
    const BoxFace& f = faces[fi];
    if (v < f.row0 || v > f.row1) continue;
    // Span of the convex polygon on this row.
    double s0, s1;
    face_row_span(f.u, f.v, f.n, static_cast<double>(v), s0, s1);
    if (s0 > s1) continue;
    const int u0 = std::max(0, static_cast<int>(std::ceil(s0)));
    const int u1 = std::min(width - 1, static_cast<int>(std::ceil(s1)) - 1);
    const float row_term = f.b * static_cast<float>(v) + f.c;
    for (int u = u0; u <= u1; ++u) {
      const float denom = f.a * static_cast<float>(u) + row_term;
      const float z = f.k / denom;
      if (z > 0 && z < zrow[u]) {
        zrow[u] = z;
        krow[u] = f.key;
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

float Renderer::shade(const RayHit& hit, const Ray& ray, const std::vector<DynamicObject>& objects,
                      float focal_px) const {
  std::shared_lock<std::shared_mutex> pass_lock(pass_mutex_);
  return shade_hit(hit, ray.origin, ray.dir, objects, blob_shadows(objects), focal_px);
}

void Renderer::face_size(const StaticBox& box, int face, float& su, float& sv) {
  const V3 size = box.hi - box.lo;
  switch (face / 2) {
    case 0:
      su = size.y;
      sv = size.z;
      break;
    case 1:
      su = size.x;
      sv = size.z;
      break;
    default:
      su = size.x;
      sv = size.y;
      break;
  }
}

AGVSLAM_SIM_CLONES float Renderer::box_face_albedo(std::size_t box_index, int face, float u, float v,
                                                   float footprint_m) const {
  const StaticBox& box = warehouse_.boxes[box_index];
  FaceSample f;
  f.box_size = box.hi - box.lo;
  face_size(box, face, f.su, f.sv);
  f.u = u;
  f.v = v;
  f.face = face;
  f.footprint_m = footprint_m;
  f.seed = (hash32(box.seed) & ~7U) | static_cast<uint32_t>(face);
  return box_albedo(box.material, box.variant, f);
}

AGVSLAM_SIM_CLONES float Renderer::cached_floor_albedo(float x, float y, float footprint_m) const {
  return textures_.sample(kFloorSurface, warehouse_.width_m, warehouse_.depth_m, x, y, footprint_m,
                          [this](float u, float v, float w) { return floor_albedo(u, v, w); });
}

AGVSLAM_SIM_CLONES float Renderer::cached_ceiling_albedo(float x, float y, float footprint_m) const {
  return textures_.sample(kCeilingSurface, warehouse_.width_m, warehouse_.depth_m, x, y, footprint_m,
                          [this](float u, float v, float w) { return ceiling_albedo(u, v, w); });
}

AGVSLAM_SIM_CLONES float Renderer::cached_wall_albedo(int wall, float u, float z, float footprint_m) const {
  const float length = (wall & 1) ? warehouse_.depth_m : warehouse_.width_m;
  return textures_.sample(kFirstWallSurface + static_cast<std::size_t>(wall), length, warehouse_.height_m, u, z,
                          footprint_m, [this, wall](float a, float b, float w) { return wall_albedo(wall, a, b, w); });
}

AGVSLAM_SIM_CLONES float Renderer::cached_box_face_albedo(std::size_t box, int face, float u, float v,
                                                          float footprint_m) const {
  float su, sv;
  face_size(warehouse_.boxes[box], face, su, sv);
  return textures_.sample(box_surface(box, face), su, sv, u, v, footprint_m,
                          [this, box, face](float a, float b, float w) { return box_face_albedo(box, face, a, b, w); });
}

std::vector<Renderer::BlobShadow> Renderer::blob_shadows(const std::vector<DynamicObject>& objects) {
  std::vector<BlobShadow> shadows;
  shadows.reserve(objects.size());
  for (const DynamicObject& obj : objects) {
    // Radius 0.45 m (people), 1.3 m (forklifts, centred 0.3 m ahead of their origin), 0.75 m (AGVs, carts and
    // pallets).
    const float inv_radius2 = obj.cls == ActorClass::kPerson
                                  ? 1.0f / (0.45f * 0.45f)
                                  : (obj.cls == ActorClass::kForklift ? 1.0f / (1.3f * 1.3f) : 1.0f / (0.75f * 0.75f));
    const float fwd = obj.cls == ActorClass::kForklift ? 0.3f : 0.0f;
    shadows.push_back({obj.origin.x + fwd * obj.cos_yaw, obj.origin.y + fwd * obj.sin_yaw, inv_radius2});
  }
  return shadows;
}

float Renderer::shade_hit(const RayHit& hit, const V3& origin, const V3& dir, const std::vector<DynamicObject>& objects,
                          const std::vector<BlobShadow>& shadows, float focal_px) const {
  const RenderSettings& s = settings_;
  if (hit.kind == RayHit::Kind::kNone) return s.haze_level;
  const float dir_len = length(dir);
  const float footprint = pixel_footprint(hit.t, dir_len, dot(hit.normal, dir), focal_px);
  const float albedo = surface_albedo(hit, origin + dir * hit.t, footprint, objects, shadows);
  return hazed(s, albedo * lighting(s, hit.normal), hit.t * dir_len);
}

AGVSLAM_SIM_CLONES float Renderer::surface_albedo(const RayHit& hit, const V3& p, float footprint,
                                                  const std::vector<DynamicObject>& objects,
                                                  const std::vector<BlobShadow>& shadows) const {
  float albedo = 0.5f;
  switch (hit.kind) {
    case RayHit::Kind::kFloor: {
      albedo = cached_floor_albedo(p.x, p.y, footprint);
      // Soft occlusion by static goods (bilinear in the AO raster) and blob shadows of the actors.
      const float gx = p.x * inv_ao_cell_ - 0.5f, gy = p.y * inv_ao_cell_ - 0.5f;
      const int ix = std::clamp(floor_to_int(gx), 0, floor_ao_.cols - 2);
      const int iy = std::clamp(floor_to_int(gy), 0, floor_ao_.rows - 2);
      const float fx = clamp01(gx - static_cast<float>(ix)), fy = clamp01(gy - static_cast<float>(iy));
      const float* r0 = floor_ao_.ptr<float>(iy);
      const float* r1 = floor_ao_.ptr<float>(iy + 1);
      albedo *= lerp(lerp(r0[ix], r0[ix + 1], fx), lerp(r1[ix], r1[ix + 1], fx), fy);
      for (const BlobShadow& b : shadows) {
        const float dx = p.x - b.x, dy = p.y - b.y;
        const float q = 1.0f - (dx * dx + dy * dy) * b.inv_radius2;
        if (q > 0) albedo *= 1.0f - 0.6f * q * q;
      }
      break;
    }
    case RayHit::Kind::kCeiling:
      albedo = cached_ceiling_albedo(p.x, p.y, footprint);
      break;
    case RayHit::Kind::kWall: {
      const Warehouse& w = warehouse_;
      float u = 0;
      switch (hit.face) {
        case 0:
          u = p.x;
          break;
        case 1:
          u = p.y;
          break;
        case 2:
          u = w.width_m - p.x;
          break;
        default:
          u = w.depth_m - p.y;
          break;
      }
      albedo = cached_wall_albedo(hit.face, u, p.z, footprint);
      break;
    }
    case RayHit::Kind::kBox: {
      const std::size_t index = static_cast<std::size_t>(hit.index);
      const StaticBox& box = warehouse_.boxes[index];
      const V3 q = p - box.lo;
      const int axis = hit.face / 2;
      const float u = axis == 0 ? q.y : q.x;
      const float v = axis == 2 ? q.y : q.z;
      albedo = cached_box_face_albedo(index, hit.face, u, v, footprint);
      break;
    }
    case RayHit::Kind::kDynamic: {
      const DynamicObject& obj = objects[static_cast<std::size_t>(hit.object)];
      const DynamicPrimitive& prim = obj.primitives[static_cast<std::size_t>(hit.index)];
      const V3 p_local = obj.to_local(p);
      const float c = obj.cos_yaw, sn = obj.sin_yaw;
      const V3 n_local{c * hit.normal.x + sn * hit.normal.y, -sn * hit.normal.x + c * hit.normal.y, hit.normal.z};
      albedo = actor_albedo(obj, prim, p_local, n_local, hit.axis_param, footprint);
      break;
    }
    case RayHit::Kind::kNone:
      break;
  }
  return albedo;
}

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

void Renderer::render(const CameraIntrinsics& cam, const Eigen::Isometry3d& T_m_c,
                      const std::vector<DynamicObject>& objects, CameraRender& out, int threads) const {
  {
    // A new texture cache pass (freeing tiles unused for a while) unless another render is under way.
    std::unique_lock<std::shared_mutex> exclusive(pass_mutex_, std::try_to_lock);
    if (exclusive.owns_lock()) textures_.begin_pass();
  }
  std::shared_lock<std::shared_mutex> pass_lock(pass_mutex_);
  const int width = cam.width, height = cam.height;
  out.radiance.create(height, width, CV_32FC1);
  out.depth_m.create(height, width, CV_32FC1);
  out.object_id.create(height, width, CV_16UC1);
  out.class_id.create(height, width, CV_8UC1);
  out.surface_key.create(height, width, CV_32SC1);
  out.edge.create(height, width, CV_8UC1);

  const Eigen::Matrix3d R = T_m_c.linear();
  const Eigen::Vector3d t = T_m_c.translation();
  const V3 origin{static_cast<float>(t.x()), static_cast<float>(t.y()), static_cast<float>(t.z())};
  const V3 col_x{static_cast<float>(R(0, 0)), static_cast<float>(R(1, 0)), static_cast<float>(R(2, 0))};
  const V3 col_y{static_cast<float>(R(0, 1)), static_cast<float>(R(1, 1)), static_cast<float>(R(2, 1))};
  const V3 col_z{static_cast<float>(R(0, 2)), static_cast<float>(R(1, 2)), static_cast<float>(R(2, 2))};
  const float fx = static_cast<float>(cam.fx), fy = static_cast<float>(cam.fy);
  const float cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  const float focal = std::sqrt(fx * fy);

  // Screen-space bounds of each object and of each of its primitives (rays outside them skip it).
  const Eigen::Isometry3d T_c_m = T_m_c.inverse();
  auto screen_rect = [&](const V3& lo, const V3& hi) {
    double u_min = 1e30, u_max = -1e30, v_min = 1e30, v_max = -1e30;
    int in_front = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p_m((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
      const Eigen::Vector3d p_c = T_c_m * p_m;
      if (p_c.z() <= 0.05) continue;
      ++in_front;
      const double pu = cam.fx * p_c.x() / p_c.z() + cam.cx, pv = cam.fy * p_c.y() / p_c.z() + cam.cy;
      u_min = std::min(u_min, pu);
      u_max = std::max(u_max, pu);
      v_min = std::min(v_min, pv);
      v_max = std::max(v_max, pv);
    }
    PixelRect r;
    if (in_front == 0) {
      r = {1, 1, 0, 0};
    } else if (in_front < 8) {
      r = {0, 0, width - 1, height - 1};
    } else {
      r.u0 = std::max(0, static_cast<int>(std::floor(std::max(u_min, -1e6))) - 2);
      r.v0 = std::max(0, static_cast<int>(std::floor(std::max(v_min, -1e6))) - 2);
      r.u1 = std::min(width - 1, static_cast<int>(std::ceil(std::min(u_max, 1e6))) + 2);
      r.v1 = std::min(height - 1, static_cast<int>(std::ceil(std::min(v_max, 1e6))) + 2);
    }
    return r;
  };
  ObjectRects rects;
  rects.object.resize(objects.size());
  rects.primitive.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const DynamicObject& obj = objects[i];
    rects.object[i] = screen_rect(obj.lo, obj.hi);
    rects.primitive[i].resize(obj.primitives.size());
    for (std::size_t k = 0; k < obj.primitives.size(); ++k) {
      const DynamicPrimitive& p = obj.primitives[k];
      V3 lo, hi;
      if (p.shape == PrimitiveShape::kBox) {
        const float ex = std::fabs(obj.cos_yaw) * p.half.x + std::fabs(obj.sin_yaw) * p.half.y;
        const float ey = std::fabs(obj.sin_yaw) * p.half.x + std::fabs(obj.cos_yaw) * p.half.y;
        lo = p.a - V3{ex, ey, p.half.z};
        hi = p.a + V3{ex, ey, p.half.z};
      } else {
        const V3 r{p.radius, p.radius, p.radius};
        const V3 end = p.shape == PrimitiveShape::kCapsule ? p.b : p.a;
        lo = vmin(p.a, end) - r;
        hi = vmax(p.a, end) + r;
      }
      rects.primitive[i][k] = screen_rect(lo, hi);
    }
  }
  const std::vector<BlobShadow> shadows = blob_shadows(objects);
  const V3 hall = hall_extent();

  // Static boxes by rasterisation into depth_m / surface_key, then per pixel: the hall, the nearer of the two,
  // the actors (ray cast inside their screen rectangles), shading.
  std::vector<BoxFace> faces;
  std::vector<std::vector<uint32_t>> face_buckets;
  project_box_faces(cam, T_m_c, faces, face_buckets);
  rasterize_boxes(cam, faces, face_buckets, out.depth_m, out.surface_key, threads);
  std::vector<float> column_x(static_cast<std::size_t>(width));  // normalised image x of each pixel column
  for (int u = 0; u < width; ++u) column_x[static_cast<std::size_t>(u)] = (static_cast<float>(u) - cx) / fx;
  RenderPass pass;
  pass.width = width;
  pass.height = height;
  pass.origin = origin;
  pass.col_x = col_x;
  pass.col_y = col_y;
  pass.col_z = col_z;
  pass.fx = fx;
  pass.fy = fy;
  pass.cx = cx;
  pass.cy = cy;
  pass.focal = focal;
  pass.hall = hall;
  pass.column_x = column_x.data();
  pass.objects = &objects;
  pass.rects = &rects;
  pass.shadows = &shadows;
  pass.faces = &faces;
  pass.face_buckets = &face_buckets;
  pass.out = &out;
  for_each_row(height, threads, [&](int v) { render_row(pass, v); });

  out.edge.setTo(0);
  if (!settings_.antialias_edges) return;
  // Supersample silhouettes: neighbouring pixels on different kinds of surface, on a moving object, or on two
  // surfaces at clearly different depths (edges within a surface, or between touching boxes, are left alone).
  auto key_class = [](int32_t key) {
    if (key >= 0x40000000) return 5;
    if (key >= 16) return 4;
    if (key >= 3) return 3;
    return key;
  };
  auto is_edge = [&](int32_t ka, int32_t kb, float za, float zb) {
    if (ka == kb) return false;
    const int ca = key_class(ka), cb = key_class(kb);
    if (ca != cb || ca == 5) return true;
    return std::fabs(za - zb) > 0.04f * std::min(za, zb);
  };
  for (int v = 0; v < height; ++v) {
    const int32_t* k0 = out.surface_key.ptr<int32_t>(v);
    const int32_t* k1 = v + 1 < height ? out.surface_key.ptr<int32_t>(v + 1) : nullptr;
    const float* z0 = out.depth_m.ptr<float>(v);
    const float* z1 = v + 1 < height ? out.depth_m.ptr<float>(v + 1) : nullptr;
    uint8_t* e0 = out.edge.ptr<uint8_t>(v);
    uint8_t* e1 = v + 1 < height ? out.edge.ptr<uint8_t>(v + 1) : nullptr;
    for (int u = 0; u < width; ++u) {
      if (u + 1 < width && is_edge(k0[u], k0[u + 1], z0[u], z0[u + 1])) e0[u] = e0[u + 1] = 1;
      if (k1 && is_edge(k0[u], k1[u], z0[u], z1[u])) e0[u] = e1[u] = 1;
    }
  }
  // The centre sample plus two more on the pixel's diagonal, see antialias_row.
  for_each_row(height, threads, [&](int v) { antialias_row(pass, v); });
}

AGVSLAM_SIM_CLONES void Renderer::render_row(const RenderPass& p, int v) const {
  const int width = p.width;
  CameraRender& out = *p.out;
  const std::vector<DynamicObject>& objects = *p.objects;
  const ObjectRects& rects = *p.rects;
  const ObjectRects* rect_ptr = p.rects;
  const std::vector<BlobShadow>& shadows = *p.shadows;
  const V3 origin = p.origin, col_x = p.col_x, col_y = p.col_y, col_z = p.col_z, hall = p.hall;
  const float fy = p.fy, cy = p.cy, focal = p.focal;
  const float* column_x = p.column_x;
  const RenderSettings& s = settings_;
  float* radiance = out.radiance.ptr<float>(v);
  float* depth = out.depth_m.ptr<float>(v);
  uint16_t* ids = out.object_id.ptr<uint16_t>(v);
  uint8_t* classes = out.class_id.ptr<uint8_t>(v);
  int32_t* keys = out.surface_key.ptr<int32_t>(v);
  const V3 row_dir = col_y * ((static_cast<float>(v) - cy) / fy) + col_z;
  // Columns of this row inside some object's screen rectangle: only there are rays cast against the actors.
  int actor_u0 = width, actor_u1 = -1;
  for (const PixelRect& r : rects.object)
    if (v >= r.v0 && v <= r.v1 && r.u0 <= r.u1) {
      actor_u0 = std::min(actor_u0, r.u0);
      actor_u1 = std::max(actor_u1, r.u1);
    }
  // The row is shaded in passes over arrays, so that the arithmetic shared by all pixels vectorises: the hits,
  // then footprints, lighting and haze, then the albedos (texture lookups), then the radiance.
  RowScratch& row = row_scratch(width);
  row_hall_hits(width, origin, col_x, row_dir, hall, column_x, row.t.data(), row.plane.data());
  for (int u = 0; u < width; ++u) {
    RayHit& hit = row.hits[static_cast<std::size_t>(u)];
    hit = RayHit{};
    set_hall_hit(row.plane[static_cast<std::size_t>(u)], row.t[static_cast<std::size_t>(u)], hit);
    if (keys[u] >= 16 && depth[u] < hit.t) set_box_hit(keys[u], depth[u], hit);
    if (u >= actor_u0 && u <= actor_u1)
      cast_dynamic(Ray(origin, col_x * column_x[static_cast<std::size_t>(u)] + row_dir), objects, rect_ptr, u, v, hit);
    const bool none = hit.kind == RayHit::Kind::kNone;
    row.t[u] = none ? 0.0f : hit.t;
    row.nx[u] = hit.normal.x;
    row.ny[u] = hit.normal.y;
    row.nz[u] = hit.normal.z;
    depth[u] = none ? 0.0f : hit.t;
    ids[u] = hit.kind == RayHit::Kind::kDynamic
                 ? static_cast<uint16_t>(objects[static_cast<std::size_t>(hit.object)].id)
                 : static_cast<uint16_t>(0);
    classes[u] = static_cast<uint8_t>(hit_class(hit, warehouse_.boxes, objects));
    keys[u] = surface_key(hit);
  }
  row_footprint_light_haze(width, col_x, row_dir, column_x, focal, s, row.t.data(), row.nx.data(), row.ny.data(),
                           row.nz.data(), row.footprint.data(), row.light.data(), row.haze.data());
  for (int u = 0; u < width; ++u) {
    const RayHit& hit = row.hits[static_cast<std::size_t>(u)];
    if (hit.kind == RayHit::Kind::kNone) {  // nothing hit (not in a closed hall): all haze
      row.albedo[u] = 0;
      row.haze[u] = 1;
      continue;
    }
    const V3 dir = col_x * column_x[static_cast<std::size_t>(u)] + row_dir;
    row.albedo[u] = surface_albedo(hit, origin + dir * hit.t, row.footprint[u], objects, shadows);
  }
  {
    const float haze_level = s.haze_level;
    const float* __restrict albedo = row.albedo.data();
    const float* __restrict light = row.light.data();
    const float* __restrict haze = row.haze.data();
    for (int u = 0; u < width; ++u) {
      const float lit = albedo[u] * light[u];
      radiance[u] = lit + (haze_level - lit) * haze[u];
    }
  }
}

// The centre sample plus two more on the pixel's diagonal (within half a pixel of the centre: the faces'
// sample rows). The static boxes at the samples are rasterised like the pixel centres, but only at the
// silhouette pixels of the row.
AGVSLAM_SIM_CLONES void Renderer::antialias_row(const RenderPass& p, int v) const {
  static constexpr float kOffsets[2][2] = {{-0.3f, -0.22f}, {0.3f, 0.22f}};
  const int width = p.width;
  CameraRender& out = *p.out;
  const std::vector<DynamicObject>& objects = *p.objects;
  const ObjectRects* rect_ptr = p.rects;
  const std::vector<BlobShadow>& shadows = *p.shadows;
  const std::vector<BoxFace>& faces = *p.faces;
  const std::vector<std::vector<uint32_t>>& face_buckets = *p.face_buckets;
  const float focal = p.focal;
  auto make_ray = [&p](float su, float sv) { return p.ray(su, sv); };
  const uint8_t* e = out.edge.ptr<uint8_t>(v);
  float* radiance = out.radiance.ptr<float>(v);
  SampleScratch& aa = sample_scratch();
  aa.cols.clear();
  for (int u = 0; u < width; ++u)
    if (e[u]) aa.cols.push_back(u);
  if (aa.cols.empty()) return;
  const std::size_t n = aa.cols.size();
  for (int k = 0; k < 2; ++k) {
    aa.z[k].assign(n, kInfinity);
    aa.key[k].assign(n, -1);
  }
  const int* cols = aa.cols.data();
  for (uint32_t fi : face_buckets[static_cast<std::size_t>(v / kFaceRowsPerBucket)]) {
    const BoxFace& f = faces[fi];
    if (v < f.sample_row0 || v > f.sample_row1) continue;
    for (int k = 0; k < 2; ++k) {
      const float du = kOffsets[k][0];
      const float vs = static_cast<float>(v) + kOffsets[k][1];
      double s0, s1;
      face_row_span(f.u, f.v, f.n, static_cast<double>(vs), s0, s1);
      if (s0 > s1) continue;
      // Silhouette pixels whose sample u + du lies in [s0, s1).
      const int u_lo = static_cast<int>(std::max(s0 - du, -4.0)) - 2;  // <= floor(s0 - du) - 1
      std::size_t i = static_cast<std::size_t>(std::lower_bound(cols, cols + n, u_lo) - cols);
      const float row_term = f.b * vs + f.c;
      float* zk = aa.z[k].data();
      int32_t* kk = aa.key[k].data();
      for (; i < n; ++i) {
        const float us = static_cast<float>(cols[i]) + du;
        if (us >= s1) break;
        if (us < s0) continue;
        const float z = f.k / (f.a * us + row_term);
        if (z > 0 && z < zk[i]) {
          zk[i] = z;
          kk[i] = f.key;
        }
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int u = cols[i];
    float sum = radiance[u];
    for (int k = 0; k < 2; ++k) {
      const Ray ray = make_ray(static_cast<float>(u) + kOffsets[k][0], static_cast<float>(v) + kOffsets[k][1]);
      RayHit hit;
      cast_hall(ray.origin, ray.dir, hit);
      if (aa.key[k][i] >= 16 && aa.z[k][i] < hit.t) set_box_hit(aa.key[k][i], aa.z[k][i], hit);
      cast_dynamic(ray, objects, rect_ptr, u, v, hit);
      sum += shade_hit(hit, ray.origin, ray.dir, objects, shadows, focal);
    }
    radiance[u] = sum * (1.0f / 3.0f);
  }
}

// ---- Analytic surfaces -----------------------------------------------------------------------------------------

AGVSLAM_SIM_CLONES float Renderer::floor_albedo(float x, float y, float w) const {
  const uint32_t seed = warehouse_.floor_seed;
  // Power-trowelled concrete: gentle broad tone variation, dark stains, lighter worn patches, fine grit.
  float c = 0.55f + 0.16f * fractal_noise(x, y, 1.2f, 3, 0.6f, w, seed);
  const float stain = value_noise(x * 0.4f, y * 0.4f, seed + 31U);
  c *= 1.0f - 0.3f * smoothstep(0.64f, 0.82f, stain);
  c += 0.07f * smoothstep(0.62f, 0.85f, 1.0f - stain);
  c += 0.26f * fractal_noise(x, y, 0.06f, 3, 0.85f, w, seed + 17U);
  // Tyre tracks (streaks along x in the aisles, along y elsewhere).
  const float track_vis = detail_visibility(0.1f, w);
  if (track_vis > 0) {
    const float track = value_noise(x * 0.35f, y * 9.0f, seed + 41U);
    c -= 0.10f * track_vis * smoothstep(0.7f, 0.88f, track);
  }
  // Saw-cut joints between slabs (6 m), dark.
  const float joints =
      std::max(stripe_coverage(x - 0.004f, 6.0f, 0.008f, w), stripe_coverage(y - 0.004f, 6.0f, 0.008f, w));
  c = lerp(c, 0.16f, 0.85f * joints);
  // Painted marks.
  const int ix = std::clamp(static_cast<int>(x / mark_cell_m_), 0, mark_nx_ - 1);
  const int iy = std::clamp(static_cast<int>(y / mark_cell_m_), 0, mark_ny_ - 1);
  for (uint16_t mi : mark_bins_[static_cast<std::size_t>(iy * mark_nx_ + ix)]) {
    const FloorMark& m = warehouse_.floor_marks[mi];
    float cov = rect_coverage(x, y, m.x0, m.x1, m.y0, m.y1, w);
    if (cov <= 0) continue;
    switch (m.kind) {
      case FloorMark::Kind::kSolid:
        break;
      case FloorMark::Kind::kDashedX:
        cov *= stripe_coverage(x, 1.0f, 0.6f, w);
        break;
      case FloorMark::Kind::kDashedY:
        cov *= stripe_coverage(y, 1.0f, 0.6f, w);
        break;
      case FloorMark::Kind::kHatched: {
        const float frame = 1.0f - rect_coverage(x, y, m.x0 + 0.06f, m.x1 - 0.06f, m.y0 + 0.06f, m.y1 - 0.06f, w);
        cov *= std::max(frame, stripe_coverage(x + y, 0.3f, 0.13f, w * 1.41f));
        break;
      }
    }
    // Worn paint.
    const float wear = 0.85f + 0.3f * fractal_noise(x, y, 0.2f, 2, 0.5f, w, seed + 53U);
    c = lerp(c, m.shade * wear, cov);
  }
  return std::max(0.02f, c);
}

AGVSLAM_SIM_CLONES float Renderer::wall_albedo(int wall, float u, float z, float w) const {
  const uint32_t seed = warehouse_.wall_seed + static_cast<uint32_t>(wall) * 7919U;
  float c;
  if (z < 0.3f) {
    // Painted kick band with hazard stripes.
    const float stripes = stripe_coverage(u + z, 0.4f, 0.2f, w * 1.41f);
    c = lerp(0.72f, 0.1f, stripes);
  } else if (z < 2.8f) {
    // Concrete blocks, 0.4 x 0.2 m, running bond.
    const float zz = z - 0.3f;
    const int32_t row = floor_to_int(zz / 0.2f);
    const float uu = u + ((row & 1) ? 0.2f : 0.0f);
    const int32_t col = floor_to_int(uu / 0.4f);
    const float block_tone = unit_from_hash(hash32(static_cast<uint32_t>(row), static_cast<uint32_t>(col), seed));
    c = 0.58f + 0.12f * (block_tone - 0.5f) * detail_visibility(0.2f, w);
    c += 0.14f * fractal_noise(u, z, 0.1f, 3, 0.65f, w, seed + 3U);
    const float mortar = std::max(stripe_coverage(zz, 0.2f, 0.012f, w), stripe_coverage(uu, 0.4f, 0.012f, w));
    c = lerp(c, 0.78f, mortar);
    // Grime towards the floor.
    c -= 0.12f * (1.0f - smoothstep(0.3f, 1.2f, z)) * (0.5f + value_noise(u * 0.7f, 0.0f, seed + 5U));
  } else if (z < 2.95f) {
    c = 0.26f + 0.05f * fractal_noise(u, z, 0.5f, 3, 0.5f, w, seed + 7U);
  } else {
    // Corrugated metal cladding with panel seams and fasteners.
    // Corrugation: a smooth periodic profile (parabolic arcs, no libm call).
    const float phase = u * 5.0f - fast_floor(u * 5.0f);     // 0.2 m ribs
    const float rib = 8.0f * phase * (1.0f - phase) - 1.0f;  // -1..1
    c = 0.56f + 0.1f * rib * detail_visibility(0.2f, w);
    // Weathering: streaks running down the panels and patchy dirt, so the ribs are not a perfect grating.
    c += 0.14f * fractal_noise(u * 4.0f, z * 0.5f, 0.6f, 3, 0.6f, w * 4.0f, seed + 11U);
    c += 0.1f * fractal_noise(u, z, 0.5f, 3, 0.6f, w, seed + 13U);
    c = lerp(c, 0.25f, stripe_coverage(u, 1.0f, 0.012f, w));
    c = lerp(c, 0.3f, stripe_coverage(z - 2.95f, 1.5f, 0.01f, w));
    c -= 0.1f * smoothstep(5.0f, 8.0f, z);
  }
  const int bin = std::clamp(floor_to_int(u), 0, wall_bins_ - 1);
  for (uint16_t fi : wall_feature_bins_[static_cast<std::size_t>(wall * wall_bins_ + bin)]) {
    const WallFeature& f = warehouse_.wall_features[fi];
    if (u < f.u0 - w || u > f.u1 + w || z < f.z0 - w || z > f.z1 + w) continue;
    const float cov = rect_coverage(u, z, f.u0, f.u1, f.z0, f.z1, w);
    if (cov <= 0) continue;
    const float lu = u - f.u0, lz = z - f.z0, fw = f.u1 - f.u0, fh = f.z1 - f.z0;
    float fc = 0.5f;
    switch (f.kind) {
      case WallFeature::Kind::kRollerDoor: {
        fc = 0.64f + 0.06f * fractal_noise(u, z, 0.5f, 2, 0.6f, w, f.seed);
        fc = lerp(fc, 0.35f, stripe_coverage(lz, 0.09f, 0.014f, w));
        fc = lerp(fc, 0.2f, rect_coverage(lu, lz, 0, fw, 0, 0.12f, w));
        // Yellow/black frame posts.
        const float post = rect_coverage(lu, lz, 0, 0.15f, 0, fh, w) + rect_coverage(lu, lz, fw - 0.15f, fw, 0, fh, w);
        fc = lerp(fc, lerp(0.78f, 0.08f, stripe_coverage(lu + lz, 0.3f, 0.15f, 1.41f * w)), post);
        // Dock number sign.
        const float sign = rect_coverage(lu, lz, fw * 0.5f - 0.25f, fw * 0.5f + 0.25f, fh - 0.55f, fh - 0.2f, w);
        fc = lerp(fc, 0.9f, sign);
        fc = lerp(
            fc, 0.05f,
            text_coverage(lu, lz, fw * 0.5f - 0.2f, fw * 0.5f + 0.2f, fh - 0.5f, fh - 0.25f, 0.1f, w, f.seed) * sign);
        break;
      }
      case WallFeature::Kind::kPoster: {
        const uint32_t h = f.seed;
        fc = 0.7f + 0.25f * unit_from_hash(hash32(h, 1U));
        fc = lerp(fc, 0.12f, frame_coverage(lu, lz, 0, fw, 0, fh, 0.02f, w));
        // Big blocks of colour (pictures / headings), then text.
        const float head_h = fh * 0.22f;
        fc = lerp(fc, 0.15f + 0.4f * unit_from_hash(hash32(h, 2U)),
                  rect_coverage(lu, lz, 0.05f, fw - 0.05f, fh - 0.05f - head_h, fh - 0.05f, w));
        fc = lerp(fc, 0.95f,
                  text_coverage(lu, lz, 0.08f, fw - 0.08f, fh - head_h, fh - 0.08f, head_h * 0.4f, w, h + 3U));
        const float pic_w = fw * (0.3f + 0.3f * unit_from_hash(hash32(h, 4U)));
        fc = lerp(fc, 0.1f + 0.6f * unit_from_hash(hash32(h, 5U)),
                  rect_coverage(lu, lz, 0.05f, 0.05f + pic_w, fh * 0.3f, fh - 0.1f - head_h, w));
        fc = lerp(fc, 0.1f,
                  text_coverage(lu, lz, 0.1f + pic_w, fw - 0.05f, fh * 0.3f, fh - 0.1f - head_h, 0.025f, w, h + 6U));
        fc = lerp(fc, 0.1f, text_coverage(lu, lz, 0.05f, fw - 0.05f, 0.05f, fh * 0.27f, 0.018f, w, h + 7U));
        break;
      }
      case WallFeature::Kind::kSign: {
        const bool dark = (f.seed & 1U) != 0;
        fc = dark ? 0.22f : 0.85f;
        fc = lerp(fc, dark ? 0.9f : 0.1f, frame_coverage(lu, lz, 0.02f, fw - 0.02f, 0.02f, fh - 0.02f, 0.025f, w));
        const float sym = std::min(fw, fh) * 0.5f;
        fc = lerp(fc, dark ? 0.92f : 0.12f,
                  rect_coverage(lu, lz, 0.08f, 0.08f + sym, (fh - sym) * 0.5f, (fh + sym) * 0.5f, w));
        fc = lerp(fc, dark ? 0.9f : 0.1f,
                  text_coverage(lu, lz, 0.12f + sym, fw - 0.05f, fh * 0.3f, fh * 0.7f, fh * 0.12f, w, f.seed));
        break;
      }
      case WallFeature::Kind::kCabinet: {
        fc = 0.62f + 0.05f * fractal_noise(lu, lz, 0.3f, 3, 0.5f, w, f.seed);
        fc = lerp(fc, 0.2f, frame_coverage(lu, lz, 0.03f, fw - 0.03f, 0.03f, fh - 0.03f, 0.008f, w));
        fc = lerp(fc, 0.1f, rect_coverage(lu, lz, fw - 0.09f, fw - 0.06f, fh * 0.4f, fh * 0.6f, w));
        fc = lerp(fc, 0.95f, rect_coverage(lu, lz, 0.08f, 0.2f, fh - 0.14f, fh - 0.08f, w));
        fc = lerp(fc, 0.15f, text_coverage(lu, lz, 0.09f, 0.19f, fh - 0.135f, fh - 0.085f, 0.012f, w, f.seed));
        break;
      }
      case WallFeature::Kind::kWindow: {
        fc = 1.35f + 0.2f * value_noise(lu * 0.5f, lz, f.seed);
        const float mullions = std::max(stripe_coverage(lu, 0.75f, 0.05f, w), stripe_coverage(lz, 0.6f, 0.05f, w));
        fc = lerp(fc, 0.18f, std::max(mullions, frame_coverage(lu, lz, 0, fw, 0, fh, 0.06f, w)));
        break;
      }
      case WallFeature::Kind::kPipe:
        fc = 0.4f;
        break;
    }
    c = lerp(c, fc, cov);
  }
  return std::max(0.02f, c);
}

AGVSLAM_SIM_CLONES float Renderer::ceiling_albedo(float x, float y, float w) const {
  const uint32_t seed = warehouse_.ceiling_seed;
  float c = 0.32f + 0.1f * fractal_noise(x, y, 1.0f, 3, 0.6f, w, seed);
  c = lerp(c, 0.5f, stripe_coverage(x, 5.0f, 0.3f, w));    // roof trusses
  c = lerp(c, 0.22f, stripe_coverage(y, 1.2f, 0.06f, w));  // purlins
  // Light fittings: bright strips on a 5 m x 4 m grid.
  const float lx = x - fast_floor(x / 5.0f) * 5.0f, ly = y - fast_floor(y / 4.0f) * 4.0f;
  c = lerp(c, 3.0f, rect_coverage(lx, ly, 2.3f, 2.7f, 1.2f, 2.8f, w));
  return c;
}

}  // namespace agvslam::sim
