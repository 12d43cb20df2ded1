#pragma once
// Superpixel boundary labelling (paper 004, III.B, eqs. 9-11). For each pair of 4-adjacent superpixels
// s_i, s_j (i < j) with disparity planes theta_i, theta_j, each type o in {co, hi, lo, ro} has the energy
//   E(o) = E_smo(o) + E_prior(o)
//   E_smo(co) = mean over U_ij (all pixels of s_i and s_j) of (d(p, theta_i) - d(p, theta_j))^2
//   E_smo(hi) = mean over B_ij (the boundary)              of (d(p, theta_i) - d(p, theta_j))^2
//   E_smo(lo) = phi_occ(theta_i, theta_j),  E_smo(ro) = phi_occ(theta_j, theta_i)
//   phi_occ(front, back) = lambda_pen if sum over B of (d(p, front) - d(p, back)) < 0, else 0
//   E_prior = lambda_occ (lo, ro), lambda_hinge (hi), 0 (co),   lambda_occ > lambda_hinge > 0
// and the boundary gets the type of least energy. lo ("left occlusion"): the smaller-index superpixel s_i
// occludes s_j (it is in front: larger disparity); ro: s_j occludes s_i. B_ij is the set of midpoints
// between 4-adjacent pixel pairs of s_i and s_j; the means are evaluated exactly from pixel moments (the
// plane difference is linear in x, y).

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/dynamic/disparity_plane.h"

namespace agvslam::dynamic {

enum class BoundaryType : uint8_t { kCoplanar = 0, kHinge = 1, kLeftOcclusion = 2, kRightOcclusion = 3, kUnknown = 4 };

const char* to_string(BoundaryType type);
inline bool is_occlusion(BoundaryType t) {
  return t == BoundaryType::kLeftOcclusion || t == BoundaryType::kRightOcclusion;
}

// params/dynamic.yaml, section `boundaries`.
struct BoundaryConfig {
  double lambda_occ = 2.0;    // px^2: an occlusion needs a plane gap of more than ~sqrt(2) px
  double lambda_hinge = 0.5;  // px^2
  double lambda_pen = 20.0;   // px^2: an "occluder" that is behind is (practically) never chosen

  void validate(const std::string& source) const;
  std::string describe() const;
};

// First and second moments of a set of points, so that sums and means of (A x + B y + C)^k, k = 1, 2, over
// the set are exact closed forms.
struct PixelMoments {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  void add(double x, double y) {
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
  }
  PixelMoments& operator+=(const PixelMoments& o) {
    n += o.n;
    sx += o.sx;
    sy += o.sy;
    sxx += o.sxx;
    sxy += o.sxy;
    syy += o.syy;
    return *this;
  }
  // sum of (A x + B y + C)
  double sum_linear(double A, double B, double C) const { return A * sx + B * sy + C * n; }
  // mean of (A x + B y + C)^2
  double mean_square(double A, double B, double C) const {
    if (n <= 0) return 0;
    return (A * A * sxx + B * B * syy + C * C * n + 2 * A * B * sxy + 2 * A * C * sx + 2 * B * C * sy) / n;
  }
  cv::Point2d centroid() const { return n > 0 ? cv::Point2d(sx / n, sy / n) : cv::Point2d(); }
};

struct SuperpixelBoundary {
  int i = 0, j = 0;  // superpixel labels, i < j
  int length = 0;    // adjacent pixel pairs
  BoundaryType type = BoundaryType::kUnknown;
  std::array<double, 4> energy{{0, 0, 0, 0}};  // E for co, hi, lo, ro (when both planes exist)
};

// Adjacency of the superpixels of one ROI, with the pixel moments the energies need.
class SuperpixelGraph {
 public:
  // labels: CV_32SC1, 0 .. count-1, of a ROI whose top-left pixel is `origin` in the full image.
  void build(const cv::Mat& labels, int count, cv::Point origin);

  int count() const { return static_cast<int>(regions_.size()); }
  const std::vector<SuperpixelBoundary>& boundaries() const { return boundaries_; }
  std::vector<SuperpixelBoundary>& boundaries() { return boundaries_; }
  // Index into boundaries() of the pair (either order), -1 when not adjacent.
  int find(int a, int b) const;
  BoundaryType type(int a, int b) const;
  // (neighbour label, boundary index) of superpixel i.
  const std::vector<std::pair<int, int>>& neighbours(int i) const { return neighbours_[static_cast<std::size_t>(i)]; }
  // Moments of the pixels of superpixel i, and of the midpoints of boundary b (full-image coordinates).
  const PixelMoments& region(int i) const { return regions_[static_cast<std::size_t>(i)]; }
  const PixelMoments& boundary_points(int b) const { return boundary_moments_[static_cast<std::size_t>(b)]; }
  cv::Rect bounding_box(int i) const { return boxes_[static_cast<std::size_t>(i)]; }  // full-image coordinates

 private:
  int add_or_get(int a, int b);

  std::vector<PixelMoments> regions_;
  std::vector<cv::Rect> boxes_;
  std::vector<SuperpixelBoundary> boundaries_;
  std::vector<PixelMoments> boundary_moments_;
  std::vector<std::vector<std::pair<int, int>>> neighbours_;
};

// E(type) of eqs. 9-11 for planes theta_i (the smaller index) and theta_j.
double boundary_energy(BoundaryType type, const DisparityPlane& theta_i, const DisparityPlane& theta_j,
                       const PixelMoments& boundary, const PixelMoments& union_ij, const BoundaryConfig& config);

// Labels every boundary of the graph with its least-energy type; kUnknown where either plane is invalid.
void label_boundaries(SuperpixelGraph& graph, const std::vector<DisparityPlane>& planes, const BoundaryConfig& config);

}  // namespace agvslam::dynamic
