#pragma once
// Constructed 256-bit descriptor sets with known cluster structure, for the place module's tests.
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

namespace agvslam::place::test {

using Descriptor = std::vector<uint8_t>;  // 32 bytes

inline Descriptor random_descriptor(std::mt19937_64& rng) {
  Descriptor d(32);
  for (auto& b : d) b = static_cast<uint8_t>(rng() & 0xff);
  return d;
}

// `d` with `bits` distinct random bits flipped.
inline Descriptor flip_bits(const Descriptor& d, int bits, std::mt19937_64& rng) {
  Descriptor out = d;
  std::vector<int> idx(256);
  for (int i = 0; i < 256; ++i) idx[i] = i;
  for (int i = 0; i < bits; ++i) {
    const int j = i + static_cast<int>(rng() % static_cast<uint64_t>(256 - i));
    std::swap(idx[i], idx[j]);
    out[idx[i] / 8] = static_cast<uint8_t>(out[idx[i] / 8] ^ (1u << (idx[i] % 8)));
  }
  return out;
}

inline int distance(const uint8_t* a, const uint8_t* b) {
  int n = 0;
  for (int i = 0; i < 32; ++i) n += __builtin_popcount(unsigned(a[i] ^ b[i]));
  return n;
}

inline cv::Mat to_mat(const std::vector<Descriptor>& ds) {
  cv::Mat m(static_cast<int>(ds.size()), 32, CV_8UC1);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < 32; ++c) m.at<uint8_t>(r, c) = ds[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
  return m;
}

}  // namespace agvslam::place::test
