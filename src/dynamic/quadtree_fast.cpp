#include "agvslam/dynamic/quadtree_fast.h"

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>

namespace agvslam::dynamic {

namespace {

struct Node {
  cv::Rect2f rect;
  std::vector<int> members;
};

bool splittable(const Node& n) { return n.members.size() > 1 && (n.rect.width > 0.5f || n.rect.height > 0.5f); }

void split(const Node& parent, const std::vector<Corner>& candidates, std::vector<Node>& out) {
  const float hw = parent.rect.width * 0.5f, hh = parent.rect.height * 0.5f;
  const float mx = parent.rect.x + hw, my = parent.rect.y + hh;
  Node child[4];
  child[0].rect = {parent.rect.x, parent.rect.y, hw, hh};
  child[1].rect = {mx, parent.rect.y, hw, hh};
  child[2].rect = {parent.rect.x, my, hw, hh};
  child[3].rect = {mx, my, hw, hh};
  for (int i : parent.members) {
    const cv::Point2f& p = candidates[static_cast<std::size_t>(i)].pt;
    const int q = (p.x < mx ? 0 : 1) + (p.y < my ? 0 : 2);
    child[q].members.push_back(i);
  }
  for (Node& c : child) {
    if (!c.members.empty()) out.push_back(std::move(c));
  }
}

}  // namespace

std::vector<Corner> distribute_quadtree(const std::vector<Corner>& candidates, const cv::Rect2f& area, int target_count,
                                        std::vector<cv::Rect2f>* node_rects) {
  std::vector<Corner> result;
  if (node_rects) node_rects->clear();
  if (candidates.empty() || target_count <= 0 || area.width <= 0 || area.height <= 0) return result;

  // (2) Initial nodes: about square, side = area height.
  const int initial = std::max(1, static_cast<int>(std::lround(area.width / area.height)));
  const float w = area.width / static_cast<float>(initial);
  std::vector<Node> nodes(static_cast<std::size_t>(initial));
  for (int i = 0; i < initial; ++i)
    nodes[static_cast<std::size_t>(i)].rect = {area.x + w * static_cast<float>(i), area.y, w, area.height};
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const cv::Point2f& p = candidates[i].pt;
    const int k = std::clamp(static_cast<int>((p.x - area.x) / w), 0, initial - 1);
    nodes[static_cast<std::size_t>(k)].members.push_back(static_cast<int>(i));
  }
  nodes.erase(std::remove_if(nodes.begin(), nodes.end(), [](const Node& n) { return n.members.empty(); }), nodes.end());

  // (3)-(4) Split rounds until N nodes hold a corner. Within a round the fullest nodes split first, so the
  // round that reaches N splits where the corners are densest.
  std::vector<Node> next;
  std::vector<int> order;
  while (static_cast<int>(nodes.size()) < target_count) {
    order.clear();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (splittable(nodes[i])) order.push_back(static_cast<int>(i));
    }
    if (order.empty()) break;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return nodes[static_cast<std::size_t>(a)].members.size() > nodes[static_cast<std::size_t>(b)].members.size();
    });
    std::vector<char> split_this(nodes.size(), 0);
    int count = static_cast<int>(nodes.size());
    std::vector<std::vector<Node>> children_of(nodes.size());
    for (int i : order) {
      if (count >= target_count) break;
      split(nodes[static_cast<std::size_t>(i)], candidates, children_of[static_cast<std::size_t>(i)]);
      split_this[static_cast<std::size_t>(i)] = 1;
      count += static_cast<int>(children_of[static_cast<std::size_t>(i)].size()) - 1;
    }
    next.clear();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (!split_this[i]) {
        next.push_back(std::move(nodes[i]));
      } else {
        for (Node& c : children_of[i]) next.push_back(std::move(c));
      }
    }
    nodes.swap(next);
  }

  // Strongest corner per node; trim the overshoot of the last round by dropping the weakest winners.
  std::vector<std::pair<Corner, cv::Rect2f>> winners;
  winners.reserve(nodes.size());
  for (const Node& n : nodes) {
    int best = n.members.front();
    for (int i : n.members) {
      if (candidates[static_cast<std::size_t>(i)].response > candidates[static_cast<std::size_t>(best)].response)
        best = i;
    }
    winners.emplace_back(candidates[static_cast<std::size_t>(best)], n.rect);
  }
  std::stable_sort(winners.begin(), winners.end(),
                   [](const auto& a, const auto& b) { return a.first.response > b.first.response; });
  if (static_cast<int>(winners.size()) > target_count) winners.resize(static_cast<std::size_t>(target_count));
  result.reserve(winners.size());
  for (const auto& w2 : winners) {
    result.push_back(w2.first);
    if (node_rects) node_rects->push_back(w2.second);
  }
  return result;
}

QuadtreeFast::QuadtreeFast(const QuadtreeFastConfig& config) : config_(config) {
  config_.validate("QuadtreeFastConfig");
}

void QuadtreeFast::detect(const cv::Mat& grey, std::vector<Corner>& corners, QuadtreeStats* stats, bool collect_nodes) {
  CV_Assert(grey.type() == CV_8UC1);
  corners.clear();
  const int b = config_.border_px;
  const cv::Rect area(b, b, grey.cols - 2 * b, grey.rows - 2 * b);
  if (area.width < 8 || area.height < 8) return;

  // (1) FAST (with non-maximum suppression) on the area plus the 3 px the FAST circle needs; in each cell the
  // corners that pass the normal threshold are kept, or all those at the fallback threshold where none does. This
  // equals running FAST per cell with the two thresholds (up to non-maximum suppression between a strong and a weak
  // corner). single_pass and two_pass find the same candidates; which is cheaper depends on the texture.
  const cv::Rect with_ring =
      cv::Rect(area.x - 3, area.y - 3, area.width + 6, area.height + 6) & cv::Rect(0, 0, grey.cols, grey.rows);
  const int cs = config_.cell_size_px;
  cells_x_ = (area.width + cs - 1) / cs;
  cells_y_ = (area.height + cs - 1) / cs;
  cell_best_.assign(static_cast<std::size_t>(cells_x_ * cells_y_), -1.0f);
  constexpr double kTwoPassMaxWeakFraction = 0.4;
  const bool two =
      config_.min_threshold < config_.threshold &&
      (extraction_ == Extraction::kTwoPass ||
       (extraction_ == Extraction::kAuto && last_weak_fraction_ >= 0 && last_weak_fraction_ < kTwoPassMaxWeakFraction));
  if (two) {
    two_pass(grey, area, with_ring);
  } else {
    single_pass(grey, area, with_ring);
  }
  const float strong = static_cast<float>(config_.threshold);
  int weak_cells = 0;
  for (float best : cell_best_) weak_cells += best >= 0 && best < strong;
  last_weak_fraction_ = static_cast<double>(weak_cells) / static_cast<double>(cell_best_.size());

  std::vector<cv::Rect2f>* rects = (stats && collect_nodes) ? &stats->node_rects : nullptr;
  corners = distribute_quadtree(candidates_, cv::Rect2f(area), config_.target_count, rects);
  if (stats) {
    stats->candidates = static_cast<int>(candidates_.size());
    stats->weak_cells = weak_cells;
  }
}

std::size_t QuadtreeFast::cell_of(const cv::Point2f& p, const cv::Rect& area) const {
  const int cs = config_.cell_size_px;
  const int cx = std::clamp(static_cast<int>(p.x - static_cast<float>(area.x)) / cs, 0, cells_x_ - 1);
  const int cy = std::clamp(static_cast<int>(p.y - static_cast<float>(area.y)) / cs, 0, cells_y_ - 1);
  return static_cast<std::size_t>(cy * cells_x_ + cx);
}

void QuadtreeFast::fast_into_candidates(const cv::Mat& grey, const cv::Rect& rect, int threshold, const cv::Rect& keep,
                                        const cv::Rect& area) {
  keypoints_.clear();
  cv::FAST(grey(rect), keypoints_, threshold, true, cv::FastFeatureDetector::TYPE_9_16);
  for (const cv::KeyPoint& kp : keypoints_) {
    const cv::Point2f p(kp.pt.x + static_cast<float>(rect.x), kp.pt.y + static_cast<float>(rect.y));
    if (!keep.contains(cv::Point(static_cast<int>(p.x), static_cast<int>(p.y)))) continue;
    float& best = cell_best_[cell_of(p, area)];
    best = std::max(best, kp.response);
    candidates_.push_back({p, kp.response});
  }
}

void QuadtreeFast::single_pass(const cv::Mat& grey, const cv::Rect& area, const cv::Rect& with_ring) {
  candidates_.clear();
  fast_into_candidates(grey, with_ring, config_.min_threshold, area, area);
  const float strong = static_cast<float>(config_.threshold);
  candidates_.erase(
      std::remove_if(candidates_.begin(), candidates_.end(),
                     [&](const Corner& c) { return c.response < strong && cell_best_[cell_of(c.pt, area)] >= strong; }),
      candidates_.end());
}

void QuadtreeFast::two_pass(const cv::Mat& grey, const cv::Rect& area, const cv::Rect& with_ring) {
  // The strong corners everywhere. Non-maximum suppression only ever removes a corner for a stronger neighbour,
  // which this pass finds as well, so these are the single pass's strong corners.
  candidates_.clear();
  fast_into_candidates(grey, with_ring, config_.threshold, area, area);
  // The weak corners of each run of cells without a strong one: FAST on the run plus 4 px (the circle's 3 and the
  // suppression's neighbour), within what the single pass sees, so suppression compares the same neighbours.
  const int cs = config_.cell_size_px;
  const float strong = static_cast<float>(config_.threshold);
  auto weak = [&](int cx, int cy) { return cell_best_[static_cast<std::size_t>(cy * cells_x_ + cx)] < strong; };
  for (int cy = 0; cy < cells_y_; ++cy) {
    for (int cx = 0; cx < cells_x_;) {
      if (!weak(cx, cy)) {
        ++cx;
        continue;
      }
      int end = cx;
      while (end < cells_x_ && weak(end, cy)) ++end;
      const cv::Rect run = cv::Rect(area.x + cx * cs, area.y + cy * cs, (end - cx) * cs, cs) & area;
      const cv::Rect padded = cv::Rect(run.x - 4, run.y - 4, run.width + 8, run.height + 8) & with_ring;
      fast_into_candidates(grey, padded, config_.min_threshold, run, area);
      cx = end;
    }
  }
  // FAST's order: row by row, left to right (the quadtree breaks ties between equal responses by this order).
  std::sort(candidates_.begin(), candidates_.end(),
            [](const Corner& a, const Corner& c) { return a.pt.y < c.pt.y || (a.pt.y == c.pt.y && a.pt.x < c.pt.x); });
}

}  // namespace agvslam::dynamic
