// The procedural albedos of the static surfaces (floor, walls, ceiling, box faces): what the texture cache bakes.

#include <algorithm>
#include <cmath>

#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/renderer.h"
#include "agvslam/sim/texture.h"

namespace agvslam::sim {

AGVSLAM_SIM_CLONES float Renderer::box_face_albedo(std::size_t box_index, int face, float u, float v,
                                                   float footprint_m) const {
  const StaticBox& box = warehouse_.boxes[box_index];
  FaceSample f;
  f.box_size = box.hi - box.lo;
  face_size(box, face, f.su, f.sv);
  f.u = u;
  f.v = v;
  f.face = face;
  f.footprint_m = footprint_m;
  f.seed = (hash32(box.seed) & ~7U) | static_cast<uint32_t>(face);
  return box_albedo(box.material, box.variant, f);
}

// ---- Analytic surfaces -----------------------------------------------------------------------------------------

AGVSLAM_SIM_CLONES float Renderer::floor_albedo(float x, float y, float w) const {
  const uint32_t seed = warehouse_.floor_seed;
  // Power-trowelled concrete: gentle broad tone variation, dark stains, lighter worn patches, fine grit.
  float c = 0.55f + 0.16f * fractal_noise(x, y, 1.2f, 3, 0.6f, w, seed);
  const float stain = value_noise(x * 0.4f, y * 0.4f, seed + 31U);
  c *= 1.0f - 0.3f * smoothstep(0.64f, 0.82f, stain);
  c += 0.07f * smoothstep(0.62f, 0.85f, 1.0f - stain);
  c += 0.26f * fractal_noise(x, y, 0.06f, 3, 0.85f, w, seed + 17U);
  // Tyre tracks (streaks along x in the aisles, along y elsewhere).
  const float track_vis = detail_visibility(0.1f, w);
  if (track_vis > 0) {
    const float track = value_noise(x * 0.35f, y * 9.0f, seed + 41U);
    c -= 0.10f * track_vis * smoothstep(0.7f, 0.88f, track);
  }
  // Saw-cut joints between slabs (6 m), dark.
  const float joints =
      std::max(stripe_coverage(x - 0.004f, 6.0f, 0.008f, w), stripe_coverage(y - 0.004f, 6.0f, 0.008f, w));
  c = lerp(c, 0.16f, 0.85f * joints);
  // Painted marks.
  const int ix = std::clamp(static_cast<int>(x / mark_cell_m_), 0, mark_nx_ - 1);
  const int iy = std::clamp(static_cast<int>(y / mark_cell_m_), 0, mark_ny_ - 1);
  for (uint16_t mi : mark_bins_[static_cast<std::size_t>(iy * mark_nx_ + ix)]) {
    const FloorMark& m = warehouse_.floor_marks[mi];
    float cov = rect_coverage(x, y, m.x0, m.x1, m.y0, m.y1, w);
    if (cov <= 0) continue;
    switch (m.kind) {
      case FloorMark::Kind::kSolid:
        break;
      case FloorMark::Kind::kDashedX:
        cov *= stripe_coverage(x, 1.0f, 0.6f, w);
        break;
      case FloorMark::Kind::kDashedY:
        cov *= stripe_coverage(y, 1.0f, 0.6f, w);
        break;
      case FloorMark::Kind::kHatched: {
        const float frame = 1.0f - rect_coverage(x, y, m.x0 + 0.06f, m.x1 - 0.06f, m.y0 + 0.06f, m.y1 - 0.06f, w);
        cov *= std::max(frame, stripe_coverage(x + y, 0.3f, 0.13f, w * 1.41f));
        break;
      }
    }
    // Worn paint.
    const float wear = 0.85f + 0.3f * fractal_noise(x, y, 0.2f, 2, 0.5f, w, seed + 53U);
    c = lerp(c, m.shade * wear, cov);
  }
  return std::max(0.02f, c);
}

AGVSLAM_SIM_CLONES float Renderer::wall_albedo(int wall, float u, float z, float w) const {
  const uint32_t seed = warehouse_.wall_seed + static_cast<uint32_t>(wall) * 7919U;
  float c;
  if (z < 0.3f) {
    // Painted kick band with hazard stripes.
    const float stripes = stripe_coverage(u + z, 0.4f, 0.2f, w * 1.41f);
    c = lerp(0.72f, 0.1f, stripes);
  } else if (z < 2.8f) {
    // Concrete blocks, 0.4 x 0.2 m, running bond.
    const float zz = z - 0.3f;
    const int32_t row = floor_to_int(zz / 0.2f);
    const float uu = u + ((row & 1) ? 0.2f : 0.0f);
    const int32_t col = floor_to_int(uu / 0.4f);
    const float block_tone = unit_from_hash(hash32(static_cast<uint32_t>(row), static_cast<uint32_t>(col), seed));
    c = 0.58f + 0.12f * (block_tone - 0.5f) * detail_visibility(0.2f, w);
    c += 0.14f * fractal_noise(u, z, 0.1f, 3, 0.65f, w, seed + 3U);
    const float mortar = std::max(stripe_coverage(zz, 0.2f, 0.012f, w), stripe_coverage(uu, 0.4f, 0.012f, w));
    c = lerp(c, 0.78f, mortar);
    // Grime towards the floor.
    c -= 0.12f * (1.0f - smoothstep(0.3f, 1.2f, z)) * (0.5f + value_noise(u * 0.7f, 0.0f, seed + 5U));
  } else if (z < 2.95f) {
    c = 0.26f + 0.05f * fractal_noise(u, z, 0.5f, 3, 0.5f, w, seed + 7U);
  } else {
    // Corrugated metal cladding with panel seams and fasteners.
    // Corrugation: a smooth periodic profile (parabolic arcs, no libm call).
    const float phase = u * 5.0f - fast_floor(u * 5.0f);     // 0.2 m ribs
    const float rib = 8.0f * phase * (1.0f - phase) - 1.0f;  // -1..1
    c = 0.56f + 0.1f * rib * detail_visibility(0.2f, w);
    // Weathering: streaks running down the panels and patchy dirt, so the ribs are not a perfect grating.
    c += 0.14f * fractal_noise(u * 4.0f, z * 0.5f, 0.6f, 3, 0.6f, w * 4.0f, seed + 11U);
    c += 0.1f * fractal_noise(u, z, 0.5f, 3, 0.6f, w, seed + 13U);
    c = lerp(c, 0.25f, stripe_coverage(u, 1.0f, 0.012f, w));
    c = lerp(c, 0.3f, stripe_coverage(z - 2.95f, 1.5f, 0.01f, w));
    c -= 0.1f * smoothstep(5.0f, 8.0f, z);
  }
  const int bin = std::clamp(floor_to_int(u), 0, wall_bins_ - 1);
  for (uint16_t fi : wall_feature_bins_[static_cast<std::size_t>(wall * wall_bins_ + bin)]) {
    const WallFeature& f = warehouse_.wall_features[fi];
    if (u < f.u0 - w || u > f.u1 + w || z < f.z0 - w || z > f.z1 + w) continue;
    const float cov = rect_coverage(u, z, f.u0, f.u1, f.z0, f.z1, w);
    if (cov <= 0) continue;
    const float lu = u - f.u0, lz = z - f.z0, fw = f.u1 - f.u0, fh = f.z1 - f.z0;
    float fc = 0.5f;
    switch (f.kind) {
      case WallFeature::Kind::kRollerDoor: {
        fc = 0.64f + 0.06f * fractal_noise(u, z, 0.5f, 2, 0.6f, w, f.seed);
        fc = lerp(fc, 0.35f, stripe_coverage(lz, 0.09f, 0.014f, w));
        fc = lerp(fc, 0.2f, rect_coverage(lu, lz, 0, fw, 0, 0.12f, w));
        // Yellow/black frame posts.
        const float post = rect_coverage(lu, lz, 0, 0.15f, 0, fh, w) + rect_coverage(lu, lz, fw - 0.15f, fw, 0, fh, w);
        fc = lerp(fc, lerp(0.78f, 0.08f, stripe_coverage(lu + lz, 0.3f, 0.15f, 1.41f * w)), post);
        // Dock number sign.
        const float sign = rect_coverage(lu, lz, fw * 0.5f - 0.25f, fw * 0.5f + 0.25f, fh - 0.55f, fh - 0.2f, w);
        fc = lerp(fc, 0.9f, sign);
        fc = lerp(
            fc, 0.05f,
            text_coverage(lu, lz, fw * 0.5f - 0.2f, fw * 0.5f + 0.2f, fh - 0.5f, fh - 0.25f, 0.1f, w, f.seed) * sign);
        break;
      }
      case WallFeature::Kind::kPoster: {
        const uint32_t h = f.seed;
        fc = 0.7f + 0.25f * unit_from_hash(hash32(h, 1U));
        fc = lerp(fc, 0.12f, frame_coverage(lu, lz, 0, fw, 0, fh, 0.02f, w));
        // Big blocks of colour (pictures / headings), then text.
        const float head_h = fh * 0.22f;
        fc = lerp(fc, 0.15f + 0.4f * unit_from_hash(hash32(h, 2U)),
                  rect_coverage(lu, lz, 0.05f, fw - 0.05f, fh - 0.05f - head_h, fh - 0.05f, w));
        fc = lerp(fc, 0.95f,
                  text_coverage(lu, lz, 0.08f, fw - 0.08f, fh - head_h, fh - 0.08f, head_h * 0.4f, w, h + 3U));
        const float pic_w = fw * (0.3f + 0.3f * unit_from_hash(hash32(h, 4U)));
        fc = lerp(fc, 0.1f + 0.6f * unit_from_hash(hash32(h, 5U)),
                  rect_coverage(lu, lz, 0.05f, 0.05f + pic_w, fh * 0.3f, fh - 0.1f - head_h, w));
        fc = lerp(fc, 0.1f,
                  text_coverage(lu, lz, 0.1f + pic_w, fw - 0.05f, fh * 0.3f, fh - 0.1f - head_h, 0.025f, w, h + 6U));
        fc = lerp(fc, 0.1f, text_coverage(lu, lz, 0.05f, fw - 0.05f, 0.05f, fh * 0.27f, 0.018f, w, h + 7U));
        break;
      }
      case WallFeature::Kind::kSign: {
        const bool dark = (f.seed & 1U) != 0;
        fc = dark ? 0.22f : 0.85f;
        fc = lerp(fc, dark ? 0.9f : 0.1f, frame_coverage(lu, lz, 0.02f, fw - 0.02f, 0.02f, fh - 0.02f, 0.025f, w));
        const float sym = std::min(fw, fh) * 0.5f;
        fc = lerp(fc, dark ? 0.92f : 0.12f,
                  rect_coverage(lu, lz, 0.08f, 0.08f + sym, (fh - sym) * 0.5f, (fh + sym) * 0.5f, w));
        fc = lerp(fc, dark ? 0.9f : 0.1f,
                  text_coverage(lu, lz, 0.12f + sym, fw - 0.05f, fh * 0.3f, fh * 0.7f, fh * 0.12f, w, f.seed));
        break;
      }
      case WallFeature::Kind::kCabinet: {
        fc = 0.62f + 0.05f * fractal_noise(lu, lz, 0.3f, 3, 0.5f, w, f.seed);
        fc = lerp(fc, 0.2f, frame_coverage(lu, lz, 0.03f, fw - 0.03f, 0.03f, fh - 0.03f, 0.008f, w));
        fc = lerp(fc, 0.1f, rect_coverage(lu, lz, fw - 0.09f, fw - 0.06f, fh * 0.4f, fh * 0.6f, w));
        fc = lerp(fc, 0.95f, rect_coverage(lu, lz, 0.08f, 0.2f, fh - 0.14f, fh - 0.08f, w));
        fc = lerp(fc, 0.15f, text_coverage(lu, lz, 0.09f, 0.19f, fh - 0.135f, fh - 0.085f, 0.012f, w, f.seed));
        break;
      }
      case WallFeature::Kind::kWindow: {
        fc = 1.35f + 0.2f * value_noise(lu * 0.5f, lz, f.seed);
        const float mullions = std::max(stripe_coverage(lu, 0.75f, 0.05f, w), stripe_coverage(lz, 0.6f, 0.05f, w));
        fc = lerp(fc, 0.18f, std::max(mullions, frame_coverage(lu, lz, 0, fw, 0, fh, 0.06f, w)));
        break;
      }
      case WallFeature::Kind::kPipe:
        fc = 0.4f;
        break;
    }
    c = lerp(c, fc, cov);
  }
  return std::max(0.02f, c);
}

AGVSLAM_SIM_CLONES float Renderer::ceiling_albedo(float x, float y, float w) const {
  const uint32_t seed = warehouse_.ceiling_seed;
  float c = 0.32f + 0.1f * fractal_noise(x, y, 1.0f, 3, 0.6f, w, seed);
  c = lerp(c, 0.5f, stripe_coverage(x, 5.0f, 0.3f, w));    // roof trusses
  c = lerp(c, 0.22f, stripe_coverage(y, 1.2f, 0.06f, w));  // purlins
  // Light fittings: bright strips on a 5 m x 4 m grid.
  const float lx = x - fast_floor(x / 5.0f) * 5.0f, ly = y - fast_floor(y / 4.0f) * 4.0f;
  c = lerp(c, 3.0f, rect_coverage(lx, ly, 2.3f, 2.7f, 1.2f, 2.8f, w));
  return c;
}

}  // namespace agvslam::sim
