#pragma once
// CPU renderer for the warehouse. Per pixel centre it finds exactly what a ray cast would: the analytic
// floor/walls/ceiling, the nearest static box face (found by rasterising the camera-facing faces of the boxes
// with each face's exact plane depth at the pixel centre; identical to casting the pixel-centre ray), and the
// few moving primitives (ray cast inside each object's screen rectangle). Pixels on silhouettes get two more
// samples, ray cast through the 2-D grid DDA (cast_static), when antialiasing is on.
//
// Outputs per camera: linear radiance (before exposure and noise), depth along the optical axis (the ray
// parameter: rays are built as R_m_c * ((u - cx) / fx, (v - cy) / fy, 1)), the id of the dynamic object seen
// at the pixel centre (0 = static scene) and a surface key (for edge detection). Rows may be split across
// threads; every pixel is computed independently, so the result does not depend on the thread count.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/sim/actors.h"
#include "agvslam/sim/geometry.h"
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
  uint8_t face = 0;     // box: axis * 2 + (outward normal positive); wall: wall index
  int32_t index = -1;   // box index (kBox) or primitive index (kDynamic)
  int16_t object = -1;  // index into the frame's objects (kDynamic)
  float axis_param = 0; // capsules: position along the axis in [0, 1]
  V3 normal;            // unit, map frame
};

// Render targets of one camera, reused from frame to frame.
struct CameraRender {
  cv::Mat radiance;   // CV_32FC1, linear
  cv::Mat depth_m;    // CV_32FC1, depth along the optical axis (0 = nothing hit)
  cv::Mat object_id;  // CV_16UC1, actor id at the pixel centre (0 = static scene)
  cv::Mat surface_key;// CV_32SC1
  cv::Mat edge;       // CV_8UC1, scratch: pixels that were supersampled
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
  // Walls, floor and ceiling only (the ray starts inside the hall).
  void cast_hall(const Ray& ray, RayHit& hit) const;
  // Primary visibility of the static boxes by rasterising their camera-facing faces, with the exact depth of
  // each face's plane at the pixel centre (what a pixel-centre ray cast returns). Fills `depth` (+inf where no
  // box) and `key` (surface key of the nearest face, -1 where none).
  void rasterize_boxes(const CameraIntrinsics& cam, const Eigen::Isometry3d& T_m_c, cv::Mat& depth, cv::Mat& key,
                       int threads) const;
  void cast_dynamic(const Ray& ray, const std::vector<DynamicObject>& objects, const ObjectRects* rects, int u, int v,
                    RayHit& hit) const;
  float floor_albedo(float x, float y, float footprint_m) const;
  float wall_albedo(int wall, float u, float z, float footprint_m) const;
  float ceiling_albedo(float x, float y, float footprint_m) const;

  const Warehouse& warehouse_;
  RenderSettings settings_;
  // Floor marks and wall features binned for fast lookup.
  float mark_cell_m_ = 2.0f;
  int mark_nx_ = 0, mark_ny_ = 0;
  std::vector<std::vector<uint16_t>> mark_bins_;
  std::vector<std::vector<uint16_t>> wall_feature_bins_;  // per wall and metre along it: [wall * wall_bins_ + m]
  int wall_bins_ = 0;
  // Ambient occlusion of the floor by the goods and racks standing on it (multiplier, 0.1 m raster).
  float ao_cell_m_ = 0.1f;
  cv::Mat floor_ao_;  // CV_32FC1
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

}  // namespace agvslam::sim
