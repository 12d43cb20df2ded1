// BowVector scoring and the FeatureVector common-node loop on hand-made vectors.
#include "agvslam/place/bow_vector.h"

#include <gtest/gtest.h>

namespace agvslam::place {
namespace {

BowVector bow(std::vector<WordWeight> e) {
  BowVector b;
  b.entries = std::move(e);
  return b;
}

TEST(BowVector, L1ScoreIsOneMinusHalfTheL1Distance) {
  const BowVector a = bow({{1, 0.5f}, {4, 0.25f}, {9, 0.25f}});
  const BowVector b = bow({{1, 0.25f}, {5, 0.5f}, {9, 0.25f}});
  // |a - b|_1 = 0.25 + 0.25 + 0.5 + 0 = 1.0 -> 0.5; sum of minima 0.25 + 0.25.
  EXPECT_DOUBLE_EQ(l1_score(a, b), 0.5);
  EXPECT_DOUBLE_EQ(l1_score(b, a), 0.5);
  EXPECT_DOUBLE_EQ(l1_score(a, a), 1.0);
  EXPECT_EQ(common_words(a, b), 2u);
  EXPECT_DOUBLE_EQ(l1_score(a, bow({{2, 1.f}})), 0.0);
  EXPECT_DOUBLE_EQ(l1_score(a, BowVector{}), 0.0);
}

TEST(FeatureVector, CommonNodesInAscendingOrder) {
  FeatureVector a, b;
  a.level = b.level = 2;
  a.nodes = {3, 7, 12};
  a.offsets = {0, 2, 3, 5};
  a.features = {0, 4, 1, 2, 3};
  b.nodes = {7, 12, 20};
  b.offsets = {0, 1, 3, 4};
  b.features = {5, 0, 2, 1};
  std::vector<NodeId> seen;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for_each_common_node(a, b,
                       [&](NodeId n, const uint32_t* a0, const uint32_t* a1, const uint32_t* b0, const uint32_t* b1) {
                         seen.push_back(n);
                         for (auto i = a0; i != a1; ++i)
                           for (auto j = b0; j != b1; ++j) pairs.emplace_back(*i, *j);
                       });
  EXPECT_EQ(seen, (std::vector<NodeId>{7, 12}));
  EXPECT_EQ(pairs, (std::vector<std::pair<uint32_t, uint32_t>>{{1, 5}, {2, 0}, {2, 2}, {3, 0}, {3, 2}}));
}

}  // namespace
}  // namespace agvslam::place
