#include "agvslam/dynamic/boundary.h"

#include <algorithm>

namespace agvslam::dynamic {

const char* to_string(BoundaryType type) {
  switch (type) {
    case BoundaryType::kCoplanar:
      return "coplanar";
    case BoundaryType::kHinge:
      return "hinge";
    case BoundaryType::kLeftOcclusion:
      return "left-occlusion";
    case BoundaryType::kRightOcclusion:
      return "right-occlusion";
    case BoundaryType::kUnknown:
      return "unknown";
  }
  return "?";
}

int SuperpixelGraph::add_or_get(int a, int b) {
  const int i = std::min(a, b), j = std::max(a, b);
  for (const auto& nb : neighbours_[static_cast<std::size_t>(i)]) {
    if (nb.first == j) return nb.second;
  }
  const int idx = static_cast<int>(boundaries_.size());
  SuperpixelBoundary sb;
  sb.i = i;
  sb.j = j;
  boundaries_.push_back(sb);
  boundary_moments_.emplace_back();
  neighbours_[static_cast<std::size_t>(i)].emplace_back(j, idx);
  neighbours_[static_cast<std::size_t>(j)].emplace_back(i, idx);
  return idx;
}

void SuperpixelGraph::build(const cv::Mat& labels, int count, cv::Point origin) {
  CV_Assert(labels.type() == CV_32SC1);
  regions_.assign(static_cast<std::size_t>(std::max(count, 0)), PixelMoments{});
  boxes_.assign(static_cast<std::size_t>(std::max(count, 0)), cv::Rect());
  boundaries_.clear();
  boundary_moments_.clear();
  neighbours_.resize(static_cast<std::size_t>(std::max(count, 0)));
  for (auto& nb : neighbours_) nb.clear();
  std::vector<cv::Point> lo(static_cast<std::size_t>(std::max(count, 0)), cv::Point(1 << 30, 1 << 30));
  std::vector<cv::Point> hi(static_cast<std::size_t>(std::max(count, 0)), cv::Point(-(1 << 30), -(1 << 30)));
  for (int y = 0; y < labels.rows; ++y) {
    const int32_t* row = labels.ptr<int32_t>(y);
    const int32_t* below = y + 1 < labels.rows ? labels.ptr<int32_t>(y + 1) : nullptr;
    const double gy = y + origin.y;
    for (int x = 0; x < labels.cols; ++x) {
      const int a = row[x];
      if (a < 0 || a >= count) continue;
      const double gx = x + origin.x;
      regions_[static_cast<std::size_t>(a)].add(gx, gy);
      cv::Point& l = lo[static_cast<std::size_t>(a)];
      cv::Point& h = hi[static_cast<std::size_t>(a)];
      l.x = std::min(l.x, x);
      l.y = std::min(l.y, y);
      h.x = std::max(h.x, x);
      h.y = std::max(h.y, y);
      if (x + 1 < labels.cols) {
        const int b = row[x + 1];
        if (b != a && b >= 0 && b < count) {
          const int idx = add_or_get(a, b);
          ++boundaries_[static_cast<std::size_t>(idx)].length;
          boundary_moments_[static_cast<std::size_t>(idx)].add(gx + 0.5, gy);
        }
      }
      if (below) {
        const int b = below[x];
        if (b != a && b >= 0 && b < count) {
          const int idx = add_or_get(a, b);
          ++boundaries_[static_cast<std::size_t>(idx)].length;
          boundary_moments_[static_cast<std::size_t>(idx)].add(gx, gy + 0.5);
        }
      }
    }
  }
  for (int k = 0; k < count; ++k) {
    const cv::Point& l = lo[static_cast<std::size_t>(k)];
    const cv::Point& h = hi[static_cast<std::size_t>(k)];
    if (h.x >= l.x) boxes_[static_cast<std::size_t>(k)] = cv::Rect(l + origin, h + origin + cv::Point(1, 1));
  }
}

int SuperpixelGraph::find(int a, int b) const {
  if (a < 0 || b < 0 || a >= count() || b >= count()) return -1;
  for (const auto& nb : neighbours_[static_cast<std::size_t>(a)]) {
    if (nb.first == b) return nb.second;
  }
  return -1;
}

BoundaryType SuperpixelGraph::type(int a, int b) const {
  const int idx = find(a, b);
  return idx < 0 ? BoundaryType::kUnknown : boundaries_[static_cast<std::size_t>(idx)].type;
}

double boundary_energy(BoundaryType type, const DisparityPlane& theta_i, const DisparityPlane& theta_j,
                       const PixelMoments& boundary, const PixelMoments& union_ij, const BoundaryConfig& config) {
  // d(p, theta_i) - d(p, theta_j) = da x + db y + dc
  const double da = theta_i.a - theta_j.a, db = theta_i.b - theta_j.b, dc = theta_i.c - theta_j.c;
  switch (type) {
    case BoundaryType::kCoplanar:
      return union_ij.mean_square(da, db, dc);
    case BoundaryType::kHinge:
      return boundary.mean_square(da, db, dc) + config.lambda_hinge;
    case BoundaryType::kLeftOcclusion:  // s_i in front
      return (boundary.sum_linear(da, db, dc) < 0 ? config.lambda_pen : 0.0) + config.lambda_occ;
    case BoundaryType::kRightOcclusion:  // s_j in front
      return (boundary.sum_linear(-da, -db, -dc) < 0 ? config.lambda_pen : 0.0) + config.lambda_occ;
    case BoundaryType::kUnknown:
      break;
  }
  return 0.0;
}

void label_boundaries(SuperpixelGraph& graph, const std::vector<DisparityPlane>& planes, const BoundaryConfig& config) {
  auto& boundaries = graph.boundaries();
  for (std::size_t b = 0; b < boundaries.size(); ++b) {
    SuperpixelBoundary& sb = boundaries[b];
    const DisparityPlane& pi = planes[static_cast<std::size_t>(sb.i)];
    const DisparityPlane& pj = planes[static_cast<std::size_t>(sb.j)];
    if (!pi.valid || !pj.valid) {
      sb.type = BoundaryType::kUnknown;
      sb.energy = {0, 0, 0, 0};
      continue;
    }
    PixelMoments u = graph.region(sb.i);
    u += graph.region(sb.j);
    const PixelMoments& bm = graph.boundary_points(static_cast<int>(b));
    int best = 0;
    for (int t = 0; t < 4; ++t) {
      sb.energy[static_cast<std::size_t>(t)] = boundary_energy(static_cast<BoundaryType>(t), pi, pj, bm, u, config);
      if (sb.energy[static_cast<std::size_t>(t)] < sb.energy[static_cast<std::size_t>(best)]) best = t;
    }
    sb.type = static_cast<BoundaryType>(best);
  }
}

}  // namespace agvslam::dynamic
