// Procedural albedo of the box materials and the actors. All patterns are band-limited (see texture.h).

#include <algorithm>
#include <cmath>

#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/renderer.h"
#include "agvslam/sim/texture.h"

namespace agvslam::sim {
namespace {

bool vertical_face(const FaceSample& f) { return f.face < 4; }
bool top_face(const FaceSample& f) { return f.face == 5; }

// White label with two text lines and a barcode, at [u0, u0 + lw] x [v0, v0 + lh].
float label(float base, const FaceSample& f, float u0, float v0, float lw, float lh, uint32_t seed) {
  const float w = f.footprint_m;
  const float cov = rect_coverage(f.u, f.v, u0, u0 + lw, v0, v0 + lh, w);
  if (cov <= 0) return base;
  float c = 0.9f;
  c = lerp(
      c, 0.08f,
      text_coverage(f.u, f.v, u0 + lw * 0.08f, u0 + lw * 0.92f, v0 + lh * 0.5f, v0 + lh * 0.92f, lh * 0.14f, w, seed));
  c = lerp(c, 0.06f,
           barcode_coverage(f.u, f.v, u0 + lw * 0.1f, u0 + lw * 0.9f, v0 + lh * 0.1f, v0 + lh * 0.42f, lw * 0.022f, w,
                            seed + 1U));
  return lerp(base, c, cov);
}

AGVSLAM_SIM_INLINE float carton(const FaceSample& f) {
  const float w = f.footprint_m;
  const uint32_t box_seed = f.seed & ~7U;  // shared by all faces of a box (tone), faces differ in f.seed
  float c = 0.38f + 0.2f * unit_from_hash(hash32(box_seed, 11U));
  c += 0.18f * fractal_noise(f.u, f.v, 0.16f, 3, 0.65f, w, f.seed);
  // Corrugation ridges (faint).
  c -= 0.03f * stripe_coverage(f.u, 0.008f, 0.004f, w);
  // Darker edges (handling dirt) and a slight shade gradient.
  const float edge = std::min(std::min(f.u, f.su - f.u), std::min(f.v, f.sv - f.v));
  c -= 0.07f * (1.0f - smoothstep(0.0f, 0.03f, edge)) * detail_visibility(0.03f, w);
  const bool long_x = f.box_size.x >= f.box_size.y;
  const float tape_w = 0.05f;
  const float tape_tone = 0.55f + 0.15f * unit_from_hash(hash32(box_seed, 12U));
  if (top_face(f)) {
    const float across = long_x ? f.v : f.u, span = long_x ? f.sv : f.su;
    c = lerp(c, tape_tone, interval_coverage(across, 0.5f * span - 0.5f * tape_w, 0.5f * span + 0.5f * tape_w, w));
    // Print on top of some boxes.
    if ((hash32(f.seed, 3U) & 3U) == 0)
      c = lerp(c, 0.12f, text_coverage(f.u, f.v, 0.05f, f.su * 0.45f, 0.05f, f.sv * 0.4f, 0.03f, w, f.seed));
    return c;
  }
  if (!vertical_face(f)) return c;
  // Tape running down the end faces.
  const bool end_face = (f.face / 2 == 0) == long_x;
  if (end_face)
    c = lerp(c, tape_tone,
             rect_coverage(f.u, f.v, 0.5f * f.su - 0.5f * tape_w, 0.5f * f.su + 0.5f * tape_w, f.sv - 0.07f, f.sv, w));
  const uint32_t h = hash32(f.seed, 5U);
  // Printed marks: a logo frame, arrows, handling symbols.
  if ((h & 3U) != 0 && f.su > 0.2f && f.sv > 0.15f) {
    const float s = std::min(0.12f, 0.35f * std::min(f.su, f.sv));
    const float u0 = 0.04f + (f.su - s - 0.08f) * unit_from_hash(hash32(h, 1U));
    const float v0 = 0.04f + (f.sv - s - 0.12f) * unit_from_hash(hash32(h, 2U));
    c = lerp(c, 0.1f, frame_coverage(f.u, f.v, u0, u0 + s, v0, v0 + s, s * 0.12f, w));
    c = lerp(c, 0.12f, rect_coverage(f.u, f.v, u0 + s * 0.3f, u0 + s * 0.7f, v0 + s * 0.3f, v0 + s * 0.7f, w));
    if ((h & 4U) != 0)
      c = lerp(c, 0.1f,
               text_coverage(f.u, f.v, u0 + s * 1.2f, std::min(f.su - 0.03f, u0 + s * 3.5f), v0, v0 + s * 0.8f,
                             s * 0.22f, w, h));
  }
  // Shipping label.
  if ((h & 24U) != 0 && f.su > 0.16f && f.sv > 0.12f) {
    const float lw = std::min(0.14f, f.su - 0.04f), lh = std::min(0.09f, f.sv - 0.04f);
    const float u0 = 0.02f + (f.su - lw - 0.04f) * unit_from_hash(hash32(h, 6U));
    const float v0 = 0.02f + (f.sv - lh - 0.04f) * unit_from_hash(hash32(h, 7U));
    c = label(c, f, u0, v0, lw, lh, h);
  }
  return c;
}

// Pallet side pattern on one 0.144 m layer (v_layer in [0, 0.144)).
float pallet_side(float u, float v_layer, float su, float w, uint32_t seed) {
  float c = 0.58f + 0.1f * unit_from_hash(hash32(seed, 1U));
  c += 0.14f * fractal_noise(u * 0.25f, v_layer * 4.0f, 0.05f, 3, 0.6f, w, seed + 2U);
  // Fork openings between the blocks.
  const float open_lo = 0.022f, open_hi = 0.122f;
  float open = rect_coverage(u, v_layer, su * 0.12f, su * 0.42f, open_lo, open_hi, w) +
               rect_coverage(u, v_layer, su * 0.58f, su * 0.88f, open_lo, open_hi, w);
  c = lerp(c, 0.06f, open);
  // Nail heads and dark plank edges.
  c = lerp(c, 0.3f, stripe_coverage(v_layer, 0.144f, 0.004f, w) * 0.8f);
  return c;
}

float pallet_top(float u, float v, float su, float sv, float w, uint32_t seed) {
  // Deck boards along the longer side; gaps between them.
  const bool along_u = su >= sv;
  const float across = along_u ? v : u;
  const float along = along_u ? u : v;
  const float board = 0.145f;
  const int32_t k = floor_to_int(across / board);
  float c =
      0.6f + 0.12f * (unit_from_hash(hash32(static_cast<uint32_t>(k), seed)) - 0.5f) * detail_visibility(board, w);
  c += 0.12f * fractal_noise(along * 0.2f, across * 3.0f, 0.04f, 3, 0.6f, w, seed + 3U);
  c = lerp(c, 0.08f, stripe_coverage(across - board + 0.035f, board, 0.035f, w));
  return c;
}

AGVSLAM_SIM_INLINE float wrapped_load(const FaceSample& f) {
  const float w = f.footprint_m;
  const uint32_t box_seed = f.seed & ~7U;
  float c = 0.62f + 0.16f * unit_from_hash(hash32(box_seed, 21U));
  if (vertical_face(f)) {
    // Film bands wound around horizontally, with glossy overlaps.
    const float streaks = value_noise(f.u * 0.8f, f.v * 12.0f, f.seed) - 0.5f;
    c += 0.18f * streaks * detail_visibility(0.08f, w);
    c += 0.12f * fractal_noise(f.u, f.v, 0.3f, 3, 0.6f, w, f.seed + 1U);
    c = lerp(c, c + 0.15f, stripe_coverage(f.v + unit_from_hash(hash32(box_seed, 22U)), 0.45f, 0.03f, w));
    // Cartons showing through the film.
    c = lerp(c, c - 0.2f, std::max(stripe_coverage(f.u, 0.4f, 0.012f, w), stripe_coverage(f.v, 0.3f, 0.012f, w)));
    const uint32_t h = hash32(f.seed, 23U);
    if ((h & 1U) != 0 && f.su > 0.3f && f.sv > 0.3f)
      c = label(c, f, 0.1f + 0.3f * (f.su - 0.3f) * unit_from_hash(h), f.sv * 0.55f, 0.21f, 0.15f, h);
  } else {
    c += 0.14f * fractal_noise(f.u, f.v, 0.3f, 3, 0.6f, w, f.seed + 2U);
  }
  return c;
}

AGVSLAM_SIM_INLINE float crate(const FaceSample& f) {
  const float w = f.footprint_m;
  const uint32_t box_seed = f.seed & ~7U;
  static constexpr float kTones[5] = {0.18f, 0.3f, 0.45f, 0.62f, 0.75f};
  float c = kTones[hash32(box_seed, 31U) % 5U];
  c += 0.06f * fractal_noise(f.u, f.v, 0.2f, 3, 0.6f, w, f.seed);
  if (vertical_face(f)) {
    c = lerp(c, c * 0.55f,
             stripe_coverage(f.u - 0.02f, 0.07f, 0.018f, w) * interval_coverage(f.v, 0.03f, f.sv - 0.05f, w));
    c = lerp(c, c + 0.12f, interval_coverage(f.v, f.sv - 0.035f, f.sv, w));
    c = lerp(c, 0.04f,
             rect_coverage(f.u, f.v, 0.5f * f.su - 0.06f, 0.5f * f.su + 0.06f, f.sv - 0.09f, f.sv - 0.05f, w));
    c = lerp(c, 0.88f, rect_coverage(f.u, f.v, 0.03f, 0.11f, 0.05f, 0.1f, w));
  } else if (top_face(f)) {
    const float inside = rect_coverage(f.u, f.v, 0.025f, f.su - 0.025f, 0.025f, f.sv - 0.025f, w);
    c = lerp(c, c * 0.3f, inside);
    c = lerp(c, c + 0.1f,
             inside * std::max(stripe_coverage(f.u, 0.05f, 0.008f, w), stripe_coverage(f.v, 0.05f, 0.008f, w)));
  }
  return c;
}

float upright(uint8_t variant, const FaceSample& f) {
  const float w = f.footprint_m;
  float c = 0.56f + 0.07f * fractal_noise(f.u, f.v, 0.2f, 3, 0.6f, w, f.seed);
  if (vertical_face(f)) {
    // Punched slots every 50 mm.
    const float slots =
        stripe_coverage(f.v, 0.05f, 0.024f, w) * interval_coverage(f.u, 0.5f * f.su - 0.009f, 0.5f * f.su + 0.009f, w);
    c = lerp(c, 0.07f, slots);
    if (variant == 1 && f.v < 0.6f) {
      const float stripes = stripe_coverage(f.u + f.v, 0.1f, 0.05f, w * 1.41f);
      c = lerp(0.8f, 0.08f, stripes);
    }
    c = lerp(c, 0.35f, interval_coverage(f.v, 0.0f, 0.012f, w));
  }
  return c;
}

AGVSLAM_SIM_INLINE float beam(const FaceSample& f) {
  const float w = f.footprint_m;
  float c = 0.27f + 0.06f * fractal_noise(f.u, f.v, 0.25f, 3, 0.6f, w, f.seed);
  if (!vertical_face(f)) return c;
  const bool along_face = f.su > 0.3f;  // the long faces carry the location labels
  if (!along_face) return c - 0.05f;
  const float slot = 0.86f;
  const int32_t k = floor_to_int(f.u / slot);
  const uint32_t h = hash32(static_cast<uint32_t>(k), f.seed);
  if ((h & 3U) != 0) {
    const float u0 = static_cast<float>(k) * slot + 0.08f + 0.25f * unit_from_hash(h);
    FaceSample g = f;
    c = label(c, g, u0, 0.018f, 0.15f, 0.085f, h);
  }
  // Safety clip and connector plates at the ends.
  c = lerp(c, 0.5f, interval_coverage(f.u, 0.0f, 0.04f, w) + interval_coverage(f.u, f.su - 0.04f, f.su, w));
  return c;
}

AGVSLAM_SIM_INLINE float deck(const FaceSample& f) {
  const float w = f.footprint_m;
  float c = 0.36f + 0.05f * fractal_noise(f.u, f.v, 0.3f, 2, 0.6f, w, f.seed);
  if (vertical_face(f)) return c;
  const float mesh = std::max(stripe_coverage(f.u, 0.05f, 0.006f, w), stripe_coverage(f.v, 0.1f, 0.006f, w));
  return lerp(c, 0.62f, mesh);
}

AGVSLAM_SIM_INLINE float pillar(const FaceSample& f) {
  const float w = f.footprint_m;
  float c = 0.6f + 0.16f * fractal_noise(f.u, f.v, 0.3f, 4, 0.62f, w, f.seed);
  if (!vertical_face(f)) return c;
  if (f.v < 1.2f) c = lerp(0.8f, 0.08f, stripe_coverage(f.u + f.v, 0.3f, 0.15f, w * 1.41f));
  c = lerp(c, 0.92f, rect_coverage(f.u, f.v, 0.05f, f.su - 0.05f, 2.2f, 2.55f, w));
  c = lerp(c, 0.06f, text_coverage(f.u, f.v, 0.08f, f.su - 0.08f, 2.25f, 2.5f, 0.12f, w, f.seed));
  return c;
}

float vehicle_body(const FaceSample& f, float tone, bool agv) {
  const float w = f.footprint_m;
  float c = tone + 0.05f * fractal_noise(f.u, f.v, 0.3f, 3, 0.6f, w, f.seed);
  if (!vertical_face(f)) return c - 0.04f;
  // Hazard stripes along the bottom, panel seams, decals.
  const float band_h = agv ? 0.08f : 0.12f;
  c = lerp(c, lerp(0.82f, 0.07f, stripe_coverage(f.u + f.v, 0.16f, 0.08f, w * 1.41f)),
           interval_coverage(f.v, 0.0f, band_h, w));
  c = lerp(c, 0.15f, stripe_coverage(f.u, 0.6f, 0.008f, w) * interval_coverage(f.v, band_h, f.sv, w));
  if (f.su > 0.5f && f.sv > 0.3f) {
    c = lerp(c, 0.08f,
             text_coverage(f.u, f.v, 0.12f, std::min(f.su - 0.1f, 0.9f), f.sv * 0.45f, f.sv * 0.8f, 0.06f, w, f.seed));
    c = lerp(c, 0.95f, rect_coverage(f.u, f.v, f.su - 0.3f, f.su - 0.12f, f.sv * 0.5f, f.sv * 0.75f, w));
  }
  return c;
}

}  // namespace

AGVSLAM_SIM_CLONES float box_albedo(Material material, uint8_t variant, const FaceSample& f) {
  const float w = f.footprint_m;
  switch (material) {
    case Material::kCarton:
      return carton(f);
    case Material::kPallet:
      if (top_face(f)) return pallet_top(f.u, f.v, f.su, f.sv, w, f.seed & ~7U);
      if (vertical_face(f)) return pallet_side(f.u, f.v, f.su, w, f.seed);
      return 0.3f;
    case Material::kPalletStack: {
      if (top_face(f)) return pallet_top(f.u, f.v, f.su, f.sv, w, f.seed & ~7U);
      if (!vertical_face(f)) return 0.3f;
      const float layer_h = 0.144f;
      const float layer = fast_floor(f.v / layer_h);
      const float vl = f.v - layer * layer_h;
      const uint32_t layer_seed = hash32(f.seed, static_cast<uint32_t>(layer));
      const float shift = 0.03f * (unit_from_hash(layer_seed) - 0.5f);
      return pallet_side(f.u + shift, vl, f.su, w, layer_seed);
    }
    case Material::kWrappedLoad:
      return wrapped_load(f);
    case Material::kCrate:
      return crate(f);
    case Material::kRackUpright:
      return upright(variant, f);
    case Material::kRackBeam:
      return beam(f);
    case Material::kRackBrace:
      return 0.5f + 0.06f * fractal_noise(f.u, f.v, 0.3f, 2, 0.6f, w, f.seed);
    case Material::kShelfDeck:
      return deck(f);
    case Material::kPillar:
      return pillar(f);
    case Material::kDockLeveller:
      return 0.4f;
    case Material::kVehicleBody:
      return vehicle_body(f, 0.72f, false);
    case Material::kVehicleDark:
      return 0.1f + 0.05f * fractal_noise(f.u, f.v, 0.2f, 2, 0.6f, w, f.seed);
    case Material::kVehicleMetal:
      return 0.34f + 0.1f * fractal_noise(f.u * 0.3f, f.v * 3.0f, 0.2f, 3, 0.6f, w, f.seed);
    case Material::kVehicleGuard:
      return 0.12f + 0.04f * fractal_noise(f.u, f.v, 0.2f, 3, 0.6f, w, f.seed);
    case Material::kTyre:
      return 0.07f + 0.03f * fractal_noise(f.u, f.v, 0.05f, 3, 0.6f, w, f.seed);
    default:
      return 0.5f;
  }
}

AGVSLAM_SIM_CLONES float actor_albedo(const DynamicObject& obj, const DynamicPrimitive& prim, const V3& p, const V3& n,
                                      float axis_param, float w) {
  const bool person_part = prim.material == Material::kPersonShirt || prim.material == Material::kPersonTrousers ||
                           prim.material == Material::kPersonSkin || prim.material == Material::kPersonHead;
  if (person_part || (obj.cls == ActorClass::kPerson && prim.material == Material::kTyre))
    return person_albedo(obj, prim, p, n, axis_param, w);
  if (prim.shape != PrimitiveShape::kBox) return 0.5f;
  // Face coordinates in the box's own frame.
  const V3 center = obj.to_local(prim.a);
  const V3 q = p - center + prim.half;  // [0, 2 * half]
  const V3 size = prim.half * 2.0f;
  FaceSample f;
  f.box_size = size;
  f.footprint_m = w;
  const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
  int axis = 2;
  if (ax >= ay && ax >= az)
    axis = 0;
  else if (ay >= az)
    axis = 1;
  const bool positive = n[axis] > 0;
  f.face = axis * 2 + (positive ? 1 : 0);
  if (axis == 2) {
    f.u = q.x;
    f.v = q.y;
    f.su = size.x;
    f.sv = size.y;
  } else if (axis == 0) {
    f.u = q.y;
    f.v = q.z;
    f.su = size.y;
    f.sv = size.z;
  } else {
    f.u = q.x;
    f.v = q.z;
    f.su = size.x;
    f.sv = size.z;
  }
  f.seed = hash32(obj.seed + prim.part * 131U, static_cast<uint32_t>(f.face)) & ~7U;
  f.seed |= static_cast<uint32_t>(f.face);
  if (prim.material == Material::kVehicleBody)
    return vehicle_body(f, obj.vehicle.body_shade, obj.cls == ActorClass::kAgv);
  return box_albedo(prim.material, 0, f);
}

}  // namespace agvslam::sim
