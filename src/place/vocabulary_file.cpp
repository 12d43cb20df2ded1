// The vocabulary file (layout in vocabulary.h): serialize / deserialize / save / load.
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "agvslam/core/error.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/place/vocabulary.h"
#include "hash.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the vocabulary file is little-endian");

namespace agvslam::place {
namespace {

constexpr char kMagic[8] = {'A', 'G', 'V', 'S', 'B', 'O', 'W', '\0'};
constexpr uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 128;
constexpr std::size_t kChecksumOffset = 96;
constexpr uint64_t kMaxDescriptionBytes = 1 << 20;
constexpr uint64_t kMaxNodes = uint64_t(1) << 31;

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;
  uint32_t descriptor_type;
  uint32_t descriptor_bytes;
  uint32_t branching;
  uint32_t levels;
  uint32_t weighting;  // 1: TF-IDF
  uint32_t scoring;    // 1: L1
  uint64_t node_count;
  uint64_t word_count;
  uint64_t training_images;
  uint64_t training_descriptors;
  uint64_t description_bytes;
  uint64_t file_bytes;
  uint64_t identity;
  uint64_t checksum;
  uint8_t reserved[24];
};
static_assert(sizeof(Header) == kHeaderBytes, "header layout");
static_assert(offsetof(Header, checksum) == kChecksumOffset, "header layout");

uint64_t align64(uint64_t x) { return (x + 63) & ~uint64_t(63); }

struct Layout {
  uint64_t descriptors, first_child, child_count, word_node, word_weight, description, file_bytes;
};

Layout layout_of(uint64_t nodes, uint64_t words, uint64_t description_bytes) {
  Layout l{};
  l.descriptors = kHeaderBytes;
  l.first_child = align64(l.descriptors + nodes * kDescriptorBytes);
  l.child_count = align64(l.first_child + nodes * 4);
  l.word_node = align64(l.child_count + nodes);
  l.word_weight = align64(l.word_node + words * 4);
  l.description = align64(l.word_weight + words * 4);
  l.file_bytes = l.description + description_bytes;
  return l;
}

uint64_t file_checksum(const uint8_t* bytes, std::size_t size) {
  detail::Fnv1a64 h;
  h.update(bytes, kChecksumOffset);
  h.update(bytes + kChecksumOffset + 8, size - kChecksumOffset - 8);
  return h.value();
}

std::string hex(uint64_t v) {
  char buf[19];
  std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(v));
  return buf;
}

}  // namespace

std::string Vocabulary::serialize() const {
  if (empty()) throw std::logic_error("Vocabulary::serialize: the vocabulary is empty (train or load one first)");
  const Layout l = layout_of(node_count(), word_count(), description_.size());
  std::string out(l.file_bytes, '\0');
  auto* bytes = reinterpret_cast<uint8_t*>(out.data());
  Header h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.header_bytes = kHeaderBytes;
  h.descriptor_type = static_cast<uint32_t>(DescriptorType::kOrb256);
  h.descriptor_bytes = kDescriptorBytes;
  h.branching = static_cast<uint32_t>(branching_);
  h.levels = static_cast<uint32_t>(levels_);
  h.weighting = 1;
  h.scoring = 1;
  h.node_count = node_count();
  h.word_count = word_count();
  h.training_images = training_images_;
  h.training_descriptors = training_descriptors_;
  h.description_bytes = description_.size();
  h.file_bytes = l.file_bytes;
  h.identity = identity_;
  std::memcpy(bytes, &h, sizeof h);
  std::memcpy(bytes + l.descriptors, node_descriptors_.data(), node_descriptors_.size());
  std::memcpy(bytes + l.first_child, first_child_.data(), first_child_.size() * 4);
  std::memcpy(bytes + l.child_count, child_count_.data(), child_count_.size());
  std::memcpy(bytes + l.word_node, word_node_.data(), word_node_.size() * 4);
  std::memcpy(bytes + l.word_weight, word_weight_.data(), word_weight_.size() * 4);
  std::memcpy(bytes + l.description, description_.data(), description_.size());
  const uint64_t checksum = file_checksum(bytes, out.size());
  std::memcpy(bytes + kChecksumOffset, &checksum, 8);
  return out;
}

Vocabulary Vocabulary::deserialize(const void* data, std::size_t size, const std::string& source) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  const std::string what_it_is = " (an agvslam vocabulary file written by agvslam-vocab)";
  if (size >= sizeof kMagic && std::memcmp(bytes, kMagic, sizeof kMagic) != 0)
    throw InputError(source, "magic",
                     "expected \"AGVSBOW\" at the start" + what_it_is +
                         "; DBoW2/ORB-SLAM2 text or YAML vocabularies are not read: train one with agvslam-vocab");
  if (size < kHeaderBytes)
    throw InputError(source, "header",
                     "expected at least " + std::to_string(kHeaderBytes) + " bytes" + what_it_is + ", found " +
                         std::to_string(size) + " (truncated)");
  Header h;
  std::memcpy(&h, bytes, sizeof h);
  if (h.version != kVersion)
    throw InputError(source, "version",
                     "expected format version " + std::to_string(kVersion) + ", found " + std::to_string(h.version));
  if (h.header_bytes != kHeaderBytes)
    throw InputError(source, "header_bytes",
                     "expected " + std::to_string(kHeaderBytes) + ", found " + std::to_string(h.header_bytes));
  if (h.descriptor_type != static_cast<uint32_t>(DescriptorType::kOrb256) || h.descriptor_bytes != kDescriptorBytes)
    throw InputError(source, "descriptor_type",
                     "expected type 1 (256-bit ORB, 32 bytes), found type " + std::to_string(h.descriptor_type) +
                         " of " + std::to_string(h.descriptor_bytes) + " bytes");
  if (h.weighting != 1 || h.scoring != 1)
    throw InputError(source, "weighting",
                     "expected TF-IDF weighting (1) and L1 scoring (1), found " + std::to_string(h.weighting) +
                         " and " + std::to_string(h.scoring));
  if (h.branching < 2 || h.branching > 255 || h.levels < 1 || h.levels > 8)
    throw InputError(source, "branching",
                     "expected k in 2..255 and L in 1..8, found k=" + std::to_string(h.branching) +
                         " L=" + std::to_string(h.levels));
  if (h.node_count < 1 || h.node_count > kMaxNodes || h.word_count > h.node_count ||
      h.description_bytes > kMaxDescriptionBytes)
    throw InputError(source, "node_count",
                     "expected 1..2^31 nodes, at most as many words, a description under 1 MiB; found " +
                         std::to_string(h.node_count) + " nodes, " + std::to_string(h.word_count) + " words, " +
                         std::to_string(h.description_bytes) + " description bytes");
  const Layout l = layout_of(h.node_count, h.word_count, h.description_bytes);
  if (h.file_bytes != l.file_bytes)
    throw InputError(source, "file_bytes",
                     "expected " + std::to_string(l.file_bytes) + " bytes for the recorded counts, header says " +
                         std::to_string(h.file_bytes));
  if (size != l.file_bytes)
    throw InputError(source, "size",
                     "expected " + std::to_string(l.file_bytes) + " bytes as recorded in the header, found " +
                         std::to_string(size) + (size < l.file_bytes ? " (truncated)" : " (trailing bytes)"));
  const uint64_t checksum = file_checksum(bytes, size);
  if (checksum != h.checksum)
    throw InputError(source, "checksum",
                     "expected " + hex(h.checksum) + ", computed " + hex(checksum) + " (the file is corrupt)");

  Vocabulary v;
  v.branching_ = int(h.branching);
  v.levels_ = int(h.levels);
  v.training_images_ = h.training_images;
  v.training_descriptors_ = h.training_descriptors;
  const auto nodes = std::size_t(h.node_count), words = std::size_t(h.word_count);
  v.node_descriptors_.assign(bytes + l.descriptors, bytes + l.descriptors + nodes * kDescriptorBytes);
  v.first_child_.resize(nodes);
  std::memcpy(v.first_child_.data(), bytes + l.first_child, nodes * 4);
  v.child_count_.assign(bytes + l.child_count, bytes + l.child_count + nodes);
  v.word_node_.resize(words);
  std::memcpy(v.word_node_.data(), bytes + l.word_node, words * 4);
  v.word_weight_.resize(words);
  std::memcpy(v.word_weight_.data(), bytes + l.word_weight, words * 4);
  v.description_.assign(reinterpret_cast<const char*>(bytes + l.description), std::size_t(h.description_bytes));

  // The tree must be breadth-first with consecutive children, at most k per node, depth <= L, and the words
  // exactly its leaves in node order (what the training writes; checked so that no file can make a lookup
  // leave the arrays).
  uint64_t expected_child = 1, leaves = 0;
  std::vector<uint8_t> depth(nodes, 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    const unsigned c = v.child_count_[i];
    if (c == 0) {
      if (leaves >= words || v.word_node_[leaves] != i)
        throw InputError(source, "nodes[" + std::to_string(i) + "]",
                         "expected leaf " + std::to_string(i) + " to be word " + std::to_string(leaves));
      ++leaves;
      continue;
    }
    if (c > h.branching || v.first_child_[i] != expected_child || expected_child <= i || expected_child + c > nodes ||
        depth[i] + 1u > h.levels)
      throw InputError(source, "nodes[" + std::to_string(i) + "]",
                       "expected up to k consecutive children in breadth-first order within " + std::to_string(nodes) +
                           " nodes and depth <= L");
    for (unsigned j = 0; j < c; ++j) depth[expected_child + j] = static_cast<uint8_t>(depth[i] + 1);
    expected_child += c;
  }
  if (expected_child != nodes || leaves != words)
    throw InputError(source, "nodes", "expected every node but the root to be a child and every leaf a word");
  for (std::size_t w = 0; w < words; ++w)
    if (!std::isfinite(v.word_weight_[w]) || v.word_weight_[w] < 0)
      throw InputError(source, "weights[" + std::to_string(w) + "]", "expected a finite weight >= 0");
  v.finish_tree();
  if (v.identity_ != h.identity)
    throw InputError(source, "identity",
                     "expected " + hex(h.identity) + ", computed " + hex(v.identity_) + " (the file is corrupt)");
  return v;
}

void Vocabulary::save(const std::string& path) const { io::write_file_atomically(path, serialize()); }

Vocabulary Vocabulary::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(path, "", "cannot open: expected a readable vocabulary file (agvslam-vocab --out)");
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(path, "", "cannot read its size: expected a regular vocabulary file");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.seekg(0);
  if (!in.read(bytes.data(), size))
    throw InputError(path, "", "read failed: expected " + std::to_string(size) + " bytes");
  return deserialize(bytes.data(), bytes.size(), path);
}

}  // namespace agvslam::place
