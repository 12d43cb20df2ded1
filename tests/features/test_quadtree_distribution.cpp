// QuadtreeDistributor (ORB-SLAM2's DistributeOctTree): count, one corner per node, the strongest per node, spread
// over clusters, and degenerate inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/core.hpp>

#include "agvslam/features/quadtree_distribution.h"

namespace agvslam::features {
namespace {

std::vector<QuadtreeCandidate> random_candidates(int n, int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<QuadtreeCandidate> c(static_cast<std::size_t>(n));
  for (auto& q : c) {
    q.x = static_cast<float>(rng.uniform(0, width));
    q.y = static_cast<float>(rng.uniform(0, height));
    q.response = static_cast<float>(rng.uniform(7, 100));
  }
  return c;
}

TEST(QuadtreeDistribution, KeepsTheTargetCountOnePerNodeTheStrongest) {
  const auto c = random_candidates(5000, 720, 448, 1);
  QuadtreeDistributor q;
  q.set_collect_nodes(true);
  std::vector<int> kept;
  q.distribute(c, 720, 448, 388, kept);
  EXPECT_EQ(kept.size(), 388u);
  const std::vector<cv::Rect>& nodes = q.nodes();
  ASSERT_GE(nodes.size(), 388u);
  ASSERT_LE(nodes.size(), 388u + 3u);  // the last split overshoots by at most 3
  for (std::size_t k = 1; k < kept.size(); ++k) {
    EXPECT_GE(c[static_cast<std::size_t>(kept[k - 1])].response, c[static_cast<std::size_t>(kept[k])].response);
  }
  // Nodes are disjoint and every candidate lies in one; each kept candidate is the strongest of its node.
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    for (std::size_t b = a + 1; b < nodes.size(); ++b) EXPECT_TRUE((nodes[a] & nodes[b]).empty());
  }
  std::vector<float> node_best(nodes.size(), -1.0f);
  for (const auto& cand : c) {
    int inside = 0;
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      if (nodes[n].contains(cv::Point(static_cast<int>(cand.x), static_cast<int>(cand.y)))) {
        ++inside;
        node_best[n] = std::max(node_best[n], cand.response);
      }
    }
    EXPECT_EQ(inside, 1);
  }
  for (int i : kept) {
    const auto& cand = c[static_cast<std::size_t>(i)];
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      if (nodes[n].contains(cv::Point(static_cast<int>(cand.x), static_cast<int>(cand.y)))) {
        EXPECT_EQ(cand.response, node_best[n]);
      }
    }
  }
}

TEST(QuadtreeDistribution, SpreadsOverAClusterInsteadOfKeepingItsStrongest) {
  // 2000 strong corners packed in a 60x60 corner of the image and 100 weak ones spread elsewhere: the weak ones
  // survive (each sits alone in its node), the cluster is thinned.
  std::vector<QuadtreeCandidate> c = random_candidates(2000, 60, 60, 2);
  for (auto& q : c) q.response += 100;
  cv::RNG rng(3);
  for (int i = 0; i < 100; ++i) {
    c.push_back({static_cast<float>(rng.uniform(100, 720)), static_cast<float>(rng.uniform(100, 448)), 8.0f});
  }
  QuadtreeDistributor q;
  std::vector<int> kept;
  q.distribute(c, 720, 448, 300, kept);
  ASSERT_EQ(kept.size(), 300u);
  int weak = 0;
  for (int i : kept) weak += i >= 2000;
  EXPECT_GE(weak, 95);
  EXPECT_LE(300 - weak, 205);
}

TEST(QuadtreeDistribution, FewerCandidatesThanWantedKeepsAll) {
  const auto c = random_candidates(50, 300, 200, 4);
  QuadtreeDistributor q;
  std::vector<int> kept;
  q.distribute(c, 300, 200, 100, kept);
  // Candidates at the same pixel cannot be separated: count the distinct pixels.
  std::vector<std::pair<int, int>> pixels;
  for (const auto& cand : c) pixels.emplace_back(static_cast<int>(cand.x), static_cast<int>(cand.y));
  std::sort(pixels.begin(), pixels.end());
  pixels.erase(std::unique(pixels.begin(), pixels.end()), pixels.end());
  EXPECT_EQ(kept.size(), pixels.size());
}

TEST(QuadtreeDistribution, DuplicatesAndEmptyInputTerminate) {
  std::vector<QuadtreeCandidate> same(20, QuadtreeCandidate{10.f, 10.f, 5.f});
  same[7].response = 9.f;
  QuadtreeDistributor q;
  std::vector<int> kept;
  q.distribute(same, 100, 100, 10, kept);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0], 7);
  q.distribute({}, 100, 100, 10, kept);
  EXPECT_TRUE(kept.empty());
  q.distribute(random_candidates(10, 100, 100, 5), 100, 100, 0, kept);
  EXPECT_TRUE(kept.empty());
  // A tall area (width < height) still works: one initial node.
  q.distribute(random_candidates(500, 50, 400, 6), 50, 400, 40, kept);
  EXPECT_EQ(kept.size(), 40u);
}

}  // namespace
}  // namespace agvslam::features
