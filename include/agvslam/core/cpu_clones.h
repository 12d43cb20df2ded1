#pragma once
// AGVSLAM_CPU_CLONES compiles a function twice, for AVX2 and for baseline x86-64, and runs the AVX2 copy on CPUs
// that have it (GCC function multiversioning: target_clones, resolved once at load time), so one binary runs on any
// x86-64 and uses the wider vectors where the CPU has them. "avx2" does not enable FMA: no multiply-add is fused,
// so both copies compute identical results. Functions inlined into a clone are compiled with it; out-of-line
// inline functions stay baseline, so no AVX2 code can leak to a caller on a CPU without it.
// Not under ThreadSanitizer: it instruments the load-time resolver, which runs before the sanitizer's runtime is set
// up and crashes the program at start.

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(__SANITIZE_THREAD__)
#define AGVSLAM_CPU_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define AGVSLAM_CPU_CLONES
#endif
