#pragma once
// CPU renderer for the warehouse. Per pixel centre it finds exactly what a ray cast would: the analytic
// floor/walls/ceiling, the nearest static box face (found by rasterising the camera-facing faces of the boxes
// with each face's exact plane depth at the pixel centre; identical to casting the pixel-centre ray), and the
// few moving primitives (ray cast inside each object's screen rectangle). Pixels on silhouettes get two more
// samples when antialiasing is on, found the same way: the box faces rasterised at the sample positions (only
// at those pixels), the hall and the actors ray cast. (cast() uses the 2-D grid DDA, cast_static, instead.)
//
// The procedural textures of the static surfaces (floor, ceiling, walls, box faces) are looked up in
// mip-mapped tiles baked on first use (TextureCache) rather than evaluated per pixel; the actors' textures are
// evaluated per pixel. Baked texels depend only on the layout, so the cache never changes a result.
//
// Outputs per camera: linear radiance (before exposure and noise), depth along the optical axis (the ray
// parameter: rays are built as R_m_c * ((u - cx) / fx, (v - cy) / fy, 1)), the id of the dynamic object seen
// at the pixel centre (0 = static scene), its semantic class (semantic_classes.h) and a surface key (for edge
// detection). Rows may be split across
// threads; every pixel is computed independently, so the result does not depend on the thread count.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <shared_mutex>
#include <vector>

#include "agvslam/sim/actors.h"
#include "agvslam/sim/geometry.h"
#include "agvslam/sim/texture_cache.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

struct CameraIntrinsics {
  double fx = 460, fy = 460, cx = 375.5, cy = 239.5;
  int width = 752, height = 480;
};

struct RenderSettings {
  bool antialias_edges = true;
  float haze_distance_m = 140.0f;  // <= 0: none
  float haze_level = 0.42f;        // radiance the haze tends to
  float ambient = 0.34f;           // lighting: ambient + sky * max(0, n.z) + sun * max(0, n . sun_dir)
  float sky = 0.30f;
  float sun = 0.42f;
  V3 sun_dir = normalized(V3{0.55f, 0.35f, 0.76f});
};

struct RayHit {
  enum class Kind : uint8_t { kNone, kFloor, kCeiling, kWall, kBox, kDynamic };
  float t = kInfinity;  // ray parameter (= depth along the optical axis for camera rays)
  Kind kind = Kind::kNone;
  uint8_t face = 0;      // box: axis * 2 + (outward normal positive); wall: wall index
  int32_t index = -1;    // box index (kBox) or primitive index (kDynamic)
  int16_t object = -1;   // index into the frame's objects (kDynamic)
  float axis_param = 0;  // capsules: position along the axis in [0, 1]
  V3 normal;             // unit, map frame
};

// Render targets of one camera, reused from frame to frame.
struct CameraRender {
  cv::Mat radiance;     // CV_32FC1, linear
  cv::Mat depth_m;      // CV_32FC1, depth along the optical axis (0 = nothing hit)
  cv::Mat object_id;    // CV_16UC1, actor id at the pixel centre (0 = static scene)
  cv::Mat class_id;     // CV_8UC1, SemanticClass of the surface at the pixel centre (semantic_classes.h)
  cv::Mat surface_key;  // CV_32SC1
  cv::Mat edge;         // CV_8UC1, scratch: pixels that were supersampled
};

class Renderer {
 public:
  Renderer(const Warehouse& warehouse, const RenderSettings& settings);

  // Renders one camera with pose T_m_c (camera frame: x right, y down, z forward) and the posed objects.
  void render(const CameraIntrinsics& cam, const Eigen::Isometry3d& T_m_c, const std::vector<DynamicObject>& objects,
              CameraRender& out, int threads = 1) const;

  // Nearest hit of one ray (map frame) with the static scene and the objects.
  RayHit cast(const Ray& ray, const std::vector<DynamicObject>& objects) const;
  // Linear radiance of a hit seen along `ray` with a pixel footprint scale of 1 / focal_px.
  float shade(const RayHit& hit, const Ray& ray, const std::vector<DynamicObject>& objects, float focal_px) const;

  // Albedo of the static surfaces as evaluated procedurally (what the texture cache bakes): the floor at (x, y),
  // wall `wall` at u metres along it and height z, the ceiling at (x, y), face `face` of box `box` at face
  // coordinates (u, v) (see FaceSample), each seen with a pixel footprint of footprint_m.
  float floor_albedo(float x, float y, float footprint_m) const;
  float wall_albedo(int wall, float u, float z, float footprint_m) const;
  float ceiling_albedo(float x, float y, float footprint_m) const;
  float box_face_albedo(std::size_t box, int face, float u, float v, float footprint_m) const;
  // The same from the texture cache (what shade() uses).
  float cached_floor_albedo(float x, float y, float footprint_m) const;
  float cached_wall_albedo(int wall, float u, float z, float footprint_m) const;
  float cached_ceiling_albedo(float x, float y, float footprint_m) const;
  float cached_box_face_albedo(std::size_t box, int face, float u, float v, float footprint_m) const;

  const Warehouse& warehouse() const { return warehouse_; }
  const RenderSettings& settings() const { return settings_; }

 private:
  struct PixelRect {
    int u0, v0, u1, v1;  // inclusive; empty when u0 > u1
  };
  // Screen rectangles of every object and of each of its primitives, for one camera.
  struct ObjectRects {
    std::vector<PixelRect> object;
    std::vector<std::vector<PixelRect>> primitive;
  };
  void cast_static(const Ray& ray, RayHit& hit) const;
  // Walls, floor and ceiling only, for the ray origin + t * dir (the origin is inside the hall).
  void cast_hall(const V3& origin, const V3& dir, RayHit& hit) const;
  V3 hall_extent() const { return {warehouse_.width_m, warehouse_.depth_m, warehouse_.height_m}; }
  // A camera-facing box face projected into the image (clipped to z >= z_near), with its plane for the depth at
  // image point (u, v): z = k / (a u + b v + c).
  struct BoxFace {
    float a, b, c, k;
    int32_t key;
    int n;
    double u[8], v[8];
    int row0, row1;                // rows whose pixel centres it may cover (empty when row0 > row1)
    int sample_row0, sample_row1;  // rows whose samples within half a pixel of the centre it may cover
  };
  static constexpr int kFaceRowsPerBucket = 8;
  // Projects the camera-facing faces of the static boxes (in box order) and lists them by blocks of
  // kFaceRowsPerBucket rows (over their sample rows; in face order).
  void project_box_faces(const CameraIntrinsics& cam, const Eigen::Isometry3d& T_m_c, std::vector<BoxFace>& faces,
                         std::vector<std::vector<uint32_t>>& buckets) const;
  // Primary visibility of the static boxes by rasterising their camera-facing faces, with the exact depth of
  // each face's plane at the pixel centre (what a pixel-centre ray cast returns). Fills `depth` (+inf where no
  // box) and `key` (surface key of the nearest face, -1 where none).
  void rasterize_boxes(const CameraIntrinsics& cam, const std::vector<BoxFace>& faces,
                       const std::vector<std::vector<uint32_t>>& buckets, cv::Mat& depth, cv::Mat& key,
                       int threads) const;
  static void rasterize_row(int width, const std::vector<BoxFace>& faces, const std::vector<uint32_t>& bucket, int v,
                            float* zrow, int32_t* krow);
  void cast_dynamic(const Ray& ray, const std::vector<DynamicObject>& objects, const ObjectRects* rects, int u, int v,
                    RayHit& hit) const;
  // The row passes of render(): hits, depth, ids, keys and radiance of row v; the antialiasing of row v.
  struct RenderPass;
  void render_row(const RenderPass& pass, int v) const;
  void antialias_row(const RenderPass& pass, int v) const;
  // Soft shadow of an actor on the floor: albedo *= 1 - 0.6 q^2 where q = 1 - squared distance / radius^2 > 0.
  struct BlobShadow {
    float x, y, inv_radius2;
  };
  static std::vector<BlobShadow> blob_shadows(const std::vector<DynamicObject>& objects);
  // shade() without the texture cache's pass lock (render() holds it).
  float shade_hit(const RayHit& hit, const V3& origin, const V3& dir, const std::vector<DynamicObject>& objects,
                  const std::vector<BlobShadow>& shadows, float focal_px) const;
  // Albedo of the surface hit at point p, seen with a pixel footprint of footprint_m.
  float surface_albedo(const RayHit& hit, const V3& p, float footprint_m, const std::vector<DynamicObject>& objects,
                       const std::vector<BlobShadow>& shadows) const;
  // Size (metres) of box face `face` (axis * 2 + positive): extents along its u and v coordinates.
  static void face_size(const StaticBox& box, int face, float& su, float& sv);

  const Warehouse& warehouse_;
  RenderSettings settings_;
  // Floor marks and wall features binned for fast lookup.
  float mark_cell_m_ = 2.0f;
  int mark_nx_ = 0, mark_ny_ = 0;
  std::vector<std::vector<uint16_t>> mark_bins_;
  std::vector<std::vector<uint16_t>> wall_feature_bins_;  // per wall and metre along it: [wall * wall_bins_ + m]
  int wall_bins_ = 0;
  // Ambient occlusion of the floor by the goods and racks standing on it (multiplier, 0.1 m raster).
  float ao_cell_m_ = 0.1f, inv_ao_cell_ = 10.0f;
  cv::Mat floor_ao_;  // CV_32FC1
  // Baked textures of the static surfaces (surface ids: floor, ceiling, 4 walls, then 6 faces per box). render()
  // starts a cache pass (which may free tiles) only while no other render or shade() holds pass_mutex_.
  mutable TextureCache textures_;
  mutable std::shared_mutex pass_mutex_;
};

// Albedo of a box face. `u`, `v` are face coordinates (metres from the face's corner; v is height on the
// vertical faces), su/sv the face size, box_size the box's extents, face = axis * 2 + positive.
struct FaceSample {
  float u = 0, v = 0, su = 1, sv = 1;
  V3 box_size;
  int face = 0;
  float footprint_m = 0.001f;
  uint32_t seed = 0;
};
float box_albedo(Material material, uint8_t variant, const FaceSample& f);
// Albedo of a point on an actor (p_local in the object's yaw frame: x forward, y left, z up).
float actor_albedo(const DynamicObject& obj, const DynamicPrimitive& prim, const V3& p_local, const V3& n_local,
                   float axis_param, float footprint_m);
// The same for a person's body, clothes and shoes (clothing.cpp).
float person_albedo(const DynamicObject& obj, const DynamicPrimitive& prim, const V3& p_local, const V3& n_local,
                    float axis_param, float footprint_m);

}  // namespace agvslam::sim
