#include "agvslam/dynamic/region_search.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace agvslam::dynamic {

namespace {
bool stops(const SuperpixelGraph& graph, int a, int b, bool stop_at_unknown) {
  if (a == b) return false;
  const BoundaryType t = graph.type(a, b);
  return is_occlusion(t) || (stop_at_unknown && t == BoundaryType::kUnknown);
}
}  // namespace

namespace {
// -1: no plane; 0: plane inside the band; 1: plane outside the band or ground-like (disparity evaluated at
// pixel p).
int band_state(const DisparityBand& band, int label, cv::Point p) {
  const DisparityPlane& plane = (*band.planes)[static_cast<std::size_t>(label)];
  if (!plane.valid) return -1;
  const double x = p.x + band.origin.x, y = p.y + band.origin.y;
  if (band.ground && is_ground_like(plane, *band.ground, x, y, band.ground_tolerance_px, band.ground_tolerance_rel,
                                    band.ground_slope_tolerance)) {
    return 1;
  }
  if (!band.enabled) return 0;
  const double d = plane.disparity_at(x, y);
  return (d < band.lo_px || d > band.hi_px) ? 1 : 0;
}
}  // namespace

bool is_ground_like(const DisparityPlane& plane, const DisparityPlane& ground, double x, double y, double tolerance_px,
                    double tolerance_rel, double slope_tolerance) {
  if (!plane.valid || !ground.valid) return false;
  const double d_ground = ground.disparity_at(x, y);
  if (std::abs(plane.disparity_at(x, y) - d_ground) > tolerance_px + tolerance_rel * std::max(0.0, d_ground))
    return false;
  return std::abs(plane.b - ground.b) <= slope_tolerance * std::abs(ground.b);
}

DisparityPlane fit_ground_plane(const std::vector<cv::Point2f>& points_px, const std::vector<float>& disparity_px,
                                double horizon_y, double min_slope, int min_inliers) {
  CV_Assert(points_px.size() == disparity_px.size());
  std::vector<cv::Point3f> samples;
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    if (disparity_px[i] > 0 && points_px[i].y > horizon_y)
      samples.emplace_back(points_px[i].x, points_px[i].y, disparity_px[i]);
  }
  DisparityPlane ground;
  if (static_cast<int>(samples.size()) < min_inliers) return ground;
  PlaneFitConfig config;
  config.ransac_iterations = 100;
  config.inlier_threshold_px = 1.0;
  config.min_valid_pixels = min_inliers;
  config.min_valid_fraction = 0;
  config.min_inlier_fraction = 0.3;
  config.max_samples = 1000;
  uint32_t rng = 0x9e3779b9u;
  ground = fit_disparity_plane(samples, config, rng);
  if (!ground.valid || ground.b <= min_slope || ground.inliers < min_inliers) ground.valid = false;
  return ground;
}

std::array<cv::Point, 4> search_to_occlusion(const cv::Mat& labels, const SuperpixelGraph& graph, cv::Point start,
                                             bool stop_at_unknown, const DisparityBand& band) {
  CV_Assert(labels.type() == CV_32SC1);
  CV_Assert(start.x >= 0 && start.y >= 0 && start.x < labels.cols && start.y < labels.rows);
  const bool use_band = (band.enabled || band.ground != nullptr) && band.planes != nullptr;
  std::array<cv::Point, 4> out;
  const int dx[4] = {1, -1, 0, 0};
  const int dy[4] = {0, 0, 1, -1};
  for (int dir = 0; dir < 4; ++dir) {
    cv::Point p = start;
    cv::Point last_good = start;
    int label = labels.at<int32_t>(p);
    while (true) {
      const cv::Point q(p.x + dx[dir], p.y + dy[dir]);
      if (q.x < 0 || q.y < 0 || q.x >= labels.cols || q.y >= labels.rows) break;
      const int next = labels.at<int32_t>(q);
      if (next != label) {
        if (stops(graph, label, next, stop_at_unknown)) break;
        if (use_band && band_state(band, next, q) == 1) break;
        if (band.vetoed && (*band.vetoed)[static_cast<std::size_t>(next)]) break;
      }
      label = next;
      p = q;
      if (!use_band || band_state(band, label, p) != -1) last_good = p;
    }
    out[static_cast<std::size_t>(dir)] = use_band ? last_good : p;
  }
  return out;
}

int choose_start_superpixel(const cv::Mat& labels, cv::Point origin, const std::vector<DisparityPlane>& planes,
                            cv::Point2f point_px, float d_px, const RegionSearchConfig& config) {
  if (!(d_px > 0)) return -1;
  const int cx = static_cast<int>(std::lround(point_px.x)) - origin.x;
  const int cy = static_cast<int>(std::lround(point_px.y)) - origin.y;
  const double tolerance = config.start_tolerance_px + config.start_tolerance_rel * d_px;
  auto error_of = [&](int k) {
    if (k < 0 || k >= static_cast<int>(planes.size()) || !planes[static_cast<std::size_t>(k)].valid) return 1e30;
    return std::abs(planes[static_cast<std::size_t>(k)].disparity_at(point_px.x, point_px.y) - d_px);
  };
  // The point's own superpixel when its plane agrees, else the best-agreeing one nearby.
  if (cx >= 0 && cy >= 0 && cx < labels.cols && cy < labels.rows) {
    const int own = labels.at<int32_t>(cy, cx);
    if (error_of(own) <= tolerance) return own;
  }
  const int r = config.start_radius_px;
  int best = -1;
  double best_err = tolerance;
  for (int y = std::max(0, cy - r); y <= std::min(labels.rows - 1, cy + r); ++y) {
    for (int x = std::max(0, cx - r); x <= std::min(labels.cols - 1, cx + r); ++x) {
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r) continue;
      const int k = labels.at<int32_t>(y, x);
      const double err = error_of(k);
      if (err <= best_err) {
        best_err = err;
        best = k;
      }
    }
  }
  return best;
}

namespace {
// The group's points with the superpixel each starts from (-1: none) and the disparity range of those that start.
struct Starts {
  std::vector<int> label;
  double d_min = 1e30, d_max = -1e30;
};

// Static veto: superpixels holding a static point whose disparity agrees with their plane.
void veto_static_superpixels(const cv::Mat& labels, cv::Point origin, const SuperpixelGraph& graph,
                             const std::vector<DisparityPlane>& planes,
                             const std::vector<cv::Point2f>& static_points_px,
                             const std::vector<float>& static_disparity_px, const RegionSearchConfig& config,
                             std::vector<char>& vetoed, DynamicRegion& region) {
  for (std::size_t i = 0; i < static_points_px.size(); ++i) {
    const float d = static_disparity_px[i];
    if (!(d > 0)) continue;
    const int x = static_cast<int>(std::lround(static_points_px[i].x)) - origin.x;
    const int y = static_cast<int>(std::lround(static_points_px[i].y)) - origin.y;
    if (x < 0 || y < 0 || x >= labels.cols || y >= labels.rows) continue;
    const int k = labels.at<int32_t>(y, x);
    if (k < 0 || k >= graph.count() || vetoed[static_cast<std::size_t>(k)]) continue;
    const DisparityPlane& plane = planes[static_cast<std::size_t>(k)];
    const double tolerance = config.start_tolerance_px + config.start_tolerance_rel * d;
    if (plane.valid && std::abs(plane.disparity_at(static_points_px[i].x, static_points_px[i].y) - d) <= tolerance) {
      vetoed[static_cast<std::size_t>(k)] = 1;
      region.vetoed_superpixels.push_back(k);
    }
  }
}

Starts choose_starts(const cv::Mat& labels, cv::Point origin, const std::vector<DisparityPlane>& planes,
                     const std::vector<cv::Point2f>& points_px, const std::vector<float>& disparity_px,
                     const RegionSearchConfig& config, const DisparityPlane* ground, const std::vector<char>& vetoed) {
  Starts starts;
  starts.label.assign(points_px.size(), -1);
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    int& k = starts.label[i];
    k = choose_start_superpixel(labels, origin, planes, points_px[i], disparity_px[i], config);
    if (k >= 0 && vetoed[static_cast<std::size_t>(k)]) k = -1;
    // A point on the floor (a foot's sole, a wheel's contact) has the floor's disparity: it cannot start.
    if (k >= 0 && config.ground_veto && ground != nullptr && ground->valid &&
        is_ground_like(planes[static_cast<std::size_t>(k)], *ground, points_px[i].x, points_px[i].y,
                       config.ground_tolerance_px, config.ground_tolerance_rel, config.ground_slope_tolerance)) {
      k = -1;
    }
    if (k < 0) continue;
    starts.d_min = std::min(starts.d_min, static_cast<double>(disparity_px[i]));
    starts.d_max = std::max(starts.d_max, static_cast<double>(disparity_px[i]));
  }
  return starts;
}

// Superpixels whose appearance moved with the background (and that no point starts from) are static too.
void veto_background_superpixels(const std::vector<char>& moves_with_background, const Starts& starts, int count,
                                 std::vector<char>& vetoed, DynamicRegion& region) {
  std::vector<char> is_start(static_cast<std::size_t>(count), 0);
  for (int k : starts.label) {
    if (k >= 0) is_start[static_cast<std::size_t>(k)] = 1;
  }
  for (int k = 0; k < count; ++k) {
    const auto u = static_cast<std::size_t>(k);
    if (moves_with_background[u] && !is_start[u] && !vetoed[u]) {
      vetoed[u] = 1;
      region.vetoed_superpixels.push_back(k);
    }
  }
}

DisparityBand make_band(const RegionSearchConfig& config, const Starts& starts,
                        const std::vector<DisparityPlane>& planes, cv::Point origin, const std::vector<char>& vetoed,
                        const DisparityPlane* ground, DynamicRegion& region) {
  DisparityBand band;
  band.enabled = config.disparity_band && starts.d_max >= starts.d_min;
  band.planes = &planes;
  band.origin = origin;
  band.vetoed = &vetoed;
  if (config.ground_veto && ground != nullptr && ground->valid) {
    band.ground = ground;
    band.ground_tolerance_px = config.ground_tolerance_px;
    band.ground_tolerance_rel = config.ground_tolerance_rel;
    band.ground_slope_tolerance = config.ground_slope_tolerance;
  }
  if (band.enabled) {
    band.lo_px = starts.d_min - (config.band_tolerance_px + config.band_tolerance_rel * starts.d_min);
    band.hi_px = starts.d_max + (config.band_tolerance_px + config.band_tolerance_rel * starts.d_max);
    region.band_lo_px = band.lo_px;
    region.band_hi_px = band.hi_px;
  }
  return band;
}

// Inside superpixel k: the point's pixel (ROI coordinates) if it belongs to it, else its nearest pixel of k within
// radius_px.
cv::Point start_pixel(const cv::Mat& labels, cv::Point origin, const cv::Point2f& point_px, int k, int radius_px) {
  cv::Point start(static_cast<int>(std::lround(point_px.x)) - origin.x,
                  static_cast<int>(std::lround(point_px.y)) - origin.y);
  start.x = std::clamp(start.x, 0, labels.cols - 1);
  start.y = std::clamp(start.y, 0, labels.rows - 1);
  if (labels.at<int32_t>(start) == k) return start;
  int best_d2 = 1 << 30;
  cv::Point best = start;
  const int r = radius_px;
  for (int y = std::max(0, start.y - r); y <= std::min(labels.rows - 1, start.y + r); ++y) {
    for (int x = std::max(0, start.x - r); x <= std::min(labels.cols - 1, start.x + r); ++x) {
      const int d2 = (x - start.x) * (x - start.x) + (y - start.y) * (y - start.y);
      if (labels.at<int32_t>(y, x) == k && d2 < best_d2) {
        best_d2 = d2;
        best = cv::Point(x, y);
      }
    }
  }
  return best;
}

// The search from each started point to the occlusion boundaries: the start superpixels, the stop points and the
// rectangle they span.
void search_from_starts(const cv::Mat& labels, cv::Point origin, const SuperpixelGraph& graph,
                        const std::vector<cv::Point2f>& points_px, const Starts& starts,
                        const RegionSearchConfig& config, const DisparityBand& band, DynamicRegion& region) {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -(1 << 30), y1 = -(1 << 30);
  std::vector<char> is_start(static_cast<std::size_t>(graph.count()), 0);
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    const int k = starts.label[i];
    if (k < 0) continue;
    const cv::Point start = start_pixel(labels, origin, points_px[i], k, config.start_radius_px);
    ++region.started_points;
    if (!is_start[static_cast<std::size_t>(k)]) {
      is_start[static_cast<std::size_t>(k)] = 1;
      region.start_superpixels.push_back(k);
    }
    const auto stops = search_to_occlusion(labels, graph, start, config.stop_at_unknown, band);
    for (const cv::Point& s : stops) {
      x0 = std::min(x0, s.x);
      y0 = std::min(y0, s.y);
      x1 = std::max(x1, s.x);
      y1 = std::max(y1, s.y);
      region.stop_points.push_back(s + origin);
    }
  }
  if (region.started_points > 0)
    region.rectangle = cv::Rect(cv::Point(x0, y0) + origin, cv::Point(x1 + 1, y1 + 1) + origin);
}

// Local band: a plane must also agree with the nearest started point of the group at c (a group that spans two
// people at different depths has a wide band, which the background between them would pass).
bool agrees_with_nearest_start(const DisparityPlane& plane, const cv::Point2d& c,
                               const std::vector<cv::Point2f>& points_px, const std::vector<float>& disparity_px,
                               const Starts& starts, const RegionSearchConfig& config) {
  double best_d2 = 1e30, d_near = 0;
  for (std::size_t i = 0; i < points_px.size(); ++i) {
    if (starts.label[i] < 0) continue;
    const double dx = points_px[i].x - c.x, dy = points_px[i].y - c.y;
    if (dx * dx + dy * dy < best_d2) {
      best_d2 = dx * dx + dy * dy;
      d_near = disparity_px[i];
    }
  }
  const double tol = config.band_tolerance_px + config.band_tolerance_rel * d_near;
  return std::abs(plane.disparity_at(c.x, c.y) - d_near) <= tol;
}

// Flood over non-occlusion boundaries from the start superpixels, among superpixels whose centre lies inside the
// rectangle and whose plane is in the band and not ground. Superpixels without a plane do not extend the flood; with
// enclosed_unknown_only they are returned for add_enclosed_unknown.
std::vector<int> flood_superpixels(const SuperpixelGraph& graph, const std::vector<DisparityPlane>& planes,
                                   cv::Point origin, const std::vector<cv::Point2f>& points_px,
                                   const std::vector<float>& disparity_px, const Starts& starts,
                                   const RegionSearchConfig& config, const DisparityBand& band,
                                   const std::vector<char>& vetoed, DynamicRegion& region) {
  std::vector<char> seen(static_cast<std::size_t>(graph.count()), 0);
  std::vector<int> queue = region.start_superpixels;
  std::vector<int> unknown;
  for (int k : queue) seen[static_cast<std::size_t>(k)] = 1;
  const cv::Rect2d rect(region.rectangle);
  const bool checks_planes = band.enabled || band.ground != nullptr;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int k = queue[head];
    region.superpixels.push_back(k);
    for (const auto& nb : graph.neighbours(k)) {
      const int m = nb.first;
      if (seen[static_cast<std::size_t>(m)] || vetoed[static_cast<std::size_t>(m)]) continue;
      const BoundaryType t = graph.boundaries()[static_cast<std::size_t>(nb.second)].type;
      if (is_occlusion(t) || (config.stop_at_unknown && t == BoundaryType::kUnknown)) continue;
      const cv::Point2d c = graph.region(m).centroid();
      if (!rect.contains(c)) continue;
      const DisparityPlane& plane = planes[static_cast<std::size_t>(m)];
      if (checks_planes) {
        const int state = band_state(
            band, m,
            cv::Point(static_cast<int>(std::lround(c.x)) - origin.x, static_cast<int>(std::lround(c.y)) - origin.y));
        if (state == 1) continue;
      }
      if (config.local_band && band.enabled && plane.valid &&
          !agrees_with_nearest_start(plane, c, points_px, disparity_px, starts, config)) {
        continue;
      }
      seen[static_cast<std::size_t>(m)] = 1;
      if (!plane.valid && config.enclosed_unknown_only) {
        unknown.push_back(m);
        continue;
      }
      queue.push_back(m);
    }
  }
  return unknown;
}

// Superpixels without a plane join when the first other superpixel met from their centre left, right, up and down
// (inside the rectangle) is a member.
void add_enclosed_unknown(const cv::Mat& labels, cv::Point origin, const SuperpixelGraph& graph,
                          const std::vector<int>& unknown, DynamicRegion& region) {
  std::vector<char> member(static_cast<std::size_t>(graph.count()), 0);
  for (int k : region.superpixels) member[static_cast<std::size_t>(k)] = 1;
  const cv::Rect rect_local =
      cv::Rect(region.rectangle.tl() - origin, region.rectangle.size()) & cv::Rect(0, 0, labels.cols, labels.rows);
  for (int m : unknown) {
    const cv::Point2d c = graph.region(m).centroid();
    const cv::Point centre(std::clamp(static_cast<int>(std::lround(c.x)) - origin.x, 0, labels.cols - 1),
                           std::clamp(static_cast<int>(std::lround(c.y)) - origin.y, 0, labels.rows - 1));
    auto member_towards = [&](int dx, int dy) {
      for (cv::Point p = centre; rect_local.contains(p); p += cv::Point(dx, dy)) {
        const int k = labels.at<int32_t>(p);
        if (k == m) continue;
        return k >= 0 && k < graph.count() && member[static_cast<std::size_t>(k)] != 0;
      }
      return false;
    };
    if (member_towards(-1, 0) && member_towards(1, 0) && member_towards(0, -1) && member_towards(0, 1)) {
      region.superpixels.push_back(m);
    }
  }
}
}  // namespace

DynamicRegion find_dynamic_region(const cv::Mat& labels, cv::Point origin, const SuperpixelGraph& graph,
                                  const std::vector<DisparityPlane>& planes, const std::vector<cv::Point2f>& points_px,
                                  const std::vector<float>& disparity_px, const RegionSearchConfig& config,
                                  const std::vector<cv::Point2f>& static_points_px,
                                  const std::vector<float>& static_disparity_px, const DisparityPlane* ground,
                                  const std::vector<char>* moves_with_background) {
  CV_Assert(points_px.size() == disparity_px.size());
  CV_Assert(static_points_px.size() == static_disparity_px.size());
  DynamicRegion region;
  std::vector<char> vetoed(static_cast<std::size_t>(graph.count()), 0);
  if (config.static_veto) {
    veto_static_superpixels(labels, origin, graph, planes, static_points_px, static_disparity_px, config, vetoed,
                            region);
  }
  const Starts starts = choose_starts(labels, origin, planes, points_px, disparity_px, config, ground, vetoed);
  if (moves_with_background != nullptr && static_cast<int>(moves_with_background->size()) == graph.count()) {
    veto_background_superpixels(*moves_with_background, starts, graph.count(), vetoed, region);
  }
  const DisparityBand band = make_band(config, starts, planes, origin, vetoed, ground, region);
  search_from_starts(labels, origin, graph, points_px, starts, config, band, region);
  if (region.started_points == 0) return region;
  const std::vector<int> unknown =
      flood_superpixels(graph, planes, origin, points_px, disparity_px, starts, config, band, vetoed, region);
  if (!unknown.empty()) add_enclosed_unknown(labels, origin, graph, unknown, region);
  return region;
}

void paint_region(const DynamicRegion& region, const cv::Mat& labels, cv::Point origin, MaskMode mode, cv::Mat& mask,
                  uint8_t value) {
  CV_Assert(mask.type() == CV_8UC1);
  const cv::Rect image(cv::Point(0, 0), mask.size());
  const cv::Rect rect = region.rectangle & image;
  if (rect.empty()) return;
  if (mode == MaskMode::kRectangle) {
    mask(rect).setTo(value);
    return;
  }
  int max_label = -1;
  for (int k : region.superpixels) max_label = std::max(max_label, k);
  std::vector<char> member(static_cast<std::size_t>(max_label + 1), 0);
  for (int k : region.superpixels) member[static_cast<std::size_t>(k)] = 1;
  const cv::Rect roi_rect(origin, labels.size());
  const cv::Rect area = rect & roi_rect;
  for (int y = area.y; y < area.y + area.height; ++y) {
    const int32_t* l = labels.ptr<int32_t>(y - origin.y);
    uint8_t* m = mask.ptr<uint8_t>(y);
    for (int x = area.x; x < area.x + area.width; ++x) {
      const int k = l[x - origin.x];
      if (k >= 0 && k <= max_label && member[static_cast<std::size_t>(k)]) m[x] = value;
    }
  }
}

int label_region_objects(const cv::Mat& region_mask, bool split_side_by_side, int first_id, cv::Mat instances) {
  const auto clamp_id = [](int id) { return static_cast<uint8_t>(std::min(id, 255)); };
  if (!split_side_by_side) {
    instances.setTo(clamp_id(first_id), region_mask);
    return first_id + 1;
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(region_mask, labels, stats, centroids, 8, CV_32S);
  if (n <= 1) return first_id;
  int total = 0, largest = 1;
  for (int k = 1; k < n; ++k) {
    total += stats.at<int>(k, cv::CC_STAT_AREA);
    if (stats.at<int>(k, cv::CC_STAT_AREA) > stats.at<int>(largest, cv::CC_STAT_AREA)) largest = k;
  }
  std::vector<int> parent(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) parent[static_cast<std::size_t>(k)] = k;
  const auto root = [&](int k) {
    while (parent[static_cast<std::size_t>(k)] != k) k = parent[static_cast<std::size_t>(k)];
    return k;
  };
  const auto join = [&](int a, int b) {
    a = root(a);
    b = root(b);
    if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  };
  for (int a = 1; a < n; ++a) {
    if (stats.at<int>(a, cv::CC_STAT_AREA) * 50 < total) {
      join(a, largest);
      continue;
    }
    const int ax0 = stats.at<int>(a, cv::CC_STAT_LEFT), ax1 = ax0 + stats.at<int>(a, cv::CC_STAT_WIDTH);
    for (int b = a + 1; b < n; ++b) {
      if (stats.at<int>(b, cv::CC_STAT_AREA) * 50 < total) continue;
      const int bx0 = stats.at<int>(b, cv::CC_STAT_LEFT), bx1 = bx0 + stats.at<int>(b, cv::CC_STAT_WIDTH);
      const int overlap = std::min(ax1, bx1) - std::max(ax0, bx0);
      if (overlap * 2 >= std::min(ax1 - ax0, bx1 - bx0)) join(a, b);  // columns overlap by half the narrower
    }
  }
  std::vector<int> id_of(static_cast<std::size_t>(n), 0);
  int next = first_id;
  for (int k = 1; k < n; ++k) {
    const int r = root(k);
    if (id_of[static_cast<std::size_t>(r)] == 0) id_of[static_cast<std::size_t>(r)] = next++;
  }
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    uint8_t* out = instances.ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] > 0) out[x] = clamp_id(id_of[static_cast<std::size_t>(root(l[x]))]);
    }
  }
  return next;
}

}  // namespace agvslam::dynamic
