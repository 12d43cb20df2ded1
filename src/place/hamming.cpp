#include "hamming.h"

namespace agvslam::place::detail {
namespace {

// The bodies, compiled once per target below (hamming256 is inlined, and its popcounts become instructions
// where the enclosing function's target allows it).
#define AGVSLAM_PLACE_NEAREST_BODY                       \
  int best = 0;                                          \
  int best_dist = hamming256(d, candidates);             \
  for (int i = 1; i < n; ++i) {                          \
    const int dist = hamming256(d, candidates + 32 * i); \
    if (dist < best_dist) {                              \
      best_dist = dist;                                  \
      best = i;                                          \
    }                                                    \
  }                                                      \
  return best;

#define AGVSLAM_PLACE_ASSIGN_BODY                           \
  for (std::size_t i = 0; i < count; ++i) {                 \
    const uint8_t* d = data + std::size_t(members[i]) * 32; \
    int best = 0;                                           \
    int best_dist = hamming256(d, centres);                 \
    for (int c = 1; c < k; ++c) {                           \
      const int dist = hamming256(d, centres + 32 * c);     \
      if (dist < best_dist) {                               \
        best_dist = dist;                                   \
        best = c;                                           \
      }                                                     \
    }                                                       \
    out_assignment[i] = static_cast<uint8_t>(best);         \
  }

#define AGVSLAM_PLACE_UPDATE_BODY                                                                         \
  for (std::size_t i = 0; i < count; ++i) {                                                               \
    const uint32_t dist = static_cast<uint32_t>(hamming256(data + std::size_t(members[i]) * 32, centre)); \
    if (dist < min_dist[i]) min_dist[i] = dist;                                                           \
  }

int nearest_generic(const uint8_t* d, const uint8_t* candidates, int n) { AGVSLAM_PLACE_NEAREST_BODY }
void assign_generic(const uint8_t* data, const uint32_t* members, std::size_t count, const uint8_t* centres, int k,
                    uint8_t* out_assignment) {
  AGVSLAM_PLACE_ASSIGN_BODY
}
void update_generic(const uint8_t* data, const uint32_t* members, std::size_t count, const uint8_t* centre,
                    uint32_t* min_dist) {
  AGVSLAM_PLACE_UPDATE_BODY
}

#if defined(__x86_64__) && defined(__GNUC__)
#define AGVSLAM_PLACE_HAVE_POPCNT_VARIANT 1
__attribute__((target("popcnt"))) int nearest_popcnt(const uint8_t* d, const uint8_t* candidates, int n) {
  AGVSLAM_PLACE_NEAREST_BODY
}
__attribute__((target("popcnt"))) void assign_popcnt(const uint8_t* data, const uint32_t* members, std::size_t count,
                                                     const uint8_t* centres, int k, uint8_t* out_assignment) {
  AGVSLAM_PLACE_ASSIGN_BODY
}
__attribute__((target("popcnt"))) void update_popcnt(const uint8_t* data, const uint32_t* members, std::size_t count,
                                                     const uint8_t* centre,
                                                     uint32_t* min_dist){AGVSLAM_PLACE_UPDATE_BODY}
#endif

HammingKernels select_kernels() {
#ifdef AGVSLAM_PLACE_HAVE_POPCNT_VARIANT
  __builtin_cpu_init();
  if (__builtin_cpu_supports("popcnt")) return {nearest_popcnt, assign_popcnt, update_popcnt, true};
#endif
  return {nearest_generic, assign_generic, update_generic, false};
}

}  // namespace

const HammingKernels& hamming_kernels() {
  static const HammingKernels kernels = select_kernels();
  return kernels;
}

}  // namespace agvslam::place::detail
