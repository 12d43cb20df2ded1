#pragma once
// The renderer's hot loops in an AVX2 and a baseline copy (agvslam/core/cpu_clones.h): they gain from AVX2's
// integer multiplies (the texture hashes), blends and wider vectors, and both copies compute bit-identical images,
// depth and radiance (every operation is IEEE-exact on both; checked equal between a baseline and an AVX2 build).

#include "agvslam/core/cpu_clones.h"

#define AGVSLAM_SIM_CLONES AGVSLAM_CPU_CLONES
