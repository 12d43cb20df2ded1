// The per-pixel passes of render() and the shading: each row's hits, depth, ids, classes and surface keys, the
// pixel footprints, lighting and haze, the albedos (texture cache lookups of the static surfaces, the actors'
// textures), and the antialiasing of the silhouette pixels; shade() for single rays. The row passes and the
// surface lookups stay in one file so that the AVX2 copy of each calls the AVX2 copy of the next directly.

#include <algorithm>
#include <cmath>

#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/renderer.h"
#include "agvslam/sim/semantic_classes.h"
#include "agvslam/sim/texture.h"
#include "renderer_internal.h"

namespace agvslam::sim {

using namespace render_detail;

namespace {

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

// Nearest hall plane of every pixel of a row (ray directions col_x * column_x[u] + row_dir).
inline void row_hall_hits(int width, const V3 origin, const V3 col_x, const V3 row_dir, const V3 extent,
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

}  // namespace

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

}  // namespace agvslam::sim
