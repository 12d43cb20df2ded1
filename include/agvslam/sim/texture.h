#pragma once
// Band-limited procedural texture primitives.
//
// Every pattern is evaluated with the pixel's footprint on the surface (`footprint_m`: the width of one pixel
// there, in metres). Noise octaves whose wavelength falls below ~3 footprints are faded out (gone at 1.5), and
// hard-edged patterns (stripes, labels, joints) are box-filtered analytically over the footprint, so textures
// keep their detail up close but neither alias nor flicker at a distance or at grazing angles.

#include <cmath>
#include <cstdint>

#include "agvslam/sim/random.h"

#if defined(__GNUC__)
#define AGVSLAM_SIM_INLINE inline __attribute__((always_inline))
#else
#define AGVSLAM_SIM_INLINE inline
#endif

namespace agvslam::sim {

AGVSLAM_SIM_INLINE float clamp01(float x) { return x < 0 ? 0 : (x > 1 ? 1 : x); }
AGVSLAM_SIM_INLINE float lerp(float a, float b, float t) { return a + (b - a) * t; }
AGVSLAM_SIM_INLINE float smoothstep(float e0, float e1, float x) {
  const float t = clamp01((x - e0) / (e1 - e0));
  return t * t * (3 - 2 * t);
}

// Weight of a detail of size `wavelength_m` seen with a pixel footprint of `footprint_m`: 1 when it spans
// >= 3 pixels, 0 below 1.5 pixels.
AGVSLAM_SIM_INLINE float detail_visibility(float wavelength_m, float footprint_m) {
  return clamp01((wavelength_m / footprint_m - 1.5f) * (1.0f / 1.5f));
}

// floor() without a libm call (the baseline x86-64 target has no SSE4.1 round instruction).
AGVSLAM_SIM_INLINE int32_t floor_to_int(float x) {
  const int32_t i = static_cast<int32_t>(x);
  return i - (x < static_cast<float>(i) ? 1 : 0);
}
AGVSLAM_SIM_INLINE float fast_floor(float x) { return static_cast<float>(floor_to_int(x)); }

// Value of a lattice point from its pre-multiplied coordinates, in [0, 1).
AGVSLAM_SIM_INLINE float lattice_mix(uint32_t hx, uint32_t hy, uint32_t seed) {
  uint32_t h = hx ^ hy ^ seed;
  h = (h ^ (h >> 16)) * 0x7feb352dU;
  return unit_from_hash(h ^ (h >> 15));
}

// Hash of an integer lattice point, in [0, 1).
AGVSLAM_SIM_INLINE float lattice_value(int32_t ix, int32_t iy, uint32_t seed) {
  return lattice_mix(static_cast<uint32_t>(ix) * 0x8da6b343U, static_cast<uint32_t>(iy) * 0xd8163841U,
                     seed * 0xcb1ab31fU);
}

// Smooth value noise in [0, 1) with unit lattice spacing.
AGVSLAM_SIM_INLINE float value_noise(float x, float y, uint32_t seed) {
  const int32_t ix = floor_to_int(x), iy = floor_to_int(y);
  float tx = x - static_cast<float>(ix), ty = y - static_cast<float>(iy);
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const uint32_t hx0 = static_cast<uint32_t>(ix) * 0x8da6b343U, hx1 = hx0 + 0x8da6b343U;
  const uint32_t hy0 = static_cast<uint32_t>(iy) * 0xd8163841U, hy1 = hy0 + 0xd8163841U;
  const uint32_t s = seed * 0xcb1ab31fU;
  const float a = lattice_mix(hx0, hy0, s), b = lattice_mix(hx1, hy0, s);
  const float c = lattice_mix(hx0, hy1, s), d = lattice_mix(hx1, hy1, s);
  return a + (b - a) * tx + (c - a) * ty + (a - b - c + d) * tx * ty;
}

// Fractal (multi-octave) value noise centred on 0: octave i has wavelength wavelength_m / 2^i and amplitude
// persistence^i; octaves finer than the footprint allows are faded out. Range about +-0.5 * sum of amplitudes.
// (The reference implementation; fractal_noise below computes exactly the same, faster.)
inline float fractal_noise_scalar(float u, float v, float wavelength_m, int octaves, float persistence,
                                  float footprint_m, uint32_t seed) {
  float sum = 0, amplitude = 1;
  float wavelength_px = wavelength_m / footprint_m;  // octave wavelength in pixel footprints
  float inv = 1.0f / wavelength_m;
  for (int i = 0; i < octaves; ++i) {
    const float visibility = clamp01((wavelength_px - 1.5f) * (1.0f / 1.5f));
    if (visibility <= 0) break;
    // Each octave is shifted so the lattices of different octaves do not line up.
    sum += amplitude * visibility *
           (value_noise(u * inv + 0.37f * static_cast<float>(i), v * inv - 0.71f * static_cast<float>(i),
                        seed + static_cast<uint32_t>(i) * 0x9e3779b9U) -
            0.5f);
    amplitude *= persistence;
    wavelength_px *= 0.5f;
    inv *= 2.0f;
  }
  return sum;
}

#if defined(__GNUC__)
// Up to four octaves at once, one per lane of a 4-wide vector (GCC/Clang vector extensions: SSE2 on x86-64,
// NEON on ARM). Every lane does the scalar code's operations in the same order and the octaves are summed in
// order, so the result is bit-identical to fractal_noise_scalar (an octave the scalar code skips adds 0).
namespace simd {
typedef float f32x4 __attribute__((vector_size(16)));
typedef int32_t i32x4 __attribute__((vector_size(16)));
typedef uint32_t u32x4 __attribute__((vector_size(16)));

AGVSLAM_SIM_INLINE i32x4 floor_to_int(f32x4 x) {
  const i32x4 i = __builtin_convertvector(x, i32x4);
  return i + (x < __builtin_convertvector(i, f32x4));  // a true comparison is -1
}
AGVSLAM_SIM_INLINE f32x4 lattice_mix(u32x4 hx, u32x4 hy, u32x4 seed) {
  u32x4 h = hx ^ hy ^ seed;
  h = (h ^ (h >> 16)) * 0x7feb352dU;
  h ^= h >> 15;
  return __builtin_convertvector(__builtin_convertvector(h >> 8, i32x4), f32x4) * (1.0f / 16777216.0f);
}
AGVSLAM_SIM_INLINE f32x4 value_noise(f32x4 x, f32x4 y, u32x4 seed) {
  const i32x4 ix = floor_to_int(x), iy = floor_to_int(y);
  f32x4 tx = x - __builtin_convertvector(ix, f32x4), ty = y - __builtin_convertvector(iy, f32x4);
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const u32x4 hx0 = reinterpret_cast<u32x4>(ix) * 0x8da6b343U, hx1 = hx0 + 0x8da6b343U;
  const u32x4 hy0 = reinterpret_cast<u32x4>(iy) * 0xd8163841U, hy1 = hy0 + 0xd8163841U;
  const u32x4 s = seed * 0xcb1ab31fU;
  const f32x4 a = lattice_mix(hx0, hy0, s), b = lattice_mix(hx1, hy0, s);
  const f32x4 c = lattice_mix(hx0, hy1, s), d = lattice_mix(hx1, hy1, s);
  return a + (b - a) * tx + (c - a) * ty + (a - b - c + d) * tx * ty;
}
}  // namespace simd
#endif

AGVSLAM_SIM_INLINE float fractal_noise(float u, float v, float wavelength_m, int octaves, float persistence,
                                       float footprint_m, uint32_t seed) {
#if defined(__GNUC__)
  if (octaves <= 4) {
    using simd::f32x4;
    const float wavelength_px = wavelength_m / footprint_m, inv = 1.0f / wavelength_m;
    const f32x4 octave = {0, 1, 2, 3};
    const f32x4 scale = {1, 2, 4, 8}, px_scale = {1, 0.5f, 0.25f, 0.125f};  // exact powers of two
    const f32x4 amplitude = {1, persistence, persistence * persistence, persistence * persistence * persistence};
    const f32x4 wavelengths_px = wavelength_px * px_scale, invs = inv * scale;
    f32x4 visibility = (wavelengths_px - 1.5f) * (1.0f / 1.5f);
    visibility = visibility < 0 ? 0 : (visibility > 1 ? 1 : visibility);
    if (visibility[0] <= 0) return 0.0f;
    const f32x4 noise = simd::value_noise(u * invs + 0.37f * octave, v * invs - 0.71f * octave,
                                          seed + simd::u32x4{0, 1, 2, 3} * 0x9e3779b9U);
    const f32x4 term = amplitude * visibility * (noise - 0.5f);
    float sum = 0;
    for (int i = 0; i < octaves; ++i) sum += term[i];
    return sum;
  }
#endif
  return fractal_noise_scalar(u, v, wavelength_m, octaves, persistence, footprint_m, seed);
}

// Fraction of the footprint window [x - w/2, x + w/2] that lies inside [lo, hi] (a box-filtered step pair).
AGVSLAM_SIM_INLINE float interval_coverage(float x, float lo, float hi, float footprint_m) {
  const float a = std::max(x - 0.5f * footprint_m, lo);
  const float b = std::min(x + 0.5f * footprint_m, hi);
  return b > a ? (b - a) / footprint_m : 0.0f;
}

// Box-filtered coverage of periodic stripes [k * period, k * period + width). Tends to width / period (the
// mean) as the footprint approaches the period.
AGVSLAM_SIM_INLINE float stripe_coverage(float x, float period, float width, float footprint_m) {
  const float mean = width / period;
  if (footprint_m >= period) return mean;
  const float f = x - fast_floor(x / period) * period;  // [0, period)
  const float exact = interval_coverage(f, 0, width, footprint_m) +
                      interval_coverage(f, period, period + width, footprint_m) +
                      interval_coverage(f, -period, -period + width, footprint_m);
  const float blend = clamp01((footprint_m / period - 0.5f) * 2.0f);
  return lerp(exact, mean, blend);
}

// Coverage of the axis-aligned rectangle [u0, u1] x [v0, v1] (separable box filter).
AGVSLAM_SIM_INLINE float rect_coverage(float u, float v, float u0, float u1, float v0, float v1, float footprint_m) {
  if (u < u0 - footprint_m || u > u1 + footprint_m || v < v0 - footprint_m || v > v1 + footprint_m) return 0.0f;
  return interval_coverage(u, u0, u1, footprint_m) * interval_coverage(v, v0, v1, footprint_m);
}

// Coverage of a rectangular frame (outline) of line width `line_w` around [u0, u1] x [v0, v1].
inline float frame_coverage(float u, float v, float u0, float u1, float v0, float v1, float line_w, float footprint_m) {
  return rect_coverage(u, v, u0, u1, v0, v1, footprint_m) -
         rect_coverage(u, v, u0 + line_w, u1 - line_w, v0 + line_w, v1 - line_w, footprint_m);
}

// Text-like print inside [u0, u1] x [v0, v1]: lines of glyph blocks with word gaps (ink coverage in [0, 1]).
// Below the glyph size it averages to its mean ink density.
inline float text_coverage(float u, float v, float u0, float u1, float v0, float v1, float glyph_m, float footprint_m,
                           uint32_t seed) {
  if (u < u0 || u > u1 || v < v0 || v > v1) return 0.0f;
  const float line_pitch = glyph_m * 1.6f;
  const float char_pitch = glyph_m * 0.8f;
  const float lu = (u - u0) / char_pitch, lv = (v1 - v) / line_pitch;
  const int32_t col = floor_to_int(lu), row = floor_to_int(lv);
  const float mean_ink = 0.28f;
  const float fade = detail_visibility(glyph_m * 0.5f, footprint_m);
  if (fade <= 0) return mean_ink;
  // Glyph = a block with a random notch; word gaps are blank glyphs.
  const uint32_t h = hash32(static_cast<uint32_t>(col), static_cast<uint32_t>(row), seed);
  float ink = 0;
  if ((h & 7U) != 0 && row < static_cast<int32_t>((v1 - v0) / line_pitch)) {
    const float fu = (lu - static_cast<float>(col)) * char_pitch, fv = (lv - static_cast<float>(row)) * line_pitch;
    const float w_glyph = char_pitch * 0.75f, h_glyph = glyph_m;
    ink = rect_coverage(fu, fv, 0, w_glyph, 0, h_glyph, footprint_m);
    // Notch: removes a random quadrant-ish part so glyphs differ.
    const float nu = ((h >> 3) & 1U) ? 0.0f : w_glyph * 0.5f, nv = ((h >> 4) & 1U) ? 0.0f : h_glyph * 0.45f;
    ink -= rect_coverage(fu, fv, nu + w_glyph * 0.12f, nu + w_glyph * 0.38f, nv + h_glyph * 0.15f, nv + h_glyph * 0.4f,
                         footprint_m);
    ink = clamp01(ink);
  }
  return lerp(mean_ink, ink, fade);
}

// A 1-D barcode across [u0, u1] (bars of random width), full height of [v0, v1].
inline float barcode_coverage(float u, float v, float u0, float u1, float v0, float v1, float module_m,
                              float footprint_m, uint32_t seed) {
  const float vertical = rect_coverage(u, v, u0, u1, v0, v1, footprint_m);
  if (vertical <= 0) return 0.0f;
  const float fade = detail_visibility(module_m, footprint_m);
  if (fade <= 0) return 0.5f * vertical;
  const float lu = (u - u0) / module_m;
  const int32_t k = floor_to_int(lu);
  const float f = (lu - static_cast<float>(k)) * module_m;
  const bool ink_here = (hash32(static_cast<uint32_t>(k), seed) & 1U) != 0;
  const bool ink_prev = (hash32(static_cast<uint32_t>(k - 1), seed) & 1U) != 0;
  const bool ink_next = (hash32(static_cast<uint32_t>(k + 1), seed) & 1U) != 0;
  // Box filter across the module boundaries (footprint below one module when fade > 0).
  float ink = (ink_here ? interval_coverage(f, 0, module_m, footprint_m) : 0.0f) +
              (ink_prev ? interval_coverage(f, -module_m, 0, footprint_m) : 0.0f) +
              (ink_next ? interval_coverage(f, module_m, 2 * module_m, footprint_m) : 0.0f);
  return vertical * lerp(0.5f, ink, fade);
}

}  // namespace agvslam::sim
