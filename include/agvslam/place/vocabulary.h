#pragma once
// Bag-of-binary-words vocabulary tree (DBoW2 / Galvez-Lopez & Tardos 2012) for 256-bit ORB descriptors.
//
// Training: hierarchical k-medians with branching k and depth L. At every node the descriptors that reached it
// are clustered into (at most) k groups: k-means++ seeding under the Hamming distance, then assignment to the
// nearest centre and majority-bit medians until the assignment no longer changes (or max_iterations); each group
// becomes a child, and is split again until depth L. A node that ends with one descriptor (or identical ones)
// stops early. The leaves are the words, numbered in breadth-first order. Word weights are IDF,
// log(N / N_w) over the N training images (N_w: images with at least one descriptor of word w); a BoW vector is
// the sum of its features' word weights (TF-IDF up to the L1 normalisation, which removes the TF factor).
// Training is deterministic for a seed, whatever the thread count.
//
// Use: transform(descriptors) -> BowVector (scored with l1_score) and FeatureVector (direct index at a level).
// A Vocabulary is immutable once trained or loaded: const methods may be called from any number of threads.
//
// File (save/load, little-endian, every section 64-byte aligned so the file can also be memory-mapped):
//   header (128 bytes): magic "AGVSBOW\0", format version, descriptor type and size, k, L, weighting (TF-IDF),
//   scoring (L1), node and word counts, training image and descriptor counts, description size, file size, the
//   identity and a checksum; then, each at the next multiple of 64 bytes (offsets follow from the counts): node
//   descriptors (node_count x 32 bytes, breadth-first), each node's first child (u32) and child count (u8), each
//   word's node (u32) and weight (f32), and a UTF-8 description of the training data.
//   checksum: FNV-1a 64 over every byte of the file except the checksum field (any changed byte is detected).
//   identity: FNV-1a 64 over the fields that decide which word a descriptor maps to and its weight (type, k, L,
//   weighting, the tree, the weights), not the description: saved maps record it, and a map built with another
//   vocabulary is refused.

#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/place/bow_vector.h"

namespace agvslam::place {

inline constexpr int kDescriptorBytes = 32;  // 256-bit ORB (rBRIEF), CV_8UC1 rows of 32 bytes

// Training descriptors, contiguous and grouped by image (the IDF counts images).
class DescriptorSet {
 public:
  // Appends the rows of an N x 32 CV_8UC1 matrix as one image (N may be 0). Throws std::invalid_argument for
  // another type or width.
  void add_image(const cv::Mat& descriptors);
  void reserve(std::size_t descriptors, std::size_t images);
  void clear();

  std::size_t size() const { return bytes_.size() / kDescriptorBytes; }
  std::size_t image_count() const { return image_begin_.size(); }
  const uint8_t* descriptor(std::size_t i) const { return bytes_.data() + i * kDescriptorBytes; }
  // Descriptors of image i: [image_begin(i), image_end(i)).
  std::size_t image_begin(std::size_t i) const { return image_begin_[i]; }
  std::size_t image_end(std::size_t i) const { return i + 1 < image_begin_.size() ? image_begin_[i + 1] : size(); }

 private:
  std::vector<uint8_t> bytes_;
  std::vector<std::size_t> image_begin_;
};

struct VocabularyTrainingConfig {
  int branching = 10;       // k: children per node (DBoW2 / ORB-SLAM2: 10)
  int levels = 5;           // L: depth of the tree; at most k^L words
  int max_iterations = 20;  // k-medians iterations per node (it stops earlier once the assignment is stable)
  uint64_t seed = 1;        // k-means++ seeding (per node, derived from this and the node)
  int threads = 1;          // the result does not depend on it

  // InputError(source, "vocabulary_training.<field>", expected) for an out-of-range value (k in 2..64, L in 1..8,
  // k^L <= 4e9 ...); the table in vocabulary.cpp.
  void validate(const std::string& source) const;
  std::string describe() const;
};

// Progress of training: a human-readable line per stage (for stderr).
using TrainingProgress = std::function<void(const std::string&)>;

enum class DescriptorType : uint32_t { kOrb256 = 1 };

class Vocabulary {
 public:
  Vocabulary() = default;  // empty: no words; transform() yields empty vectors

  // Trains on `set` (needs at least one descriptor). description: free text stored in the file (what it was
  // trained on). Throws std::invalid_argument for an invalid config or an empty set.
  static Vocabulary train(const DescriptorSet& set, const VocabularyTrainingConfig& config,
                          const std::string& description = "", const TrainingProgress& progress = {});

  // Throws InputError(path, what, expected) for a missing, truncated, corrupt, foreign or unsupported file.
  static Vocabulary load(const std::string& path);
  // Writes atomically (temporary file, fsync, rename). Throws InputError(path, ...) when it cannot be written.
  void save(const std::string& path) const;
  // The file's bytes (what save() writes).
  std::string serialize() const;
  // Parses the bytes of a file; `source` names it in errors.
  static Vocabulary deserialize(const void* data, std::size_t size, const std::string& source);

  bool empty() const { return word_count() == 0; }
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  DescriptorType descriptor_type() const { return DescriptorType::kOrb256; }
  std::size_t node_count() const { return child_count_.size(); }
  std::size_t word_count() const { return word_node_.size(); }
  uint64_t training_images() const { return training_images_; }
  uint64_t training_descriptors() const { return training_descriptors_; }
  const std::string& description() const { return description_; }
  // Hash of the content that decides words and weights (see the file layout above); 0 when empty.
  uint64_t identity() const { return identity_; }
  std::string identity_hex() const;  // 16 lower-case hex digits
  // One line: k, L, words, nodes, identity, training counts.
  std::string describe() const;

  // The word of one descriptor (32 bytes), and the node on its path at depth `level` (1..L; the word's own node
  // when the word lies above that level). Requires a non-empty vocabulary.
  WordId word(const uint8_t* descriptor) const;
  WordId word(const uint8_t* descriptor, int level, NodeId& node_at_level) const;
  float word_weight(WordId w) const { return word_weight_[w]; }
  NodeId word_node(WordId w) const { return word_node_[w]; }
  // Tree access (tests, tools): a node's descriptor, children [first_child, first_child + child_count), depth.
  const uint8_t* node_descriptor(NodeId n) const {
    return node_descriptors_.data() + std::size_t(n) * kDescriptorBytes;
  }
  NodeId first_child(NodeId n) const { return first_child_[n]; }
  int child_count(NodeId n) const { return child_count_[n]; }
  bool is_leaf(NodeId n) const { return child_count_[n] == 0; }
  // Word of a leaf node (undefined for inner nodes).
  WordId node_word(NodeId n) const { return node_word_[n]; }

  // BoW vector (L1-normalised TF-IDF) of an N x 32 CV_8UC1 descriptor matrix; words of weight 0 (seen in every
  // training image) are left out. Reuses `bow`'s storage. Throws std::invalid_argument for another type/width.
  void transform(const cv::Mat& descriptors, BowVector& bow) const;
  // The same, plus the direct index at depth `direct_index_level` (1..L). Reuses the outputs' storage.
  void transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features, int direct_index_level) const;
  // l1_score(a, b).
  static double score(const BowVector& a, const BowVector& b) { return l1_score(a, b); }

 private:
  friend class VocabularyBuilder;
  void finish_tree();  // derives node_word_, depth_, identity_ from the stored arrays
  // Leaf reached by a descriptor; *node_at_level (if given) receives the node at depth `level` on the path.
  NodeId descend(const uint8_t* descriptor, int level, NodeId* node_at_level) const;

  int branching_ = 0;
  int levels_ = 0;
  uint64_t training_images_ = 0;
  uint64_t training_descriptors_ = 0;
  std::string description_;
  uint64_t identity_ = 0;
  std::vector<uint8_t> node_descriptors_;  // node_count x 32 bytes (the root's is all zero, never used)
  std::vector<uint32_t> first_child_;      // 0 for a leaf
  std::vector<uint8_t> child_count_;       // 0 for a leaf
  std::vector<uint32_t> word_node_;        // word -> its leaf node
  std::vector<float> word_weight_;         // word -> IDF weight
  std::vector<uint32_t> node_word_;        // leaf node -> word (derived)
  std::vector<uint8_t> node_depth_;        // node -> depth (derived)
};

}  // namespace agvslam::place
