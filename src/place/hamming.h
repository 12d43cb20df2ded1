#pragma once
// Hamming-distance kernels of the place module (internal).
//
// The build targets baseline x86-64, where __builtin_popcountll is a library call; every x86-64 CPU made since
// 2008 has the POPCNT instruction. The loops below are compiled twice, once for POPCNT, and the variant is
// chosen once at run time (hamming_kernels()), so the same binary runs anywhere and fast where it can.

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace agvslam::place::detail {

inline int hamming256(const uint8_t* a, const uint8_t* b) {
  uint64_t x[4], y[4];
  std::memcpy(x, a, 32);
  std::memcpy(y, b, 32);
  return __builtin_popcountll(x[0] ^ y[0]) + __builtin_popcountll(x[1] ^ y[1]) + __builtin_popcountll(x[2] ^ y[2]) +
         __builtin_popcountll(x[3] ^ y[3]);
}

struct HammingKernels {
  // Index of the nearest of n candidates (32 bytes each, consecutive); the first one on ties. n >= 1.
  int (*nearest)(const uint8_t* d, const uint8_t* candidates, int n);
  // For members[0..count): out_assignment[i] = nearest centre of descriptor data[members[i]] (first on ties).
  void (*assign)(const uint8_t* data, const uint32_t* members, std::size_t count, const uint8_t* centres, int k,
                 uint8_t* out_assignment);
  // min_dist[i] = min(min_dist[i], distance(data[members[i]], centre)).
  void (*update_min_distance)(const uint8_t* data, const uint32_t* members, std::size_t count, const uint8_t* centre,
                              uint32_t* min_dist);
  bool uses_popcnt_instruction;
};

const HammingKernels& hamming_kernels();

}  // namespace agvslam::place::detail
