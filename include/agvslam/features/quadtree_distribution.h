#pragma once
// ORB-SLAM2's DistributeOctTree: spreads corners over an area by a quadtree. The area is first cut into
// round(width / height) square-ish nodes; every node holding more than one corner is split into four, breadth
// first, until there are at least as many nodes as corners wanted (or no node can be split); when one more
// round would overshoot, the most populated nodes are split first. Each node keeps its strongest corner.
//
// This version works in place on an index array (a split partitions its node's range into four), so it does not
// allocate once its buffers have grown, and it is deterministic (ties go to the earlier candidate).

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace agvslam::features {

struct QuadtreeCandidate {
  float x = 0, y = 0;  // px, relative to the area's top-left corner
  float response = 0;  // larger is better
};

class QuadtreeDistributor {
 public:
  // candidates: inside [0, area_width) x [0, area_height). Writes to `kept` the indices (into `candidates`) of at
  // most `target_count` candidates, one per final node (if the last round overshoots, the weakest node winners
  // are dropped). Order: by decreasing response.
  void distribute(const std::vector<QuadtreeCandidate>& candidates, int area_width, int area_height, int target_count,
                  std::vector<int>& kept);

  // The final nodes of the last call (area coordinates), one per kept candidate before trimming, when
  // collect_nodes was set. A node is [x0, x1) x [y0, y1).
  void set_collect_nodes(bool collect) { collect_nodes_ = collect; }
  const std::vector<cv::Rect>& nodes() const { return node_rects_; }

 private:
  struct Node {
    int x0, y0, x1, y1;  // ORB-SLAM2's UL and BR corners (integer, the split point rounds up)
    int begin, end;      // range in index_
    int serial;          // creation order (tie-break of the size sort)
    bool alive;
  };
  void split(int node_index);

  std::vector<int> index_;    // candidate indices, grouped by node
  std::vector<int> scratch_;  // partition buffer
  std::vector<Node> nodes_;
  std::vector<int> expandable_, previous_expandable_;
  std::vector<int> winners_;
  std::vector<int> bucket_, fill_;
  const std::vector<QuadtreeCandidate>* candidates_ = nullptr;
  int alive_ = 0;
  bool collect_nodes_ = false;
  std::vector<cv::Rect> node_rects_;
};

}  // namespace agvslam::features
