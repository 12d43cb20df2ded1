#pragma once
// Block-matching kernels of the stereo matcher (private to the features module): the SAD of one left window
// against n consecutive right windows along a row, four columns at a time. The scalar kernel and the SIMD ones
// give identical costs (exact integer sums); the best one for this CPU is picked at run time.
#include <cstdint>

namespace agvslam::features::detail {

// left_rows[r]: first pixel of row r of the left window; right_rows[r]: first pixel of row r of the first right
// window (candidate k starts k pixels further right). Window: `rows` rows x 4 * blocks columns (blocks in [1, 4]).
// Writes costs[0 .. round_up(n, 16)) (entries past n are garbage): the cost array needs that size, and the right
// rows must stay readable for n + 48 bytes.
using SadRowKernel = void (*)(const uint8_t* const* left_rows, const uint8_t* const* right_rows, int rows, int blocks,
                              int n, uint16_t* costs);

void sad_costs_scalar(const uint8_t* const* left_rows, const uint8_t* const* right_rows, int rows, int blocks, int n,
                      uint16_t* costs);

// The fastest kernel this CPU runs (SSE4.1 mpsadbw, AVX2, or the scalar one) and its name.
SadRowKernel best_sad_kernel(const char** name = nullptr);
// A kernel by name ("scalar", "sse41", "avx2"), or nullptr when this build or CPU lacks it (for tests).
SadRowKernel sad_kernel(const char* name);

}  // namespace agvslam::features::detail
