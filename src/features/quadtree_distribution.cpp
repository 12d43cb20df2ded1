#include "agvslam/features/quadtree_distribution.h"

#include <algorithm>
#include <cmath>

namespace agvslam::features {

namespace {
// A node can be split while it holds several candidates and is more than one pixel wide or high (candidates at
// the same pixel cannot be separated; ORB-SLAM2 would split such a node forever).
bool splittable(int size, int x0, int y0, int x1, int y1) { return size > 1 && (x1 - x0 > 1 || y1 - y0 > 1); }
}  // namespace

// Splits node `node_index` into up to four children holding its candidates (ORB-SLAM2's ExtractorNode::DivideNode:
// the split point is the node's corner plus half its size rounded up); children without candidates are not
// created. Children that can be split again are appended to expandable_.
void QuadtreeDistributor::split(int node_index) {
  const Node parent = nodes_[static_cast<std::size_t>(node_index)];
  const int half_x = static_cast<int>(std::ceil(static_cast<float>(parent.x1 - parent.x0) / 2.0f));
  const int half_y = static_cast<int>(std::ceil(static_cast<float>(parent.y1 - parent.y0) / 2.0f));
  const float mid_x = static_cast<float>(parent.x0 + half_x);
  const float mid_y = static_cast<float>(parent.y0 + half_y);
  const std::vector<QuadtreeCandidate>& c = *candidates_;

  // Counting sort of the node's range by quadrant (n1 top-left, n2 top-right, n3 bottom-left, n4 bottom-right).
  int counts[4] = {0, 0, 0, 0};
  for (int k = parent.begin; k < parent.end; ++k) {
    const QuadtreeCandidate& q = c[static_cast<std::size_t>(index_[static_cast<std::size_t>(k)])];
    const int quadrant = (q.x < mid_x ? 0 : 1) + (q.y < mid_y ? 0 : 2);
    scratch_[static_cast<std::size_t>(k)] = quadrant;
    ++counts[quadrant];
  }
  int starts[4];
  starts[0] = parent.begin;
  for (int q = 1; q < 4; ++q) starts[q] = starts[q - 1] + counts[q - 1];
  int fill[4] = {starts[0], starts[1], starts[2], starts[3]};
  // scratch_ holds quadrants in [begin, end); move the indices through winners_ as a temporary.
  winners_.resize(static_cast<std::size_t>(parent.end - parent.begin));
  for (int k = parent.begin; k < parent.end; ++k) {
    const int quadrant = scratch_[static_cast<std::size_t>(k)];
    winners_[static_cast<std::size_t>(fill[quadrant]++ - parent.begin)] = index_[static_cast<std::size_t>(k)];
  }
  std::copy(winners_.begin(), winners_.end(), index_.begin() + parent.begin);

  nodes_[static_cast<std::size_t>(node_index)].alive = false;
  --alive_;
  const int xs[3] = {parent.x0, parent.x0 + half_x, parent.x1};
  const int ys[3] = {parent.y0, parent.y0 + half_y, parent.y1};
  for (int q = 0; q < 4; ++q) {
    if (counts[q] == 0) continue;
    Node child;
    child.x0 = xs[q & 1];
    child.x1 = xs[(q & 1) + 1];
    child.y0 = ys[q >> 1];
    child.y1 = ys[(q >> 1) + 1];
    child.begin = starts[q];
    child.end = starts[q] + counts[q];
    child.serial = static_cast<int>(nodes_.size());
    child.alive = true;
    nodes_.push_back(child);
    ++alive_;
    if (splittable(counts[q], child.x0, child.y0, child.x1, child.y1)) expandable_.push_back(child.serial);
  }
}

void QuadtreeDistributor::distribute(const std::vector<QuadtreeCandidate>& candidates, int area_width, int area_height,
                                     int target_count, std::vector<int>& kept) {
  kept.clear();
  nodes_.clear();
  node_rects_.clear();
  expandable_.clear();
  alive_ = 0;
  const int n = static_cast<int>(candidates.size());
  if (n == 0 || target_count <= 0 || area_width <= 0 || area_height <= 0) return;
  candidates_ = &candidates;
  index_.resize(static_cast<std::size_t>(n));
  scratch_.resize(static_cast<std::size_t>(n));

  // Initial nodes: round(width / height) columns over the whole height.
  const int n_initial =
      std::max(1, static_cast<int>(std::lround(static_cast<float>(area_width) / static_cast<float>(area_height))));
  const float h_x = static_cast<float>(area_width) / static_cast<float>(n_initial);
  std::vector<int>& counts = bucket_;  // candidates per initial node, then their start offsets
  counts.assign(static_cast<std::size_t>(n_initial) + 1, 0);
  auto boundary = [&](int k) { return k >= n_initial ? area_width : static_cast<int>(h_x * static_cast<float>(k)); };
  for (int i = 0; i < n; ++i) {
    // ORB-SLAM2 picks the node by x / h_x but gives it the truncated bounds [int(h_x k), int(h_x (k + 1))); use
    // the bounds, so that each candidate lies inside its node's rectangle.
    const float x = candidates[static_cast<std::size_t>(i)].x;
    int node = std::clamp(static_cast<int>(x / h_x), 0, n_initial - 1);
    if (node > 0 && x < static_cast<float>(boundary(node))) --node;
    if (node + 1 < n_initial && x >= static_cast<float>(boundary(node + 1))) ++node;
    scratch_[static_cast<std::size_t>(i)] = node;
    ++counts[static_cast<std::size_t>(node) + 1];
  }
  for (int k = 0; k < n_initial; ++k) counts[static_cast<std::size_t>(k) + 1] += counts[static_cast<std::size_t>(k)];
  for (int k = 0; k < n_initial; ++k) {
    const int begin = counts[static_cast<std::size_t>(k)];
    const int end = counts[static_cast<std::size_t>(k) + 1];
    if (begin == end) continue;
    Node node;
    node.x0 = boundary(k);
    node.x1 = boundary(k + 1);
    node.y0 = 0;
    node.y1 = area_height;
    node.begin = begin;
    node.end = end;
    node.serial = static_cast<int>(nodes_.size());
    node.alive = true;
    nodes_.push_back(node);
    ++alive_;
    if (splittable(end - begin, node.x0, node.y0, node.x1, node.y1)) expandable_.push_back(node.serial);
  }
  fill_.assign(counts.begin(), counts.end() - 1);
  for (int i = 0; i < n; ++i) {
    index_[static_cast<std::size_t>(fill_[static_cast<std::size_t>(scratch_[static_cast<std::size_t>(i)])]++)] = i;
  }

  // Rounds of splitting every node with several candidates, until enough nodes exist or nothing changes. When a
  // whole round would overshoot the target, split the most populated nodes first and stop at the target.
  bool finish = false;
  while (!finish) {
    const int previous_alive = alive_;
    previous_expandable_.swap(expandable_);
    expandable_.clear();
    for (int node : previous_expandable_) split(node);
    const int n_to_expand = static_cast<int>(expandable_.size());
    if (alive_ >= target_count || alive_ == previous_alive) {
      finish = true;
    } else if (alive_ + 3 * n_to_expand > target_count) {
      while (!finish) {
        const int round_start_alive = alive_;
        previous_expandable_.swap(expandable_);
        expandable_.clear();
        std::sort(previous_expandable_.begin(), previous_expandable_.end(), [&](int a, int b) {
          const Node& na = nodes_[static_cast<std::size_t>(a)];
          const Node& nb = nodes_[static_cast<std::size_t>(b)];
          const int sa = na.end - na.begin, sb = nb.end - nb.begin;
          return sa != sb ? sa < sb : na.serial < nb.serial;
        });
        for (auto it = previous_expandable_.rbegin(); it != previous_expandable_.rend(); ++it) {
          split(*it);
          if (alive_ >= target_count) break;
        }
        if (alive_ >= target_count || alive_ == round_start_alive) finish = true;
      }
    }
  }

  // The strongest candidate of each node (ties: the earlier candidate).
  winners_.clear();
  for (const Node& node : nodes_) {
    if (!node.alive) continue;
    int best = index_[static_cast<std::size_t>(node.begin)];
    for (int k = node.begin + 1; k < node.end; ++k) {
      const int i = index_[static_cast<std::size_t>(k)];
      const float r = candidates[static_cast<std::size_t>(i)].response;
      const float rb = candidates[static_cast<std::size_t>(best)].response;
      if (r > rb || (r == rb && i < best)) best = i;
    }
    winners_.push_back(best);
    if (collect_nodes_) node_rects_.emplace_back(node.x0, node.y0, node.x1 - node.x0, node.y1 - node.y0);
  }
  auto stronger = [&](int a, int b) {
    const float ra = candidates[static_cast<std::size_t>(a)].response;
    const float rb = candidates[static_cast<std::size_t>(b)].response;
    return ra != rb ? ra > rb : a < b;
  };
  std::sort(winners_.begin(), winners_.end(), stronger);
  if (static_cast<int>(winners_.size()) > target_count) winners_.resize(static_cast<std::size_t>(target_count));
  kept.assign(winners_.begin(), winners_.end());
  candidates_ = nullptr;
}

}  // namespace agvslam::features
