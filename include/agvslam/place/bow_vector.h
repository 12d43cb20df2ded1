#pragma once
// Bag-of-words vectors and the direct index of one image (DBoW2's BowVector and FeatureVector, flat layouts).
//
// BowVector: sparse TF-IDF vector, entries sorted by word id, weights > 0, L1-normalised (the weights sum to 1)
// unless empty. Scoring is DBoW2's L1 score, 1 - |a - b|_1 / 2, which for two L1-normalised non-negative vectors
// equals the sum over their common words of min(a_w, b_w): 1 for identical vectors, 0 without a common word.
//
// FeatureVector (direct index): for every vocabulary node at one level (depth from the root) that some feature of
// the image passes through, the indices of those features (rows of the descriptor matrix). Two images' features
// that share a node are the only candidates ORB-SLAM2's SearchByBoW compares: for_each_common_node() is that loop.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace agvslam::place {

using WordId = uint32_t;  // 0 .. word_count - 1
using NodeId = uint32_t;  // 0 = root; nodes are numbered breadth-first, a node's children are consecutive

struct WordWeight {
  WordId word = 0;
  float weight = 0;
};

struct BowVector {
  std::vector<WordWeight> entries;  // ascending word id, unique, weight > 0

  bool empty() const { return entries.empty(); }
  std::size_t size() const { return entries.size(); }
  void clear() { entries.clear(); }
};

// DBoW2's L1 score in [0, 1] (see above). Both vectors must be L1-normalised (as Vocabulary::transform makes them).
double l1_score(const BowVector& a, const BowVector& b);
// Number of words present in both.
std::size_t common_words(const BowVector& a, const BowVector& b);

struct FeatureVector {
  int level = 0;                   // depth of the nodes below the root (1 .. vocabulary levels)
  std::vector<NodeId> nodes;       // ascending, unique
  std::vector<uint32_t> offsets;   // nodes.size() + 1 entries; features of nodes[i]: [offsets[i], offsets[i+1])
  std::vector<uint32_t> features;  // feature indices grouped by node, ascending within a node

  std::size_t size() const { return nodes.size(); }
  bool empty() const { return nodes.empty(); }
  void clear() {
    nodes.clear();
    offsets.clear();
    features.clear();
  }
  const uint32_t* features_begin(std::size_t i) const { return features.data() + offsets[i]; }
  const uint32_t* features_end(std::size_t i) const { return features.data() + offsets[i + 1]; }
};

// Calls f(node, a_begin, a_end, b_begin, b_end) for each node present in both feature vectors, in ascending node
// order; [a_begin, a_end) are feature indices of a's image, [b_begin, b_end) of b's. Both must use one level.
template <class F>
void for_each_common_node(const FeatureVector& a, const FeatureVector& b, F&& f) {
  std::size_t i = 0, j = 0;
  while (i < a.nodes.size() && j < b.nodes.size()) {
    if (a.nodes[i] < b.nodes[j]) {
      ++i;
    } else if (b.nodes[j] < a.nodes[i]) {
      ++j;
    } else {
      f(a.nodes[i], a.features_begin(i), a.features_end(i), b.features_begin(j), b.features_end(j));
      ++i;
      ++j;
    }
  }
}

}  // namespace agvslam::place
