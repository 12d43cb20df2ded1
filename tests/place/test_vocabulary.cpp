// Vocabulary training (known clusters are recovered), TF-IDF weights, transform, scoring and the direct index.
#include "agvslam/place/vocabulary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include "agvslam/core/error.h"
#include "synthetic_descriptors.h"

namespace agvslam::place {
namespace {

using test::Descriptor;

struct Labelled {
  std::vector<Descriptor> descriptors;
  std::vector<int> label;
};

// `clusters` random centres; `per_cluster` members each, `noise_bits` bits flipped per member.
Labelled flat_clusters(int clusters, int per_cluster, int noise_bits, uint64_t seed,
                       std::vector<Descriptor>* centres_out) {
  std::mt19937_64 rng(seed);
  std::vector<Descriptor> centres;
  for (int c = 0; c < clusters; ++c) centres.push_back(test::random_descriptor(rng));
  Labelled out;
  for (int i = 0; i < per_cluster; ++i)
    for (int c = 0; c < clusters; ++c) {
      out.descriptors.push_back(test::flip_bits(centres[std::size_t(c)], noise_bits, rng));
      out.label.push_back(c);
    }
  if (centres_out) *centres_out = centres;
  return out;
}

DescriptorSet as_images(const std::vector<Descriptor>& ds, std::size_t per_image) {
  DescriptorSet set;
  for (std::size_t b = 0; b < ds.size(); b += per_image)
    set.add_image(test::to_mat({ds.begin() + long(b), ds.begin() + long(std::min(ds.size(), b + per_image))}));
  return set;
}

// Checks that labels and words are in one-to-one correspondence.
void expect_bijection(const Vocabulary& v, const Labelled& data, int clusters) {
  std::map<int, std::set<WordId>> words_of_label;
  std::map<WordId, std::set<int>> labels_of_word;
  for (std::size_t i = 0; i < data.descriptors.size(); ++i) {
    const WordId w = v.word(data.descriptors[i].data());
    words_of_label[data.label[i]].insert(w);
    labels_of_word[w].insert(data.label[i]);
  }
  ASSERT_EQ(int(words_of_label.size()), clusters);
  for (auto& [label, words] : words_of_label) EXPECT_EQ(words.size(), 1u) << "cluster " << label << " was split";
  for (auto& [word, labels] : labels_of_word) EXPECT_EQ(labels.size(), 1u) << "word " << word << " mixes clusters";
}

TEST(VocabularyTraining, RecoversKnownClustersAndTheirCentres) {
  std::vector<Descriptor> centres;
  const Labelled data = flat_clusters(10, 200, 12, 42, &centres);
  VocabularyTrainingConfig cfg;
  cfg.branching = 10;
  cfg.levels = 1;
  const Vocabulary v = Vocabulary::train(as_images(data.descriptors, 100), cfg);
  ASSERT_EQ(v.word_count(), 10u);
  EXPECT_EQ(v.node_count(), 11u);
  expect_bijection(v, data, 10);
  // The majority-bit median of a cluster is its centre (every bit is flipped in ~5 % of the members).
  for (int c = 0; c < 10; ++c) {
    const WordId w = v.word(centres[std::size_t(c)].data());
    EXPECT_EQ(test::distance(v.node_descriptor(v.word_node(w)), centres[std::size_t(c)].data()), 0) << "cluster " << c;
  }
}

TEST(VocabularyTraining, RecoversHierarchicalClusters) {
  // 4 groups of 4 sub-clusters: groups are ~128 bits apart, sub-clusters of a group ~37, members 4 bits from their
  // sub-cluster. k = 4, L = 2 must put each group under one level-1 node and each sub-cluster in one word.
  for (uint64_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    Labelled data;
    std::vector<int> group_of_label;
    for (int g = 0; g < 4; ++g) {
      const Descriptor top = test::random_descriptor(rng);
      for (int s = 0; s < 4; ++s) {
        const Descriptor sub = test::flip_bits(top, 20, rng);
        group_of_label.push_back(g);
        for (int i = 0; i < 60; ++i) {
          data.descriptors.push_back(test::flip_bits(sub, 4, rng));
          data.label.push_back(g * 4 + s);
        }
      }
    }
    VocabularyTrainingConfig cfg;
    cfg.branching = 4;
    cfg.levels = 2;
    cfg.seed = seed;
    const Vocabulary v = Vocabulary::train(as_images(data.descriptors, 40), cfg);
    SCOPED_TRACE("seed " + std::to_string(seed));
    EXPECT_EQ(v.word_count(), 16u);
    expect_bijection(v, data, 16);
    std::map<NodeId, std::set<int>> groups_of_node;
    for (std::size_t i = 0; i < data.descriptors.size(); ++i) {
      NodeId n = 0;
      v.word(data.descriptors[i].data(), 1, n);
      groups_of_node[n].insert(group_of_label[std::size_t(data.label[i])]);
    }
    EXPECT_EQ(groups_of_node.size(), 4u);
    for (auto& [node, groups] : groups_of_node) EXPECT_EQ(groups.size(), 1u) << "level-1 node " << node;
  }
}

TEST(VocabularyTraining, IdenticalDescriptorsStopTheSplitAndFewDescriptorsBecomeWords) {
  std::mt19937_64 rng(5);
  const Descriptor a = test::random_descriptor(rng), b = test::random_descriptor(rng);
  std::vector<Descriptor> ds(50, a);
  ds.push_back(b);
  VocabularyTrainingConfig cfg;
  cfg.branching = 10;
  cfg.levels = 4;
  const Vocabulary v = Vocabulary::train(as_images(ds, 10), cfg);
  EXPECT_EQ(v.word_count(), 2u);  // two distinct descriptors: two leaves right under the root
  EXPECT_EQ(v.node_count(), 3u);
  EXPECT_NE(v.word(a.data()), v.word(b.data()));
}

TEST(VocabularyTraining, SameResultForAnyThreadCount) {
  // Large enough (30000 descriptors) for the root to be split with several threads, too.
  const Labelled data = flat_clusters(300, 100, 30, 9, nullptr);
  const DescriptorSet set = as_images(data.descriptors, 300);
  VocabularyTrainingConfig cfg;
  cfg.branching = 6;
  cfg.levels = 3;
  cfg.seed = 77;
  cfg.threads = 1;
  const std::string one = Vocabulary::train(set, cfg).serialize();
  cfg.threads = 3;
  const std::string three = Vocabulary::train(set, cfg).serialize();
  EXPECT_TRUE(one == three);
  cfg.seed = 78;
  EXPECT_FALSE(Vocabulary::train(set, cfg).serialize() == one);
}

TEST(VocabularyTraining, RejectsBadSettingsAndEmptyInput) {
  VocabularyTrainingConfig cfg;
  cfg.branching = 1;
  EXPECT_THROW(cfg.validate("cli"), InputError);
  try {
    cfg.validate("cli");
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "vocabulary_training.branching");
  }
  cfg = {};
  cfg.levels = 0;
  EXPECT_THROW(cfg.validate("cli"), InputError);
  cfg = {};
  cfg.branching = 64;
  cfg.levels = 6;  // 2^36 words: more than 32-bit ids can number
  try {
    cfg.validate("cli");
    ADD_FAILURE() << "k^L above 4e9 must be rejected";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "vocabulary_training.levels");
  }
  cfg.levels = 5;  // 2^30 words
  EXPECT_NO_THROW(cfg.validate("cli"));
  cfg = {};
  cfg.threads = 0;
  EXPECT_THROW(cfg.validate("cli"), InputError);
  EXPECT_THROW(Vocabulary::train(DescriptorSet{}, VocabularyTrainingConfig{}), std::invalid_argument);
  DescriptorSet set;
  EXPECT_THROW(set.add_image(cv::Mat(3, 64, CV_8UC1)), std::invalid_argument);
  EXPECT_EQ(set.image_count(), 0u);
}

// Cluster c (1..9) appears in images 0..c-1 of 10, cluster 0 in all of them: IDF = log(10 / c), and 0 for cluster 0.
class TfIdf : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(11);
    for (int c = 0; c < 10; ++c) centres.push_back(test::random_descriptor(rng));
    for (int img = 0; img < 10; ++img) {
      std::vector<Descriptor> ds;
      for (int c = 0; c < 10; ++c)
        if (c == 0 || img < c)
          for (int i = 0; i < 20; ++i) ds.push_back(test::flip_bits(centres[std::size_t(c)], 8, rng));
      set.add_image(test::to_mat(ds));
    }
    VocabularyTrainingConfig cfg;
    cfg.levels = 1;
    vocabulary = Vocabulary::train(set, cfg);
    ASSERT_EQ(vocabulary.word_count(), 10u);
  }
  WordId word_of(int c) const { return vocabulary.word(centres[std::size_t(c)].data()); }
  std::vector<Descriptor> centres;
  DescriptorSet set;
  Vocabulary vocabulary;
};

TEST_F(TfIdf, WeightsAreLogOfImagesOverImagesWithTheWord) {
  EXPECT_EQ(vocabulary.training_images(), 10u);
  EXPECT_FLOAT_EQ(vocabulary.word_weight(word_of(0)), 0.f);
  for (int c = 1; c < 10; ++c) EXPECT_NEAR(vocabulary.word_weight(word_of(c)), std::log(10.0 / c), 1e-6) << c;
}

TEST_F(TfIdf, BowVectorIsNormalisedTfIdf) {
  // Two features of cluster 1, one of cluster 5, three of cluster 0 (weight 0: left out).
  std::vector<Descriptor> ds = {centres[1], centres[1], centres[5], centres[0], centres[0], centres[0]};
  BowVector bow;
  vocabulary.transform(test::to_mat(ds), bow);
  ASSERT_EQ(bow.size(), 2u);
  const double w1 = 2 * std::log(10.0), w5 = std::log(2.0);
  std::map<WordId, double> expected = {{word_of(1), w1 / (w1 + w5)}, {word_of(5), w5 / (w1 + w5)}};
  for (const auto& e : bow.entries) EXPECT_NEAR(e.weight, expected.at(e.word), 1e-6);
  EXPECT_LT(bow.entries[0].word, bow.entries[1].word);
}

TEST_F(TfIdf, IdenticalImagesScoreOneDisjointZeroAndPartialOverlapTheSumOfMinima) {
  BowVector a, b, c, d;
  vocabulary.transform(test::to_mat({centres[1], centres[2], centres[3]}), a);
  vocabulary.transform(test::to_mat({centres[3], centres[2], centres[1]}), b);  // same features, other order
  vocabulary.transform(test::to_mat({centres[4], centres[5]}), c);
  vocabulary.transform(test::to_mat({centres[1], centres[4]}), d);
  EXPECT_NEAR(Vocabulary::score(a, a), 1.0, 1e-6);
  EXPECT_NEAR(Vocabulary::score(a, b), 1.0, 1e-6);
  EXPECT_EQ(Vocabulary::score(a, c), 0.0);
  EXPECT_EQ(common_words(a, c), 0u);
  // Shared word: cluster 1. a's weight of it: log10 / (log10 + log5 + log(10/3)); d's: log10 / (log10 + log2.5).
  const double a1 = std::log(10.0) / (std::log(10.0) + std::log(5.0) + std::log(10.0 / 3));
  const double d1 = std::log(10.0) / (std::log(10.0) + std::log(2.5));
  EXPECT_NEAR(Vocabulary::score(a, d), std::min(a1, d1), 1e-6);
  EXPECT_NEAR(Vocabulary::score(d, a), Vocabulary::score(a, d), 1e-12);
  EXPECT_EQ(common_words(a, d), 1u);
  // The L1 definition: 1 - |a - d|_1 / 2.
  std::map<WordId, double> diff;
  for (auto& e : a.entries) diff[e.word] += e.weight;
  for (auto& e : d.entries) diff[e.word] -= e.weight;
  double l1 = 0;
  for (auto& [w, x] : diff) l1 += std::abs(x);
  EXPECT_NEAR(Vocabulary::score(a, d), 1 - l1 / 2, 1e-6);
}

TEST_F(TfIdf, EmptyInputAndBadMatrices) {
  BowVector bow;
  FeatureVector fv;
  vocabulary.transform(cv::Mat(), bow, fv, 1);
  EXPECT_TRUE(bow.empty());
  EXPECT_TRUE(fv.empty());
  EXPECT_EQ(fv.offsets.size(), 1u);
  EXPECT_THROW(vocabulary.transform(cv::Mat(2, 16, CV_8UC1), bow), std::invalid_argument);
  EXPECT_THROW(vocabulary.transform(cv::Mat(2, 32, CV_8UC1), bow, fv, 2), std::invalid_argument);  // L = 1
  EXPECT_EQ(Vocabulary::score(BowVector{}, BowVector{}), 0.0);
}

// Parent of every node, from the breadth-first child ranges.
std::vector<NodeId> parents(const Vocabulary& v) {
  std::vector<NodeId> p(v.node_count(), 0);
  for (NodeId n = 0; n < v.node_count(); ++n)
    for (int c = 0; c < v.child_count(n); ++c) p[v.first_child(n) + NodeId(c)] = n;
  return p;
}

TEST(DirectIndex, EveryFeatureOnceUnderTheAncestorOfItsWordAtTheLevel) {
  const Labelled train = flat_clusters(400, 30, 40, 21, nullptr);
  VocabularyTrainingConfig cfg;
  cfg.branching = 5;
  cfg.levels = 4;
  const Vocabulary v = Vocabulary::train(as_images(train.descriptors, 200), cfg);
  const auto parent = parents(v);
  auto depth = [&](NodeId n) {
    int d = 0;
    for (; n != 0; n = parent[n]) ++d;
    return d;
  };
  std::mt19937_64 rng(3);
  std::vector<Descriptor> img;
  for (int i = 0; i < 500; ++i)
    img.push_back(i % 2 ? test::random_descriptor(rng) : train.descriptors[std::size_t(i) * 7]);
  const cv::Mat m = test::to_mat(img);
  for (int level = 1; level <= 4; ++level) {
    BowVector bow, plain;
    FeatureVector fv;
    v.transform(m, bow, fv, level);
    v.transform(m, plain);
    EXPECT_EQ(fv.level, level);
    ASSERT_EQ(bow.entries.size(), plain.entries.size());
    for (std::size_t i = 0; i < bow.size(); ++i) {
      EXPECT_EQ(bow.entries[i].word, plain.entries[i].word);
      EXPECT_FLOAT_EQ(bow.entries[i].weight, plain.entries[i].weight);
    }
    ASSERT_EQ(fv.offsets.size(), fv.nodes.size() + 1);
    ASSERT_EQ(fv.features.size(), img.size());
    std::vector<int> seen(img.size(), 0);
    for (std::size_t k = 0; k < fv.size(); ++k) {
      if (k > 0) {
        EXPECT_LT(fv.nodes[k - 1], fv.nodes[k]);
      }
      for (const uint32_t* f = fv.features_begin(k); f != fv.features_end(k); ++f) {
        if (f != fv.features_begin(k)) {
          EXPECT_LT(*(f - 1), *f);
        }
        ++seen[*f];
        // The node is the word's ancestor at `level`, or the word itself when it lies higher.
        NodeId node_at_level = 0;
        const NodeId leaf = v.word_node(v.word(img[*f].data(), level, node_at_level));
        EXPECT_EQ(node_at_level, fv.nodes[k]);
        NodeId n = leaf;
        while (depth(n) > level) n = parent[n];
        EXPECT_EQ(n, fv.nodes[k]);
      }
    }
    for (int s : seen) EXPECT_EQ(s, 1);
  }
}

TEST(DirectIndex, CommonNodesPairFeaturesOfTheSameNode) {
  const Labelled train = flat_clusters(50, 40, 20, 8, nullptr);
  VocabularyTrainingConfig cfg;
  cfg.branching = 4;
  cfg.levels = 3;
  const Vocabulary v = Vocabulary::train(as_images(train.descriptors, 100), cfg);
  std::vector<Descriptor> a(train.descriptors.begin(), train.descriptors.begin() + 120);
  std::vector<Descriptor> b(train.descriptors.begin() + 60, train.descriptors.begin() + 200);
  BowVector ba, bb;
  FeatureVector fa, fb;
  v.transform(test::to_mat(a), ba, fa, 2);
  v.transform(test::to_mat(b), bb, fb, 2);
  int nodes = 0, pairs_same_descriptor = 0;
  for_each_common_node(
      fa, fb, [&](NodeId node, const uint32_t* a0, const uint32_t* a1, const uint32_t* b0, const uint32_t* b1) {
        ++nodes;
        for (const uint32_t* i = a0; i != a1; ++i) {
          NodeId n = 0;
          v.word(a[*i].data(), 2, n);
          EXPECT_EQ(n, node);
          for (const uint32_t* j = b0; j != b1; ++j) pairs_same_descriptor += a[*i] == b[*j];
        }
        for (const uint32_t* j = b0; j != b1; ++j) {
          NodeId n = 0;
          v.word(b[*j].data(), 2, n);
          EXPECT_EQ(n, node);
        }
      });
  EXPECT_GT(nodes, 0);
  EXPECT_EQ(pairs_same_descriptor, 60);  // the 60 shared descriptors always meet under their node
}

}  // namespace
}  // namespace agvslam::place
