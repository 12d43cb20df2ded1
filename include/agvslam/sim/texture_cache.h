#pragma once
// Lazily baked, mip-mapped textures of the static surfaces.
//
// A surface is a rectangle [0, size_u] x [0, size_v] (metres) whose albedo comes from a procedural source
// source(u, v, footprint_m), band-limited to the footprint (texture.h). Level L of its mip pyramid holds the
// source sampled at the centres of square texels of side T = base_texel_m * 2^L, each evaluated with a footprint
// of kBakeFootprint * T (pre-filtered texels; below one texel because the bilinear reconstruction blurs too, so
// that lookups stay as sharp as evaluating the source per pixel). A lookup with footprint w blends bilinear
// samples of the two levels whose texel sizes bracket w (trilinear filtering). A static surface's texture is thus
// evaluated about once per texel, and each texel serves both cameras and the frames while the surface stays at about
// that distance, instead of the source being evaluated for every pixel of every frame.
//
// Texels are baked in tiles of kTileTexels x kTileTexels (plus a one-texel apron, so a bilinear lookup never
// straddles two tiles) the first time a lookup needs them. A texel's value depends only on the surface, the
// level and the texel's position, so when, where and by which thread it was baked never changes a result.
// Lookups may run concurrently (tiles are published atomically). begin_pass() frees the tiles that no lookup
// used during the last keep_passes passes; it must not overlap any lookup.

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <vector>

namespace agvslam::sim {

class TextureCache {
 public:
  static constexpr int kTileShift = 5;
  static constexpr int kTileTexels = 1 << kTileShift;
  static constexpr int kMaxLevels = 20;
  static constexpr float kBakeFootprint = 0.65f;  // footprint of a texel's source evaluation, in texels

  // `surface_count` surfaces with ids [0, surface_count); level-0 texels of `base_texel_m` (a power of two keeps
  // the texel centres exact); tiles unused for `keep_passes` passes are freed by begin_pass().
  TextureCache(std::size_t surface_count, float base_texel_m, uint32_t keep_passes);
  ~TextureCache();
  TextureCache(const TextureCache&) = delete;
  TextureCache& operator=(const TextureCache&) = delete;

  // Albedo of surface `id` (of size size_u x size_v; the same for every lookup of that surface) at (u, v) seen
  // with a pixel footprint of `footprint_m`. `source(u, v, footprint_m)` is called only to bake missing texels.
  template <typename Source>
#if defined(__GNUC__)
  __attribute__((always_inline))  // into the caller, and so into its AVX2 copy (cpu_dispatch.h)
#endif
  float
  sample(std::size_t id, float size_u, float size_v, float u, float v, float footprint_m, const Source& source) const {
    const Surface& s = surface(id, size_u, size_v);
    // footprint / base texel = 2^level * (1 + blend), blend in [0, 1): read straight from the float's bits.
    const float ratio = footprint_m * inv_base_texel_m_;
    if (!(ratio > 1.0f)) return decode(sample_level(s, 0, u, v, source));
    uint32_t bits;
    std::memcpy(&bits, &ratio, sizeof bits);
    const int level = static_cast<int>(bits >> 23) - 127;
    if (level >= s.top_level) return decode(sample_level(s, s.top_level, u, v, source));
    const uint32_t mantissa_bits = (bits & 0x007fffffU) | 0x3f800000U;
    float mantissa;
    std::memcpy(&mantissa, &mantissa_bits, sizeof mantissa);
    const float blend = mantissa - 1.0f;
    const float fine = sample_level(s, level, u, v, source);
    const float coarse = sample_level(s, level + 1, u, v, source);
    return decode(fine + (coarse - fine) * blend);
  }

  // Starts a pass (a rendered image): frees the tiles not used during the last keep_passes passes.
  void begin_pass();

  struct Stats {
    std::size_t tiles = 0;      // tiles held now
    std::size_t bytes = 0;      // memory of the tiles held now
    uint64_t texels_baked = 0;  // source evaluations so far
    uint64_t tiles_freed = 0;
  };
  Stats stats() const;

  float base_texel_m() const { return base_texel_m_; }

 private:
  // Texels are stored as 16-bit codes: albedo = code / kCodeScale + kCodeMin (steps of 1.2e-4, 0.03 grey levels).
  static constexpr float kCodeMin = -0.5f;
  static constexpr float kCodeScale = 8192.0f;
  static constexpr int kTileStride = kTileTexels + 1;  // texels per tile row, apron included
  struct Tile {
    // Row-major, kTileStride per row; a tile at the surface's edge uses the top-left part.
    uint16_t texels[kTileStride * kTileStride];
  };
  // Where a tile is published, with the last pass that used it (next to the pointer, so that marking the use
  // touches no other memory).
  struct Slot {
    std::atomic<Tile*> tile{nullptr};
    std::atomic<uint32_t> last_pass{0};
  };
  struct Level {
    float texel_m = 0, inv_texel_m = 0;
    float x_max = 0, y_max = 0;      // largest texel coordinate a lookup may use (texels - 1)
    int texels_u = 0, texels_v = 0;  // texels covering the surface (the apron adds one more)
    int tiles_u = 0, tiles_v = 0;
    Slot* slots = nullptr;  // tiles_u * tiles_v, row-major
  };
  struct Surface {
    int top_level = 0;
    std::array<Level, kMaxLevels> levels;
    std::unique_ptr<Slot[]> slots;  // the tiles of all levels
  };

  const Surface& surface(std::size_t id, float size_u, float size_v) const {
    const Surface* s = surfaces_[id].load(std::memory_order_acquire);
    return s ? *s : create_surface(id, size_u, size_v);
  }
  const Surface& create_surface(std::size_t id, float size_u, float size_v) const;

  template <typename Source>
#if defined(__GNUC__)
  __attribute__((always_inline))
#endif
  float
  sample_level(const Surface& s, int level, float u, float v, const Source& source) const {
    const Level& lv = s.levels[static_cast<std::size_t>(level)];
    // Texel coordinates clamped to the surface (std::max(0, NaN) is 0).
    const float x = std::min(std::max(0.0f, u * lv.inv_texel_m - 0.5f), lv.x_max);
    const float y = std::min(std::max(0.0f, v * lv.inv_texel_m - 0.5f), lv.y_max);
    const int ix = static_cast<int>(x), iy = static_cast<int>(y);
    const float fx = x - static_cast<float>(ix), fy = y - static_cast<float>(iy);
    const int tx = ix >> kTileShift, ty = iy >> kTileShift;
    Slot& slot = lv.slots[ty * lv.tiles_u + tx];
    const Tile* tile = slot.tile.load(std::memory_order_acquire);
    if (!tile) tile = bake(lv, tx, ty, slot, source);
    if (slot.last_pass.load(std::memory_order_relaxed) != pass_) slot.last_pass.store(pass_, std::memory_order_relaxed);
    const uint16_t* p = tile->texels + (iy & (kTileTexels - 1)) * kTileStride + (ix & (kTileTexels - 1));
    const float p00 = p[0], p01 = p[1], p10 = p[kTileStride], p11 = p[kTileStride + 1];
    const float top = p00 + (p01 - p00) * fx;
    const float bottom = p10 + (p11 - p10) * fx;
    return top + (bottom - top) * fy;  // a texel code (see decode)
  }
  static float decode(float code) { return code * (1.0f / kCodeScale) + kCodeMin; }
  static uint16_t encode(float albedo) {
    const float code = (albedo - kCodeMin) * kCodeScale + 0.5f;
    return static_cast<uint16_t>(code > 0.0f ? (code < 65535.0f ? code : 65535.0f) : 0.0f);
  }

  // Bakes tile (tx, ty) of a level and publishes it in `slot` (or returns the one another thread published).
  template <typename Source>
#if defined(__GNUC__)
  __attribute__((noinline))
#endif
  const Tile*
  bake(const Level& lv, int tx, int ty, Slot& slot, const Source& source) const {
    const int i0 = tx << kTileShift, j0 = ty << kTileShift;
    const int nu = std::min(kTileTexels, lv.texels_u - i0) + 1, nv = std::min(kTileTexels, lv.texels_v - j0) + 1;
    auto tile = std::make_unique<Tile>();
    const float t = lv.texel_m;
    for (int j = 0; j < nv; ++j) {
      const float v = (static_cast<float>(j0 + j) + 0.5f) * t;
      uint16_t* row = tile->texels + j * kTileStride;
      for (int i = 0; i < nu; ++i)
        row[i] = encode(source((static_cast<float>(i0 + i) + 0.5f) * t, v, kBakeFootprint * t));
    }
    return publish(std::move(tile), static_cast<uint64_t>(nu) * static_cast<uint64_t>(nv), slot);
  }
  const Tile* publish(std::unique_ptr<Tile> tile, uint64_t texels, Slot& slot) const;

  float base_texel_m_, inv_base_texel_m_;
  uint32_t keep_passes_;
  uint32_t pass_ = 1;
  std::unique_ptr<std::atomic<Surface*>[]> surfaces_;
  std::size_t surface_count_;
  // Tiles held (for eviction), guarded by mutex_ together with the statistics.
  mutable std::mutex mutex_;
  mutable std::vector<Slot*> held_;
  mutable uint64_t texels_baked_ = 0, tiles_freed_ = 0;
};

}  // namespace agvslam::sim
