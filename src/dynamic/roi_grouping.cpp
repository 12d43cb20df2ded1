#include "agvslam/dynamic/roi_grouping.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace agvslam::dynamic {

namespace {
int find_root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}
}  // namespace

std::vector<DynamicGroup> group_dynamic_points(const std::vector<cv::Point2f>& points_px,
                                               const std::vector<float>& disparity_px, cv::Size image_size,
                                               const RoiGroupingConfig& config, double baseline_m) {
  CV_Assert(points_px.size() == disparity_px.size());
  const int n = static_cast<int>(points_px.size());
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  for (int i = 0; i < n; ++i) {
    const float di = disparity_px[static_cast<std::size_t>(i)];
    if (!(di > 0)) continue;
    for (int j = i + 1; j < n; ++j) {
      const float dj = disparity_px[static_cast<std::size_t>(j)];
      if (!(dj > 0)) continue;
      const double d = 0.5 * (static_cast<double>(di) + dj);
      const double t_disp = config.t_disp_px + config.t_disp_rel * d;
      if (std::abs(static_cast<double>(di) - dj) > t_disp) continue;
      const double t_s = config.a_s_px + config.b_s * d;  // eq. 4
      const cv::Point2f delta = points_px[static_cast<std::size_t>(i)] - points_px[static_cast<std::size_t>(j)];
      if (static_cast<double>(delta.dot(delta)) > t_s * t_s) continue;
      const int ri = find_root(parent, i), rj = find_root(parent, j);
      if (ri != rj) parent[static_cast<std::size_t>(std::max(ri, rj))] = std::min(ri, rj);
    }
  }
  std::vector<std::vector<int>> by_root(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (disparity_px[static_cast<std::size_t>(i)] > 0)
      by_root[static_cast<std::size_t>(find_root(parent, i))].push_back(i);
  }
  std::vector<DynamicGroup> groups;
  const cv::Rect image(cv::Point(0, 0), image_size);
  auto finish = [&](DynamicGroup& g) {
    float x0 = 1e9f, y0 = 1e9f, x1 = -1e9f, y1 = -1e9f;
    double sum_d = 0;
    for (int i : g.members) {
      const cv::Point2f& p = points_px[static_cast<std::size_t>(i)];
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
      sum_d += disparity_px[static_cast<std::size_t>(i)];
    }
    g.mean_disparity_px = sum_d / static_cast<double>(g.members.size());
    g.bounds = cv::Rect(cv::Point(static_cast<int>(std::floor(x0)), static_cast<int>(std::floor(y0))),
                        cv::Point(static_cast<int>(std::floor(x1)) + 1, static_cast<int>(std::floor(y1)) + 1));
    const int margin =
        config.margin_px + static_cast<int>(std::lround(config.margin_disparity_factor * g.mean_disparity_px));
    g.roi =
        cv::Rect(g.bounds.x - margin, g.bounds.y - margin, g.bounds.width + 2 * margin, g.bounds.height + 2 * margin) &
        image;
  };
  std::vector<DynamicGroup> candidates;
  const std::size_t min_merge = config.merge_overlapping ? 2 : static_cast<std::size_t>(config.min_points);
  for (auto& members : by_root) {
    if (members.size() < std::max<std::size_t>(1, std::min(min_merge, static_cast<std::size_t>(config.min_points))))
      continue;
    DynamicGroup g;
    g.members = std::move(members);
    finish(g);
    candidates.push_back(std::move(g));
  }
  if (config.merge_overlapping) {
    bool merged = true;
    while (merged) {
      merged = false;
      for (std::size_t a = 0; a < candidates.size() && !merged; ++a) {
        for (std::size_t b = a + 1; b < candidates.size() && !merged; ++b) {
          const double d = 0.5 * (candidates[a].mean_disparity_px + candidates[b].mean_disparity_px);
          if (std::abs(candidates[a].mean_disparity_px - candidates[b].mean_disparity_px) >
              config.t_disp_px + config.t_disp_rel * d) {
            continue;
          }
          // Overlapping ROIs, or parts stacked vertically (overlapping columns, gap <= T_s): an upright object.
          const cv::Rect& ra = candidates[a].roi;
          const cv::Rect& rb = candidates[b].roi;
          const bool columns_overlap = std::max(ra.x, rb.x) < std::min(ra.br().x, rb.br().x);
          const int gap_y = std::max(ra.y, rb.y) - std::min(ra.br().y, rb.br().y);
          // Side by side: rows overlap, columns within merge_side_gap_m at this depth (d px = B / Z).
          const int gap_x = std::max(ra.x, rb.x) - std::min(ra.br().x, rb.br().x);
          const bool side_by_side = baseline_m > 0 && config.merge_side_gap_m > 0 && gap_y < 0 &&
                                    gap_x <= config.merge_side_gap_m * d / baseline_m;
          if ((ra & rb).empty() && !(columns_overlap && gap_y <= config.a_s_px + config.b_s * d) && !side_by_side)
            continue;
          candidates[a].members.insert(candidates[a].members.end(), candidates[b].members.begin(),
                                       candidates[b].members.end());
          finish(candidates[a]);
          candidates.erase(candidates.begin() + static_cast<std::ptrdiff_t>(b));
          merged = true;
        }
      }
    }
  }
  for (auto& g : candidates) {
    if (static_cast<int>(g.members.size()) >= config.min_points) groups.push_back(std::move(g));
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const DynamicGroup& a, const DynamicGroup& b) { return a.members.size() > b.members.size(); });
  return groups;
}

}  // namespace agvslam::dynamic
