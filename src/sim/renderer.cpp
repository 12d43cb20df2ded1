// The renderer's construction (lookup tables of the static surfaces) and render(): the actors' screen
// rectangles, the static boxes' rasterisation, the row passes and the silhouettes to antialias. The row passes
// and the shading are in renderer_shading.cpp, the ray casts in renderer_raycast.cpp, the box rasterisation in
// renderer_raster.cpp, the procedural textures of the static surfaces in renderer_surfaces.cpp.

#include "agvslam/sim/renderer.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "renderer_internal.h"

namespace agvslam::sim {

using namespace render_detail;

namespace {

// Texture cache: level-0 texels of 1/512 m (about 2 mm: the footprint of a pixel on the floor nearest to the
// camera), tiles kept while any of the last 16 images (8 stereo frames) used them.
constexpr float kBaseTexelM = 1.0f / 512.0f;
constexpr uint32_t kKeepPasses = 16;

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

}  // namespace agvslam::sim
