#pragma once
// AGVSLAM_SIM_CLONES compiles a function twice, for AVX2 and for baseline x86-64, and runs the AVX2 copy on CPUs
// that have it (GCC function multiversioning: target_clones, resolved once at load time). The renderer's hot
// loops gain from AVX2's integer multiplies (the texture hashes), blends and wider vectors. Both copies compute
// bit-identical results: "avx2" does not enable FMA, so no multiply-add is ever fused, and every other operation
// is IEEE-exact on both (images, depth and radiance checked equal between a baseline and an AVX2 build).
// Functions inlined into a clone are compiled with it; out-of-line inline functions stay baseline, so no
// AVX2 code can leak to a caller on a CPU without it. Not under ThreadSanitizer (the resolver it would instrument
// runs before the sanitizer's runtime is set up).

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(AGVSLAM_SIM_NO_CLONES) && !defined(__SANITIZE_THREAD__)
#define AGVSLAM_SIM_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define AGVSLAM_SIM_CLONES
#endif
