// Primary visibility of the static boxes: their camera-facing faces projected into the image and rasterised row
// by row with each face's exact plane depth.

#include <algorithm>
#include <cmath>

#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/renderer.h"
#include "renderer_internal.h"

namespace agvslam::sim {

using namespace render_detail;

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

}  // namespace agvslam::sim
