#include "agvslam/dynamic/static_carve.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace agvslam::dynamic {

namespace {
float squared_distance(cv::Point2f a, cv::Point2f b) {
  const cv::Point2f e = a - b;
  return e.x * e.x + e.y * e.y;
}

// True when image point p is nearer to one of static_px than to every point of object_px.
bool nearer_static(cv::Point2f p, const std::vector<cv::Point2f>& object_px,
                   const std::vector<cv::Point2f>& static_px) {
  float nearest_static = std::numeric_limits<float>::max();
  for (const cv::Point2f& q : static_px) nearest_static = std::min(nearest_static, squared_distance(q, p));
  for (const cv::Point2f& q : object_px) {
    if (squared_distance(q, p) <= nearest_static) return false;
  }
  return true;
}

// The points of `points` that can be the nearest one to some pixel of a block centred at c, whose pixels lie within
// half_diagonal of c: within the nearest distance from c plus twice that (triangle inequality, both ways).
void near_block(const std::vector<cv::Point2f>& points, cv::Point2f c, float nearest, float half_diagonal,
                std::vector<cv::Point2f>& out) {
  const float reach = (nearest + 2 * half_diagonal) * (nearest + 2 * half_diagonal);
  for (const cv::Point2f& q : points) {
    if (squared_distance(q, c) <= reach) out.push_back(q);
  }
}

float nearest_distance(const std::vector<cv::Point2f>& points, cv::Point2f c) {
  float best = std::numeric_limits<float>::max();
  for (const cv::Point2f& q : points) best = std::min(best, squared_distance(q, c));
  return std::sqrt(best);
}
}  // namespace

namespace {
constexpr int kBlock = 4;
enum : uint8_t { kEmpty = 0, kObject = 1, kStatic = 2 };

// Each 4x4 block of `outline` holding outline pixels: kObject or kStatic by the distance transforms from the blocks
// holding each set's points (O(blocks), whatever the number of points); kEmpty otherwise.
std::vector<uint8_t> classify_blocks(const cv::Mat& outline, cv::Point outline_origin,
                                     const std::vector<cv::Point2f>& object_px,
                                     const std::vector<cv::Point2f>& static_px, int gw, int gh) {
  cv::Mat static_seeds(gh, gw, CV_8UC1, cv::Scalar(255)), object_seeds(gh, gw, CV_8UC1, cv::Scalar(255));
  const auto mark = [&](const std::vector<cv::Point2f>& points, cv::Mat& seeds) {
    for (const cv::Point2f& q : points) {
      const int gx =
          std::clamp(static_cast<int>(std::floor((q.x - static_cast<float>(outline_origin.x)) / kBlock)), 0, gw - 1);
      const int gy =
          std::clamp(static_cast<int>(std::floor((q.y - static_cast<float>(outline_origin.y)) / kBlock)), 0, gh - 1);
      seeds.at<uint8_t>(gy, gx) = 0;
    }
  };
  mark(static_px, static_seeds);
  mark(object_px, object_seeds);
  cv::Mat static_distance, object_distance;
  cv::distanceTransform(static_seeds, static_distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(object_seeds, object_distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  std::vector<uint8_t> block(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh), kEmpty);
  for (int by = 0; by < gh; ++by) {
    const float* ds = static_distance.ptr<float>(by);
    const float* dobj = object_distance.ptr<float>(by);
    for (int bx = 0; bx < gw; ++bx) {
      const cv::Rect r =
          cv::Rect(bx * kBlock, by * kBlock, kBlock, kBlock) & cv::Rect(0, 0, outline.cols, outline.rows);
      bool any = false;
      for (int y = r.y; y < r.br().y && !any; ++y) {
        const uint8_t* row = outline.ptr<uint8_t>(y);
        for (int x = r.x; x < r.br().x; ++x) any = any || row[x] != 0;
      }
      if (any) block[static_cast<std::size_t>(by * gw + bx)] = ds[bx] < dobj[bx] ? kStatic : kObject;
    }
  }
  return block;
}

// Whether every non-empty neighbour of block (bx, by) was decided as it was.
bool uniform_around(const std::vector<uint8_t>& block, int bx, int by, int gw, int gh) {
  const uint8_t b = block[static_cast<std::size_t>(by * gw + bx)];
  for (int ny = std::max(0, by - 1); ny <= std::min(gh - 1, by + 1); ++ny) {
    for (int nx = std::max(0, bx - 1); nx <= std::min(gw - 1, bx + 1); ++nx) {
      const uint8_t n = block[static_cast<std::size_t>(ny * gw + nx)];
      if (n != kEmpty && n != b) return false;
    }
  }
  return true;
}
}  // namespace

int carve_static_cells(cv::Mat& outline, cv::Point outline_origin, const std::vector<cv::Point2f>& object_px,
                       const std::vector<cv::Point2f>& static_px) {
  CV_Assert(outline.type() == CV_8UC1);
  if (object_px.empty() || static_px.empty() || outline.empty()) return cv::countNonZero(outline);
  // The split on a grid of 4x4 blocks first; blocks with a neighbour decided otherwise (where a cell boundary passes)
  // are then decided pixel by pixel, against the few points that can be nearest there.
  const int gw = (outline.cols + kBlock - 1) / kBlock, gh = (outline.rows + kBlock - 1) / kBlock;
  const std::vector<uint8_t> block = classify_blocks(outline, outline_origin, object_px, static_px, gw, gh);
  std::vector<cv::Point2f> near_object, near_static;
  const float half_diagonal = kBlock * 0.7072f;  // >= the 1.5 * sqrt(2) px from a block's centre to its pixels
  int kept = 0;
  for (int by = 0; by < gh; ++by) {
    for (int bx = 0; bx < gw; ++bx) {
      const uint8_t b = block[static_cast<std::size_t>(by * gw + bx)];
      if (b == kEmpty) continue;
      const bool uniform = uniform_around(block, bx, by, gw, gh);
      const int y1 = std::min(outline.rows, (by + 1) * kBlock), x1 = std::min(outline.cols, (bx + 1) * kBlock);
      if (!uniform) {
        const cv::Point2f c(static_cast<float>(outline_origin.x) + static_cast<float>(bx * kBlock + x1 - 1) * 0.5f,
                            static_cast<float>(outline_origin.y) + static_cast<float>(by * kBlock + y1 - 1) * 0.5f);
        const float nearest = std::min(nearest_distance(object_px, c), nearest_distance(static_px, c));
        near_object.clear();
        near_static.clear();
        near_block(object_px, c, nearest, half_diagonal, near_object);
        near_block(static_px, c, nearest, half_diagonal, near_static);
      }
      for (int y = by * kBlock; y < y1; ++y) {
        uint8_t* row = outline.ptr<uint8_t>(y);
        for (int x = bx * kBlock; x < x1; ++x) {
          if (!row[x]) continue;
          bool carve = b == kStatic;
          if (!uniform) {
            const cv::Point2f p(static_cast<float>(x + outline_origin.x), static_cast<float>(y + outline_origin.y));
            carve = !near_static.empty() && (near_object.empty() || nearer_static(p, near_object, near_static));
          }
          if (carve) {
            row[x] = 0;
          } else {
            ++kept;
          }
        }
      }
    }
  }
  return kept;
}

int carve_static_tracks(const StaticCarveOptions& options, const std::vector<TrackedPoint>& points,
                        const std::vector<cv::Point2f>& object_px, cv::Point outline_origin, cv::Mat& outline,
                        std::vector<cv::Point2f>& static_px) {
  const double min_d2 = options.min_distance_px * options.min_distance_px;
  static_px.clear();
  for (const TrackedPoint& p : points) {
    if (!p.tracked || p.dynamic || p.reprojection_px < 0 || p.reprojection_px > options.max_offset_px ||
        p.multiframe_px < 0 || p.multiframe_px > options.max_multiframe_px) {
      continue;
    }
    const cv::Point q(cvRound(p.cur_px.x) - outline_origin.x, cvRound(p.cur_px.y) - outline_origin.y);
    if (q.x < 0 || q.y < 0 || q.x >= outline.cols || q.y >= outline.rows || !outline.at<uint8_t>(q)) continue;
    bool far_from_object = true;
    for (const cv::Point2f& o : object_px) {
      const double dx = o.x - p.cur_px.x, dy = o.y - p.cur_px.y;
      if (dx * dx + dy * dy < min_d2) {
        far_from_object = false;
        break;
      }
    }
    if (far_from_object) static_px.push_back(p.cur_px);
  }
  if (static_cast<int>(static_px.size()) < options.min_tracks) return -1;
  return carve_static_cells(outline, outline_origin, object_px, static_px);
}

}  // namespace agvslam::dynamic
