#include "agvslam/place/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "agvslam/core/param_table.h"
#include "hamming.h"
#include "hash.h"

namespace agvslam::place {

// ---- DescriptorSet ------------------------------------------------------------------------------------------

void DescriptorSet::add_image(const cv::Mat& descriptors) {
  image_begin_.push_back(size());
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != kDescriptorBytes) {
    image_begin_.pop_back();
    throw std::invalid_argument("DescriptorSet::add_image: expected N x 32 CV_8UC1 descriptors");
  }
  for (int r = 0; r < descriptors.rows; ++r) {
    const uint8_t* row = descriptors.ptr<uint8_t>(r);
    bytes_.insert(bytes_.end(), row, row + kDescriptorBytes);
  }
}

void DescriptorSet::reserve(std::size_t descriptors, std::size_t images) {
  bytes_.reserve(descriptors * kDescriptorBytes);
  image_begin_.reserve(images);
}

void DescriptorSet::clear() {
  bytes_.clear();
  image_begin_.clear();
}

// ---- VocabularyTrainingConfig -----------------------------------------------------------------------------

namespace {

const params::Table<VocabularyTrainingConfig>& training_params() {
  using params::Range;
  static const params::Table<VocabularyTrainingConfig> table =
      params::Table<VocabularyTrainingConfig>(
          "vocabulary_training",
          {
              {"branching", &VocabularyTrainingConfig::branching, Range::closed(2, 64), "children per node"},
              {"levels", &VocabularyTrainingConfig::levels, Range::closed(1, 8), "", "the file format's limit"},
              {"max_iterations", &VocabularyTrainingConfig::max_iterations, Range::closed(1, 1000), "per node"},
              {"seed", &VocabularyTrainingConfig::seed},
              {"threads", &VocabularyTrainingConfig::threads, Range::closed(1, 256)},
          })
          .check(
              "levels",
              [](const VocabularyTrainingConfig& c) {
                return std::pow(double(c.branching), double(c.levels)) <= 4.0e9;
              },
              "branching^levels <= 4e9 words (word ids are 32-bit)")
          .summary([](const VocabularyTrainingConfig&) {
            return std::string("hierarchical k-medians, k-means++ seeding, Hamming, TF-IDF");
          });
  return table;
}

}  // namespace

void VocabularyTrainingConfig::validate(const std::string& source) const { training_params().validate(source, *this); }

std::string VocabularyTrainingConfig::describe() const { return training_params().describe(*this); }

// ---- Vocabulary ---------------------------------------------------------------------------------------------

std::string Vocabulary::identity_hex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(identity_));
  return buf;
}

std::string Vocabulary::describe() const {
  return "vocabulary: k=" + std::to_string(branching_) + " L=" + std::to_string(levels_) +
         " words=" + std::to_string(word_count()) + " nodes=" + std::to_string(node_count()) +
         " identity=" + identity_hex() + " trained on " + std::to_string(training_descriptors_) +
         " ORB descriptors of " + std::to_string(training_images_) + " images";
}

void Vocabulary::finish_tree() {
  const std::size_t n = child_count_.size();
  node_word_.assign(n, UINT32_MAX);
  for (std::size_t w = 0; w < word_node_.size(); ++w) node_word_[word_node_[w]] = static_cast<uint32_t>(w);
  node_depth_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < child_count_[i]; ++c)
      node_depth_[first_child_[i] + c] = static_cast<uint8_t>(node_depth_[i] + 1);

  detail::Fnv1a64 h;
  h.update_value(static_cast<uint32_t>(DescriptorType::kOrb256));
  h.update_value(static_cast<uint32_t>(kDescriptorBytes));
  h.update_value(static_cast<uint32_t>(branching_));
  h.update_value(static_cast<uint32_t>(levels_));
  h.update_value(static_cast<uint32_t>(1));  // weighting: TF-IDF
  h.update_value(static_cast<uint32_t>(1));  // scoring: L1
  h.update_value(static_cast<uint64_t>(n));
  h.update_value(static_cast<uint64_t>(word_node_.size()));
  h.update(node_descriptors_.data(), node_descriptors_.size());
  h.update(first_child_.data(), first_child_.size() * sizeof(uint32_t));
  h.update(child_count_.data(), child_count_.size());
  h.update(word_node_.data(), word_node_.size() * sizeof(uint32_t));
  h.update(word_weight_.data(), word_weight_.size() * sizeof(float));
  identity_ = word_node_.empty() ? 0 : h.value();
}

NodeId Vocabulary::descend(const uint8_t* descriptor, int level, NodeId* node_at_level) const {
  const auto nearest = detail::hamming_kernels().nearest;
  NodeId node = 0;
  int depth = 0;
  while (child_count_[node] != 0) {
    const NodeId first = first_child_[node];
    node =
        first + static_cast<NodeId>(nearest(
                    descriptor, node_descriptors_.data() + std::size_t(first) * kDescriptorBytes, child_count_[node]));
    if (++depth == level && node_at_level) *node_at_level = node;
  }
  if (node_at_level && depth < level) *node_at_level = node;
  return node;
}

WordId Vocabulary::word(const uint8_t* descriptor) const { return node_word_[descend(descriptor, 0, nullptr)]; }

WordId Vocabulary::word(const uint8_t* descriptor, int level, NodeId& node_at_level) const {
  return node_word_[descend(descriptor, level, &node_at_level)];
}

namespace {

void check_descriptors(const cv::Mat& descriptors) {
  if (!descriptors.empty() && (descriptors.type() != CV_8UC1 || descriptors.cols != kDescriptorBytes))
    throw std::invalid_argument("Vocabulary::transform: expected N x 32 CV_8UC1 descriptors");
}

// Sorts by word, merges repeated words, L1-normalises.
void finish_bow(BowVector& bow) {
  auto& e = bow.entries;
  std::sort(e.begin(), e.end(), [](const WordWeight& a, const WordWeight& b) { return a.word < b.word; });
  std::size_t out = 0;
  double total = 0;
  for (std::size_t i = 0; i < e.size();) {
    const WordId w = e[i].word;
    double sum = 0;
    for (; i < e.size() && e[i].word == w; ++i) sum += e[i].weight;
    e[out++] = {w, static_cast<float>(sum)};
    total += sum;
  }
  e.resize(out);
  if (total > 0)
    for (auto& x : e) x.weight = static_cast<float>(x.weight / total);
}

}  // namespace

void Vocabulary::transform(const cv::Mat& descriptors, BowVector& bow) const {
  check_descriptors(descriptors);
  bow.entries.clear();
  if (empty() || descriptors.empty()) return;
  bow.entries.reserve(std::size_t(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) {
    const WordId w = node_word_[descend(descriptors.ptr<uint8_t>(i), 0, nullptr)];
    if (word_weight_[w] > 0) bow.entries.push_back({w, word_weight_[w]});
  }
  finish_bow(bow);
}

void Vocabulary::transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features,
                           int direct_index_level) const {
  check_descriptors(descriptors);
  if (direct_index_level < 1 || direct_index_level > std::max(1, levels_))
    throw std::invalid_argument("Vocabulary::transform: direct_index_level must be in 1..L");
  bow.entries.clear();
  features.clear();
  features.level = direct_index_level;
  if (empty() || descriptors.empty()) {
    features.offsets.push_back(0);
    return;
  }
  // (node << 32 | feature index), sorted: features grouped by node, ascending within a node.
  thread_local std::vector<uint64_t> keys;
  keys.clear();
  keys.reserve(std::size_t(descriptors.rows));
  bow.entries.reserve(std::size_t(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) {
    NodeId node = 0;
    const WordId w = node_word_[descend(descriptors.ptr<uint8_t>(i), direct_index_level, &node)];
    if (word_weight_[w] > 0) bow.entries.push_back({w, word_weight_[w]});
    keys.push_back((uint64_t(node) << 32) | uint32_t(i));
  }
  finish_bow(bow);
  std::sort(keys.begin(), keys.end());
  features.features.reserve(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const auto node = static_cast<NodeId>(keys[i] >> 32);
    if (features.nodes.empty() || features.nodes.back() != node) {
      features.nodes.push_back(node);
      features.offsets.push_back(static_cast<uint32_t>(i));
    }
    features.features.push_back(static_cast<uint32_t>(keys[i] & 0xffffffffu));
  }
  features.offsets.push_back(static_cast<uint32_t>(keys.size()));
}

}  // namespace agvslam::place
