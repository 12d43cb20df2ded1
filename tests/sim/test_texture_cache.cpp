// The texture cache (lazily baked mip-mapped tiles of the static surfaces' procedural textures): lookups agree
// with the procedural evaluation, texels are baked once and freed when unused, and a result never depends on
// what was baked before or on how many threads look up concurrently. And the vectorised fractal noise computes
// exactly what its scalar reference does.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>
#include <vector>

#include "agvslam/sim/random.h"
#include "agvslam/sim/simulator.h"
#include "agvslam/sim/texture.h"
#include "agvslam/sim/texture_cache.h"

namespace agvslam::sim {
namespace {

constexpr float kBaseTexel = 1.0f / 512.0f;

// A smooth pattern (no detail to filter): what a lookup returns must be the pattern itself.
float smooth_pattern(float u, float v, float /*footprint*/) {
  return 0.5f + 0.3f * std::sin(6.2831853f * u / 0.4f) * std::cos(6.2831853f * v / 0.3f);
}

struct Lookup {
  float u, v, footprint;
};

std::vector<Lookup> random_lookups(int n, float size_u, float size_v, float min_footprint, float max_footprint,
                                   uint64_t seed) {
  Rng rng(seed, RngStream::kTextures);
  std::vector<Lookup> out;
  for (int i = 0; i < n; ++i)
    out.push_back({static_cast<float>(rng.uniform(0, size_u)), static_cast<float>(rng.uniform(0, size_v)),
                   static_cast<float>(min_footprint * std::pow(max_footprint / min_footprint, rng.uniform()))});
  return out;
}

TEST(Texture, FractalNoiseIsBitIdenticalToTheReference) {
  Rng rng(7, RngStream::kTextures);
  for (int i = 0; i < 200000; ++i) {
    const float u = static_cast<float>(rng.uniform(-50, 50)), v = static_cast<float>(rng.uniform(-50, 50));
    const float wavelength = static_cast<float>(rng.uniform(0.01, 2.0));
    const int octaves = rng.uniform_int(1, 5);
    const float persistence = static_cast<float>(rng.uniform(0.3, 0.9));
    const float footprint = static_cast<float>(0.0005 * std::pow(1000.0, rng.uniform()));
    const uint32_t seed = rng.next_u32();
    ASSERT_EQ(fractal_noise(u, v, wavelength, octaves, persistence, footprint, seed),
              fractal_noise_scalar(u, v, wavelength, octaves, persistence, footprint, seed))
        << u << " " << v << " " << wavelength << " " << octaves << " " << persistence << " " << footprint;
  }
}

TEST(TextureCache, LookupsReproduceASmoothPatternAtAnyFootprint) {
  const TextureCache cache(1, kBaseTexel, 4);
  double worst = 0;
  for (const Lookup& q : random_lookups(20000, 3.0f, 2.0f, 0.0005f, 0.01f, 1)) {
    const float cached = cache.sample(0, 3.0f, 2.0f, q.u, q.v, q.footprint, smooth_pattern);
    worst = std::max(worst, static_cast<double>(std::fabs(cached - smooth_pattern(q.u, q.v, q.footprint))));
  }
  // Interpolation error of the pattern (amplitude 0.3) with texels up to 15.6 mm: about 0.01.
  EXPECT_LT(worst, 0.02);
  // Beyond the surface, lookups clamp to its edge.
  EXPECT_NEAR(cache.sample(0, 3.0f, 2.0f, -1.0f, 0.5f, 0.001f, smooth_pattern), smooth_pattern(0, 0.5f, 0), 0.01);
  EXPECT_NEAR(cache.sample(0, 3.0f, 2.0f, 2.9f, 5.0f, 0.001f, smooth_pattern), smooth_pattern(2.9f, 2.0f, 0), 0.01);
}

TEST(TextureCache, BakesEachTexelOnceAndFreesTilesUnusedForKeepPasses) {
  TextureCache cache(2, kBaseTexel, 3);
  int calls = 0;
  auto counting = [&](float u, float v, float w) {
    ++calls;
    return smooth_pattern(u, v, w);
  };
  const float first = cache.sample(1, 1.0f, 1.0f, 0.3f, 0.4f, 0.003f, counting);  // levels 0 and 1: two tiles
  const int baked = calls;
  EXPECT_EQ(baked, 2 * (TextureCache::kTileTexels + 1) * (TextureCache::kTileTexels + 1));
  EXPECT_EQ(cache.stats().texels_baked, static_cast<uint64_t>(baked));
  EXPECT_EQ(cache.stats().tiles, 2u);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(cache.sample(1, 1.0f, 1.0f, 0.3f, 0.4f, 0.003f, counting), first);
  EXPECT_EQ(calls, baked);
  // Used in every pass: kept.
  for (int pass = 0; pass < 5; ++pass) {
    cache.begin_pass();
    EXPECT_EQ(cache.sample(1, 1.0f, 1.0f, 0.3f, 0.4f, 0.003f, counting), first);
  }
  EXPECT_EQ(calls, baked);
  // Unused for more than keep_passes passes: freed, and baked again (identically) when needed.
  for (int pass = 0; pass < 4; ++pass) cache.begin_pass();
  EXPECT_EQ(cache.stats().tiles, 0u);
  EXPECT_EQ(cache.stats().tiles_freed, 2u);
  EXPECT_EQ(cache.sample(1, 1.0f, 1.0f, 0.3f, 0.4f, 0.003f, counting), first);
  EXPECT_EQ(calls, 2 * baked);
}

TEST(TextureCache, ResultsDoNotDependOnHistoryOrThreads) {
  auto source = [](float u, float v, float w) { return 0.5f + fractal_noise(u, v, 0.05f, 4, 0.7f, w, 99U); };
  const std::vector<Lookup> lookups = random_lookups(20000, 4.0f, 4.0f, 0.001f, 0.2f, 2);
  // Reference: a fresh cache, one thread, in order.
  std::vector<float> reference;
  {
    const TextureCache cache(1, kBaseTexel, 2);
    for (const Lookup& q : lookups) reference.push_back(cache.sample(0, 4.0f, 4.0f, q.u, q.v, q.footprint, source));
  }
  // A cache that baked and freed other things first, looked up in reverse order.
  {
    TextureCache cache(1, kBaseTexel, 2);
    for (const Lookup& q : random_lookups(5000, 4.0f, 4.0f, 0.001f, 0.2f, 3))
      cache.sample(0, 4.0f, 4.0f, q.u, q.v, q.footprint, source);
    for (int pass = 0; pass < 2; ++pass) cache.begin_pass();
    for (std::size_t i = lookups.size(); i-- > 0;)
      ASSERT_EQ(cache.sample(0, 4.0f, 4.0f, lookups[i].u, lookups[i].v, lookups[i].footprint, source), reference[i]);
  }
  // Four threads looking up (and baking) the same texels concurrently.
  {
    const TextureCache cache(1, kBaseTexel, 2);
    std::vector<std::vector<float>> results(4);
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < results.size(); ++k)
      threads.emplace_back([&, k] {
        for (const Lookup& q : lookups)
          results[k].push_back(cache.sample(0, 4.0f, 4.0f, q.u, q.v, q.footprint, source));
      });
    for (auto& t : threads) t.join();
    for (const auto& r : results) EXPECT_EQ(r, reference);
  }
}

// Statistics of cached against procedural albedos of one kind of surface over random lookups.
struct Agreement {
  double mean_abs_error = 0;  // mean |cached - procedural|
  double mean_offset = 0;     // mean (cached - procedural)
  double contrast = 0;        // mean |procedural - its mean|: the texture's own variation
};

template <typename Cached, typename Procedural>
Agreement compare(const std::vector<Lookup>& lookups, const Cached& cached, const Procedural& procedural) {
  std::vector<double> exact;
  Agreement a;
  double mean = 0;
  for (std::size_t i = 0; i < lookups.size(); ++i) {
    const double p = procedural(i, lookups[i]), c = cached(i, lookups[i]);
    exact.push_back(p);
    mean += p;
    a.mean_abs_error += std::fabs(c - p);
    a.mean_offset += c - p;
  }
  const double n = static_cast<double>(lookups.size());
  mean /= n;
  for (double p : exact) a.contrast += std::fabs(p - mean);
  a.mean_abs_error /= n;
  a.mean_offset /= n;
  a.contrast /= n;
  return a;
}

TEST(TextureCache, RendererLookupsAgreeWithTheProceduralTextures) {
  ScenarioOptions o;
  o.name = "static";
  o.seed = 5;
  const Simulator sim(SimConfig{}, o);
  const Renderer& r = sim.renderer();
  const Warehouse& w = sim.warehouse();
  // Footprints from the nearest floor pixels (2 mm) to distant ones (10 cm).
  const std::vector<Lookup> floor = random_lookups(3000, w.width_m, w.depth_m, 0.002f, 0.1f, 4);
  const Agreement floor_agreement = compare(
      floor, [&](std::size_t, const Lookup& q) { return r.cached_floor_albedo(q.u, q.v, q.footprint); },
      [&](std::size_t, const Lookup& q) { return r.floor_albedo(q.u, q.v, q.footprint); });
  const std::vector<Lookup> wall = random_lookups(3000, w.width_m, w.height_m, 0.002f, 0.1f, 5);
  const Agreement wall_agreement = compare(
      wall, [&](std::size_t, const Lookup& q) { return r.cached_wall_albedo(0, q.u, q.v, q.footprint); },
      [&](std::size_t, const Lookup& q) { return r.wall_albedo(0, q.u, q.v, q.footprint); });
  // Box faces: a vertical face of every 11th box.
  std::vector<Lookup> faces;
  std::vector<std::size_t> face_box;
  for (std::size_t b = 0; b < w.boxes.size(); b += 11) {
    const V3 size = w.boxes[b].hi - w.boxes[b].lo;
    for (const Lookup& q : random_lookups(10, size.x, size.z, 0.001f, 0.05f, 6 + b)) {
      faces.push_back(q);
      face_box.push_back(b);
    }
  }
  const Agreement face_agreement = compare(
      faces,
      [&](std::size_t i, const Lookup& q) { return r.cached_box_face_albedo(face_box[i], 3, q.u, q.v, q.footprint); },
      [&](std::size_t i, const Lookup& q) { return r.box_face_albedo(face_box[i], 3, q.u, q.v, q.footprint); });
  for (const auto& [name, a] : {std::pair{"floor", floor_agreement}, std::pair{"wall", wall_agreement},
                                std::pair{"box faces", face_agreement}}) {
    std::printf("%s: mean |cached - procedural| %.4f, mean offset %+.4f, texture contrast %.4f\n", name,
                a.mean_abs_error, a.mean_offset, a.contrast);
    EXPECT_LT(a.mean_abs_error, 0.3 * a.contrast) << name;  // the same texture, filtered a little differently
    EXPECT_LT(std::fabs(a.mean_offset), 0.01) << name;      // no change of tone
  }
}

}  // namespace
}  // namespace agvslam::sim
