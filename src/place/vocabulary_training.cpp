// Hierarchical k-medians training of the vocabulary tree (see vocabulary.h).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>

#include "agvslam/core/parallel_for.h"
#include "agvslam/place/vocabulary.h"
#include "hamming.h"

namespace agvslam::place {
namespace {

uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Deterministic random numbers (the standard distributions differ between library versions).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() { return splitmix64(state_); }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)

 private:
  uint64_t state_;
};

// Runs f(begin, end, worker) over [0, n) in about `threads` contiguous blocks (worker < threads); per-worker
// partial results must be sums, since a worker may take more than one block.
template <class F>
void for_blocks(int threads, std::size_t n, F&& f) {
  const std::size_t workers = static_cast<std::size_t>(std::max(threads, 1));
  parallel_for(threads, n, (n + workers - 1) / workers, f);
}

// Runs f(i, worker) for i in [0, n), handing out indices one by one.
template <class F>
void for_each_index(int threads, std::size_t n, F&& f) {
  parallel_for(threads, n, 1, [&](std::size_t begin, std::size_t end, int worker) {
    for (std::size_t i = begin; i < end; ++i) f(i, worker);
  });
}

// spread[b]: byte j is bit j of b, so adding spread[d[j]] counts 8 bits of a descriptor byte at once.
struct SpreadTable {
  uint64_t v[256];
  SpreadTable() {
    for (int b = 0; b < 256; ++b) {
      uint64_t x = 0;
      for (int j = 0; j < 8; ++j) x |= uint64_t((b >> j) & 1) << (8 * j);
      v[b] = x;
    }
  }
};
const SpreadTable& spread() {
  static const SpreadTable table;
  return table;
}

// Per-bit counts of a set of descriptors -> majority-bit median.
class BitCounter {
 public:
  void add(const uint8_t* d, const SpreadTable& s) {
    for (int j = 0; j < kDescriptorBytes; ++j) acc_[j] += s.v[d[j]];
    ++n_;
    if (++pending_ == 255) flush();  // byte lanes hold at most 255
  }
  void merge(BitCounter& other) {
    other.flush();
    flush();
    for (int i = 0; i < 256; ++i) counts_[i] += other.counts_[i];
    n_ += other.n_;
  }
  uint32_t count() const { return n_; }
  // Bit set where more than half of the descriptors have it.
  void median(uint8_t* out) {
    flush();
    for (int j = 0; j < kDescriptorBytes; ++j) {
      unsigned byte = 0;
      for (int b = 0; b < 8; ++b)
        if (2 * uint64_t(counts_[8 * j + b]) > n_) byte |= 1u << b;
      out[j] = static_cast<uint8_t>(byte);
    }
  }

 private:
  void flush() {
    if (pending_ == 0) return;
    for (int j = 0; j < kDescriptorBytes; ++j) {
      for (int b = 0; b < 8; ++b) counts_[8 * j + b] += uint32_t((acc_[j] >> (8 * b)) & 0xff);
      acc_[j] = 0;
    }
    pending_ = 0;
  }
  uint64_t acc_[kDescriptorBytes] = {};
  uint32_t counts_[256] = {};
  uint32_t n_ = 0;
  uint32_t pending_ = 0;
};

struct Cluster {
  std::array<uint8_t, kDescriptorBytes> centre{};
  std::vector<uint32_t> members;
};

// Clusters the descriptors `members` of a node into at most k groups (see vocabulary.h).
std::vector<Cluster> cluster_node(const uint8_t* data, const std::vector<uint32_t>& members, int k, int max_iterations,
                                  uint64_t seed, int threads) {
  const auto& kernels = detail::hamming_kernels();
  const std::size_t n = members.size();
  std::vector<Cluster> clusters;
  if (n <= std::size_t(k)) {  // every distinct descriptor is its own cluster
    for (uint32_t m : members) {
      const uint8_t* d = data + std::size_t(m) * kDescriptorBytes;
      auto it = std::find_if(clusters.begin(), clusters.end(),
                             [&](const Cluster& c) { return std::memcmp(c.centre.data(), d, kDescriptorBytes) == 0; });
      if (it == clusters.end()) {
        clusters.emplace_back();
        std::memcpy(clusters.back().centre.data(), d, kDescriptorBytes);
        it = clusters.end() - 1;
      }
      it->members.push_back(m);
    }
    return clusters;
  }
  if (n < 20000) threads = 1;

  // k-means++ seeding: the next centre is drawn with probability proportional to the squared distance to the
  // nearest centre chosen so far.
  Rng rng(seed);
  std::vector<uint8_t> centres;
  centres.reserve(std::size_t(k) * kDescriptorBytes);
  auto add_centre = [&](uint32_t member) {
    const uint8_t* d = data + std::size_t(member) * kDescriptorBytes;
    centres.insert(centres.end(), d, d + kDescriptorBytes);
  };
  std::vector<uint32_t> min_dist(n, UINT32_MAX);
  add_centre(members[rng.next() % n]);
  for (int c = 1;; ++c) {
    const uint8_t* centre = centres.data() + std::size_t(c - 1) * kDescriptorBytes;
    for_blocks(threads, n, [&](std::size_t b, std::size_t e, int) {
      kernels.update_min_distance(data, members.data() + b, e - b, centre, min_dist.data() + b);
    });
    if (c == k) break;
    double total = 0;
    for (uint32_t d : min_dist) total += double(d) * d;
    if (total <= 0) break;  // every descriptor equals a centre: fewer distinct descriptors than k
    const double r = rng.uniform() * total;
    double acc = 0;
    std::size_t pick = n;
    for (std::size_t i = 0; i < n; ++i) {
      acc += double(min_dist[i]) * min_dist[i];
      if (acc > r && min_dist[i] > 0) {
        pick = i;
        break;
      }
    }
    if (pick == n)  // rounding at the very end of the sum: the last descriptor with a distance
      for (std::size_t i = n; i-- > 0;)
        if (min_dist[i] > 0) {
          pick = i;
          break;
        }
    add_centre(members[pick]);
  }
  const int kc = int(centres.size() / kDescriptorBytes);
  if (kc == 1) {
    clusters.emplace_back();
    std::memcpy(clusters[0].centre.data(), centres.data(), kDescriptorBytes);
    clusters[0].members = members;
    return clusters;
  }

  // Assignment to the nearest centre / majority-bit medians until the assignment is stable.
  std::vector<uint8_t> assignment(n), previous(n, 0xff);
  const int n_threads = threads;
  std::vector<std::vector<BitCounter>> counters(std::size_t(std::max(n_threads, 1)));
  const SpreadTable& s = spread();
  for (int iteration = 0;; ++iteration) {
    for_blocks(threads, n, [&](std::size_t b, std::size_t e, int) {
      kernels.assign(data, members.data() + b, e - b, centres.data(), kc, assignment.data() + b);
    });
    if (assignment == previous || iteration == max_iterations) break;
    for (auto& c : counters) c.assign(std::size_t(kc), BitCounter{});
    for_blocks(threads, n, [&](std::size_t b, std::size_t e, int t) {
      auto& mine = counters[std::size_t(t)];
      for (std::size_t i = b; i < e; ++i) mine[assignment[i]].add(data + std::size_t(members[i]) * kDescriptorBytes, s);
    });
    for (int c = 0; c < kc; ++c) {
      BitCounter& total = counters[0][std::size_t(c)];
      for (std::size_t t = 1; t < counters.size(); ++t) total.merge(counters[t][std::size_t(c)]);
      if (total.count() > 0) total.median(centres.data() + std::size_t(c) * kDescriptorBytes);  // empty: keep
    }
    previous.swap(assignment);
  }

  std::vector<uint32_t> sizes(std::size_t(kc), 0);
  for (uint8_t a : assignment) ++sizes[a];
  std::vector<int> index_of(std::size_t(kc), -1);
  for (int c = 0; c < kc; ++c) {
    if (sizes[std::size_t(c)] == 0) continue;  // an empty cluster is dropped
    index_of[std::size_t(c)] = int(clusters.size());
    clusters.emplace_back();
    std::memcpy(clusters.back().centre.data(), centres.data() + std::size_t(c) * kDescriptorBytes, kDescriptorBytes);
    clusters.back().members.reserve(sizes[std::size_t(c)]);
  }
  for (std::size_t i = 0; i < n; ++i) clusters[std::size_t(index_of[assignment[i]])].members.push_back(members[i]);
  return clusters;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace

class VocabularyBuilder {
 public:
  static Vocabulary build(const DescriptorSet& set, const VocabularyTrainingConfig& config,
                          const std::string& description, const TrainingProgress& progress);
};

Vocabulary VocabularyBuilder::build(const DescriptorSet& set, const VocabularyTrainingConfig& config,
                                    const std::string& description, const TrainingProgress& progress) {
  auto say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  const uint8_t* data = set.descriptor(0);
  const int k = config.branching;

  struct TreeNode {
    std::array<uint8_t, kDescriptorBytes> descriptor{};
    uint32_t first_child = 0;
    uint8_t child_count = 0;
  };
  struct Pending {
    uint32_t node;
    std::vector<uint32_t> members;
  };
  std::vector<TreeNode> nodes(1);
  std::vector<Pending> current(1);
  current[0].node = 0;
  current[0].members.resize(set.size());
  for (std::size_t i = 0; i < set.size(); ++i) current[0].members[i] = static_cast<uint32_t>(i);

  for (int depth = 0; depth < config.levels && !current.empty(); ++depth) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::vector<Cluster>> results(current.size());
    // Largest nodes first, so the threads finish together.
    std::vector<std::size_t> order(current.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return current[a].members.size() > current[b].members.size();
    });
    const int inner_threads = current.size() == 1 ? config.threads : 1;
    for_each_index(current.size() == 1 ? 1 : config.threads, current.size(), [&](std::size_t oi, int) {
      const std::size_t i = order[oi];
      uint64_t seed_state = config.seed ^ (uint64_t(current[i].node) * 0xD1B54A32D192ED03ULL);
      results[i] =
          cluster_node(data, current[i].members, k, config.max_iterations, splitmix64(seed_state), inner_threads);
      std::vector<uint32_t>().swap(current[i].members);
    });
    std::vector<Pending> next;
    std::size_t children = 0, leaves_here = 0;
    for (std::size_t i = 0; i < current.size(); ++i) {
      auto& clusters = results[i];
      if (clusters.size() <= 1) {  // cannot be split: stays a leaf
        ++leaves_here;
        continue;
      }
      const uint32_t parent = current[i].node;
      nodes[parent].first_child = static_cast<uint32_t>(nodes.size());
      nodes[parent].child_count = static_cast<uint8_t>(clusters.size());
      for (auto& c : clusters) {
        const auto id = static_cast<uint32_t>(nodes.size());
        nodes.emplace_back();
        nodes.back().descriptor = c.centre;
        ++children;
        if (depth + 1 < config.levels && c.members.size() > 1) next.push_back({id, std::move(c.members)});
      }
      std::vector<Cluster>().swap(clusters);
    }
    say("level " + std::to_string(depth + 1) + "/" + std::to_string(config.levels) + ": clustered " +
        std::to_string(current.size()) + " nodes into " + std::to_string(children) + " children (" +
        std::to_string(leaves_here) + " could not be split) in " + fixed(seconds_since(t0), 1) + " s");
    current = std::move(next);
  }

  Vocabulary v;
  v.branching_ = k;
  v.levels_ = config.levels;
  v.description_ = description;
  v.training_descriptors_ = set.size();
  v.node_descriptors_.resize(nodes.size() * kDescriptorBytes);
  v.first_child_.resize(nodes.size());
  v.child_count_.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    std::memcpy(v.node_descriptors_.data() + i * kDescriptorBytes, nodes[i].descriptor.data(), kDescriptorBytes);
    v.first_child_[i] = nodes[i].first_child;
    v.child_count_[i] = nodes[i].child_count;
  }
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (nodes[i].child_count == 0) v.word_node_.push_back(static_cast<uint32_t>(i));
  v.word_weight_.assign(v.word_node_.size(), 0.f);
  v.finish_tree();

  // IDF: log(N / N_w), N = training images with descriptors, N_w = those with a descriptor of word w.
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t words = v.word_count();
  // One table pair per worker that can run (a worker takes whole images, so its counts add up).
  const int threads =
      static_cast<int>(std::clamp<std::size_t>(set.image_count(), 1, std::size_t(std::max(1, config.threads))));
  std::vector<std::vector<uint32_t>> df(static_cast<std::size_t>(threads), std::vector<uint32_t>(words, 0));
  std::vector<std::vector<uint32_t>> last(static_cast<std::size_t>(threads), std::vector<uint32_t>(words, UINT32_MAX));
  for_blocks(threads, set.image_count(), [&](std::size_t b, std::size_t e, int t) {
    auto& my_df = df[std::size_t(t)];
    auto& my_last = last[std::size_t(t)];
    for (std::size_t img = b; img < e; ++img)
      for (std::size_t i = set.image_begin(img); i < set.image_end(img); ++i) {
        const WordId w = v.word(set.descriptor(i));
        if (my_last[w] != img) {
          my_last[w] = static_cast<uint32_t>(img);
          ++my_df[w];
        }
      }
  });
  uint64_t images = 0;
  for (std::size_t img = 0; img < set.image_count(); ++img) images += set.image_end(img) > set.image_begin(img);
  v.training_images_ = images;
  for (std::size_t w = 0; w < words; ++w) {
    uint64_t n_w = 0;
    for (auto& d : df)
      if (!d.empty()) n_w += d[w];
    v.word_weight_[w] = static_cast<float>(std::log(double(images) / double(std::max<uint64_t>(n_w, 1))));
  }
  v.finish_tree();
  say("weights: IDF over " + std::to_string(images) + " images in " + fixed(seconds_since(t0), 1) + " s; " +
      v.describe());
  return v;
}

Vocabulary Vocabulary::train(const DescriptorSet& set, const VocabularyTrainingConfig& config,
                             const std::string& description, const TrainingProgress& progress) {
  try {
    config.validate("vocabulary training");
  } catch (const std::exception& e) {
    throw std::invalid_argument(e.what());
  }
  if (set.size() == 0) throw std::invalid_argument("Vocabulary::train: no training descriptors");
  if (set.size() > UINT32_MAX) throw std::invalid_argument("Vocabulary::train: more than 2^32 descriptors");
  return VocabularyBuilder::build(set, config, description, progress);
}

}  // namespace agvslam::place
