// Albedo of people: clothing, skin, hair and shoes (see PersonLook). Real clothes give a feature detector corners:
// checks and plaids cross, prints and badges have letters and frames, pockets, zips, buttons and seams are small
// contrasting shapes, fabric folds into creases. All patterns are band-limited like the rest (texture.h).

#include <algorithm>
#include <cmath>

#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/renderer.h"
#include "agvslam/sim/texture.h"

namespace agvslam::sim {
namespace {

using Look = PersonLook;

// Coverage of the pattern's second colour at (u, v) (m on the garment).
float pattern_coverage(const Look& look, float u, float v, float w, uint32_t seed) {
  const float period = look.pattern_period_m;
  switch (look.pattern) {
    case Look::Pattern::kPlain:
      return 0.0f;
    case Look::Pattern::kStripes:
      return stripe_coverage(v, period, 0.5f * period, w);
    case Look::Pattern::kChecks: {
      const float a = stripe_coverage(u, period, 0.5f * period, w), b = stripe_coverage(v, period, 0.5f * period, w);
      return a + b - 2.0f * a * b;
    }
    case Look::Pattern::kPlaid: {
      // Broad bands both ways (their crossings darkest), thin lines between them.
      const float a = stripe_coverage(u, period, 0.4f * period, w), b = stripe_coverage(v, period, 0.4f * period, w);
      const float thin = std::max(stripe_coverage(u + 0.7f * period, period, 0.07f * period, w),
                                  stripe_coverage(v + 0.7f * period, period, 0.07f * period, w));
      return std::max(0.5f * (a + b), thin);
    }
    case Look::Pattern::kBlotches: {
      const float scale = 1.0f / (1.3f * period);
      const float vis = detail_visibility(period, w);
      if (vis <= 0) return 0.3f;
      const float edge = std::clamp(w * scale, 0.02f, 0.25f);
      return vis * smoothstep(0.55f - edge, 0.55f + edge, value_noise(u * scale, v * scale, seed + 19U)) +
             (1.0f - vis) * 0.3f;
    }
    case Look::Pattern::kDots: {
      const float vis = detail_visibility(0.5f * period, w);
      if (vis <= 0) return 0.15f;
      const float row = fast_floor(v / period);
      const float uu = u / period + 0.5f * (row - 2.0f * fast_floor(0.5f * row));  // every other row shifted
      const float fu = uu - fast_floor(uu) - 0.5f, fv = v / period - row - 0.5f;
      const float d = std::sqrt(fu * fu + fv * fv) * period, r = 0.22f * period;
      return vis * clamp01((r - d) / w + 0.5f) + (1.0f - vis) * 0.15f;
    }
  }
  return 0.0f;
}

// Brightness factor of fabric folds: creases (thin dark lines along the iso-lines of a stretched noise) and the
// soft shading between them.
float fold_factor(float u, float v, float w, uint32_t seed) {
  const float vis = detail_visibility(0.03f, w);
  if (vis <= 0) return 1.0f;
  const float n = value_noise(u * 8.0f + 3.1f, v * 3.5f, seed + 23U);
  const float crease = 1.0f - smoothstep(0.0f, 0.07f + 4.0f * w, std::fabs(n - 0.5f));
  return 1.0f - vis * (0.24f * crease - 0.1f * (n - 0.5f));
}

// A small emblem: a frame around a filled block, and a line of text beside it, in [u0, u1] x [v0, v1].
float emblem(float base, float ink, float u, float v, float u0, float u1, float v0, float v1, float w, uint32_t seed) {
  const float h = v1 - v0;
  float c = lerp(base, ink, frame_coverage(u, v, u0, u0 + h, v0, v1, 0.12f * h, w));
  c = lerp(c, ink, rect_coverage(u, v, u0 + 0.3f * h, u0 + 0.7f * h, v0 + 0.3f * h, v0 + 0.7f * h, w));
  return lerp(c, ink, text_coverage(u, v, u0 + 1.2f * h, u1, v0 + 0.25f * h, v1 - 0.25f * h, 0.3f * h, w, seed));
}

// The top on the torso: across = metres left of its centre line as seen on the face (front: +y, back: -y),
// height = metres above the hem, torso_h = the torso's height.
float top_on_torso(const Look& look, uint32_t seed, bool front, bool back, float u, float across, float height,
                   float torso_h, float w) {
  const float V = torso_h;
  float c = look.shirt_shade;
  c = lerp(c, look.pattern_shade, pattern_coverage(look, u, height, w, seed));
  const float ink = look.shirt_shade > 0.45f ? 0.08f : 0.9f;
  const float trim = look.pattern == Look::Pattern::kPlain ? look.pattern_shade : ink;
  switch (look.top) {
    case Look::Top::kTshirt:
      if (front || back) c = lerp(c, trim, interval_coverage(height, V - 0.03f, V, w));  // neckband
      if ((look.prints & Look::kFrontGraphic) != 0 && front) {
        const float u0 = -0.12f, u1 = 0.12f, v0 = 0.42f * V, v1 = 0.82f * V;
        const float box = rect_coverage(across, height, u0, u1, v0, v1, w);
        if (box > 0) {
          float g = lerp(look.pattern_shade, ink, frame_coverage(across, height, u0, u1, v0, v1, 0.012f, w));
          g = lerp(g, ink, rect_coverage(across, height, u0 + 0.03f, u0 + 0.1f, v0 + 0.12f * V, v1 - 0.05f, w));
          g = lerp(g, look.shirt_shade,
                   rect_coverage(across, height, u0 + 0.05f, u0 + 0.08f, v0 + 0.2f * V, v1 - 0.09f, w));
          g = lerp(g, ink,
                   text_coverage(across, height, u0 + 0.12f, u1 - 0.02f, v0 + 0.03f, v1 - 0.04f, 0.028f, w, seed + 5U));
          c = lerp(c, g, box);
        }
      }
      break;
    case Look::Top::kLongSleeve:
      if (front && look.pockets) {
        c = lerp(c, trim,
                 interval_coverage(across, -0.009f, 0.009f, w) * interval_coverage(height, 0.0f, V - 0.02f, w));
        // Buttons down the placket, a chest pocket with its flap.
        const float b =
            stripe_coverage(height - 0.03f, 0.085f, 0.012f, w) * interval_coverage(across, -0.006f, 0.006f, w);
        c = lerp(c, ink, b);
        c = lerp(c, trim, frame_coverage(across, height, 0.04f, 0.13f, 0.6f * V, 0.78f * V, 0.006f, w));
        c = lerp(c, trim,
                 interval_coverage(height, 0.74f * V, 0.75f * V, w) * interval_coverage(across, 0.04f, 0.13f, w));
      }
      if (front || back) c = lerp(c, trim, interval_coverage(height, V - 0.035f, V, w));  // collar
      break;
    case Look::Top::kJacket: {
      if (front) {
        c = lerp(c, look.inner_shade,
                 interval_coverage(across, -0.05f, 0.05f, w) * interval_coverage(height, 0.78f * V, V, w));
        c = lerp(c, 0.55f,
                 interval_coverage(across, -0.006f, 0.006f, w) * interval_coverage(height, 0.0f, 0.78f * V, w));
        if (look.pockets) {
          for (float side : {-1.0f, 1.0f}) {  // chest pockets with zips, hand pockets with flaps
            const float a0 = side > 0 ? 0.035f : -0.14f, a1 = a0 + 0.105f;
            c = lerp(c, trim, frame_coverage(across, height, a0, a1, 0.6f * V, 0.74f * V, 0.005f, w));
            c = lerp(c, 0.6f,
                     interval_coverage(height, 0.7f * V, 0.71f * V, w) *
                         interval_coverage(across, a0 + 0.01f, a1 - 0.01f, w));
            c = lerp(c, trim, frame_coverage(across, height, a0, a1, 0.12f * V, 0.3f * V, 0.005f, w));
            c = lerp(c, ink,
                     rect_coverage(across, height, 0.5f * (a0 + a1) - 0.008f, 0.5f * (a0 + a1) + 0.008f, 0.25f * V,
                                   0.27f * V, w));
          }
        }
      }
      c = lerp(c, look.pattern_shade, interval_coverage(height, 0.86f * V, V, w));  // shoulder yoke
      c = lerp(c, 0.92f, interval_coverage(height, 0.5f * V, 0.52f * V, w));        // reflective piping
      break;
    }
    case Look::Top::kHoodie:
      if (front) {
        c = lerp(c, trim, frame_coverage(across, height, -0.13f, 0.13f, 0.08f * V, 0.35f * V, 0.007f, w));  // pocket
        for (float a : {-0.04f, 0.04f})  // drawstrings
          c = lerp(c, ink,
                   interval_coverage(across, a - 0.005f, a + 0.005f, w) * interval_coverage(height, 0.68f * V, V, w));
      }
      c = lerp(c, c * 0.8f,
               interval_coverage(height, 0.0f, 0.06f * V, w) * stripe_coverage(u, 0.012f, 0.006f, w));  // ribbing
      break;
    case Look::Top::kHiVisVest: {
      c = look.shirt_shade;  // the vest covers the shirt's pattern
      if (front) c = lerp(c, look.inner_shade, interval_coverage(across, -0.035f, 0.035f, w));
      for (float band : {0.18f, 0.5f}) {  // reflective bands with dark edges
        const float v0 = band * V;
        c = lerp(c, 0.98f, interval_coverage(height, v0, v0 + 0.05f, w));
        c = lerp(c, 0.3f,
                 interval_coverage(height, v0 - 0.006f, v0, w) + interval_coverage(height, v0 + 0.05f, v0 + 0.056f, w));
      }
      if (back) {
        c = lerp(c, 0.1f, text_coverage(across, height, -0.13f, 0.13f, 0.66f * V, 0.86f * V, 0.045f, w, seed + 7U));
      }
      break;
    }
    case Look::Top::kOveralls: {
      // A bib with straps over the shirt; the shirt shows beside the bib.
      const float bib = interval_coverage(across, -0.12f, 0.12f, w) * (front ? 1.0f : 0.0f);
      const float straps = interval_coverage(std::fabs(across), 0.07f, 0.11f, w);
      const float upper = interval_coverage(height, 0.62f * V, V, w);
      c = lerp(c, look.inner_shade, upper * (1.0f - std::max(bib, straps)));
      if (front && look.pockets) {
        c = lerp(c, trim, frame_coverage(across, height, -0.08f, 0.08f, 0.45f * V, 0.6f * V, 0.006f, w));
        for (float a : {-0.09f, 0.09f})
          c = lerp(c, 0.6f, rect_coverage(across, height, a - 0.012f, a + 0.012f, 0.6f * V, 0.63f * V, w));
      }
      break;
    }
  }
  // Prints over the garment.
  if ((look.prints & Look::kChestLogo) != 0 && front)
    c = emblem(c, ink, across, height, -0.14f, -0.03f, 0.72f * V, 0.78f * V, w, seed + 11U);
  if ((look.prints & Look::kNameBadge) != 0 && front) {
    const float badge = rect_coverage(across, height, 0.04f, 0.13f, 0.82f * V, 0.86f * V, w);
    if (badge > 0) {
      const float b =
          lerp(0.92f, 0.1f, text_coverage(across, height, 0.05f, 0.12f, 0.825f * V, 0.855f * V, 0.01f, w, seed + 13U));
      c = lerp(c, b, badge);
    }
  }
  if ((look.prints & Look::kBackPrint) != 0 && back && look.top != Look::Top::kHiVisVest) {
    c = lerp(c, ink, text_coverage(across, height, -0.13f, 0.13f, 0.62f * V, 0.86f * V, 0.04f, w, seed + 17U));
    c = lerp(c, ink, frame_coverage(across, height, -0.15f, 0.15f, 0.58f * V, 0.9f * V, 0.008f, w));
  }
  return c;
}

// Trousers on a leg capsule: `along` (m from the hip or knee end), `around` (m along the surface from the front,
// towards the outer side), part 5 the thigh, 6 the shin.
float trousers(const Look& look, int part, float along, float len, float around, float r, float w) {
  float c = look.trousers_shade;
  const float ink = c > 0.45f ? 0.1f : 0.6f;
  const float side = 0.5f * 3.14159265f * r;  // around at the outer side seam
  const float seam = interval_coverage(around, side - 0.004f, side + 0.004f, w);
  switch (look.bottom) {
    case Look::Bottom::kJeans: {
      c = lerp(c, std::min(0.9f, c + 0.25f), seam);  // stitched seams are lighter
      if (part == 5) {
        const float back = 2.0f * side;  // centre of the back
        c = lerp(c, std::min(0.9f, c + 0.2f),
                 frame_coverage(around, along, back - 0.08f, back - 0.01f, 0.05f, 0.18f, 0.004f, w));
        c = lerp(c, std::min(0.9f, c + 0.2f),
                 interval_coverage(along, 0.0f, 0.1f, w) * interval_coverage(around, 0.45f * side, 0.5f * side, w));
      }
      c += 0.06f * (1.0f - smoothstep(0.0f, 0.12f, std::fabs(part == 5 ? len - along : along)));  // worn knees
      break;
    }
    case Look::Bottom::kCargo:
      c = lerp(c, c * 0.7f, seam);
      if (part == 5 && look.pockets) {
        const float a0 = side - 0.06f, a1 = side + 0.06f;
        c = lerp(c, ink, frame_coverage(around, along, a0, a1, 0.4f * len, 0.75f * len, 0.005f, w));
        c = lerp(c, ink, interval_coverage(along, 0.5f * len, 0.51f * len, w) * interval_coverage(around, a0, a1, w));
        c = lerp(c, 0.05f, rect_coverage(around, along, side - 0.01f, side + 0.01f, 0.45f * len, 0.48f * len, w));
      }
      break;
    case Look::Bottom::kWork:
      c = lerp(c, c * 0.7f, seam);
      if (part == 6 && look.pockets)  // knee pad pockets
        c = lerp(c, look.trousers_shade * 0.55f, rect_coverage(around, along, -0.05f, 0.05f, 0.0f, 0.14f, w));
      break;
    case Look::Bottom::kHiVis:
      c = lerp(c, c * 0.75f, seam);
      if (part == 6)
        for (float band : {0.3f, 0.48f})
          c = lerp(c, 0.98f, interval_coverage(along, band * len, band * len + 0.05f, w));
      break;
  }
  if (part == 5) c = lerp(c, 0.08f, interval_coverage(along, 0.0f, 0.035f, w));  // belt
  return c;
}

}  // namespace

AGVSLAM_SIM_CLONES float person_albedo(const DynamicObject& obj, const DynamicPrimitive& prim, const V3& p, const V3& n,
                                       float axis_param, float w) {
  const Look& look = obj.look;
  const uint32_t seed = obj.seed;
  const float fabric = 1.0f + 0.1f * fractal_noise(p.y + p.x, p.z, 0.12f, 3, 0.6f, w, seed + 3U);
  switch (prim.material) {
    case Material::kPersonShirt: {
      float c;
      const float u = p.y + 0.6f * p.x;
      if (prim.part == 0) {
        const V3 centre = obj.to_local(prim.a);
        const bool front = n.x > 0.5f, back = n.x < -0.5f;
        const float across = back ? centre.y - p.y : p.y - centre.y;
        const float height = p.z - (centre.z - prim.half.z);
        c = top_on_torso(look, seed, front, back, u, across, height, 2.0f * prim.half.z, w);
      } else {
        // Arms: sleeves (a t-shirt's end above the elbow; a vest or overalls show the shirt), cuffs, hands.
        const bool forearm = prim.part == 4;
        if (forearm && axis_param > 0.8f) return look.skin_shade;
        if (look.top == Look::Top::kTshirt && (forearm || axis_param > 0.55f)) return look.skin_shade;
        const bool inner = look.top == Look::Top::kHiVisVest || look.top == Look::Top::kOveralls;
        c = inner ? look.inner_shade
                  : lerp(look.shirt_shade, look.pattern_shade, pattern_coverage(look, u, p.z, w, seed));
        if (forearm) c = lerp(c, c * 0.75f, smoothstep(0.72f, 0.74f, axis_param));  // cuff
      }
      if (look.folds) c *= fold_factor(u, p.z, w, seed);
      return std::clamp(c * fabric, 0.03f, 1.0f);
    }
    case Material::kPersonTrousers: {
      const V3 a = obj.to_local(prim.a), b = obj.to_local(prim.b);
      const float len = std::sqrt((b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y) + (b.z - a.z) * (b.z - a.z));
      const float side_sign = a.y >= 0 ? 1.0f : -1.0f;  // the outer side of this leg
      const float around = prim.radius * std::atan2(n.y * side_sign, n.x);
      const float along = axis_param * len;
      float c = trousers(look, prim.part, along, len, std::fabs(around), prim.radius, w);
      if (look.folds) c *= fold_factor(around * 3.0f, p.z, w, seed + 31U);
      return std::clamp(c * fabric, 0.03f, 1.0f);
    }
    case Material::kPersonSkin:
      if (look.top == Look::Top::kHoodie) return look.shirt_shade;  // the hood around the neck
      return look.skin_shade;
    case Material::kPersonHead: {
      const V3 c_local = obj.to_local(prim.a);
      const V3 d = p - c_local;  // on the sphere
      const float r = prim.radius;
      float c = look.skin_shade + 0.04f * fractal_noise(d.y, d.z, 0.05f, 3, 0.6f, w, seed + 9U);
      if (look.helmet) {
        const float cov = smoothstep(-0.1f * r - w, -0.1f * r + w, d.z);
        c = lerp(c, 0.85f, cov);
        c = lerp(c, 0.6f, interval_coverage(d.z, -0.15f * r, -0.05f * r, w));
      } else {
        // Hair: top and back of the head.
        const float hair =
            std::max(smoothstep(0.15f * r - w, 0.15f * r + w, d.z),
                     smoothstep(-0.2f * r - w, -0.2f * r + w, -d.x) * smoothstep(-0.6f * r - w, -0.6f * r + w, d.z));
        c = lerp(c, look.hair_shade, hair);
      }
      if (d.x > 0.5f * r) {  // eyes and mouth
        c = lerp(c, 0.05f, rect_coverage(std::fabs(d.y), d.z, 0.25f * r, 0.5f * r, 0.02f * r, 0.18f * r, w));
        c = lerp(c, c * 0.6f, rect_coverage(d.y, d.z, -0.25f * r, 0.25f * r, -0.5f * r, -0.42f * r, w));
      }
      return c;
    }
    default:  // shoes
      return look.shoe_shade + 0.03f * fractal_noise(p.x, p.z, 0.05f, 3, 0.6f, w, seed + 11U);
  }
}

}  // namespace agvslam::sim
