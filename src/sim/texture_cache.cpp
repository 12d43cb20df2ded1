#include "agvslam/sim/texture_cache.h"

#include <cmath>

namespace agvslam::sim {

TextureCache::TextureCache(std::size_t surface_count, float base_texel_m, uint32_t keep_passes)
    : base_texel_m_(base_texel_m),
      inv_base_texel_m_(1.0f / base_texel_m),
      keep_passes_(keep_passes),
      surfaces_(std::make_unique<std::atomic<Surface*>[]>(surface_count)),
      surface_count_(surface_count) {
  for (std::size_t i = 0; i < surface_count; ++i) surfaces_[i].store(nullptr, std::memory_order_relaxed);
}

TextureCache::~TextureCache() {
  for (Slot* slot : held_) delete slot->tile.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < surface_count_; ++i) delete surfaces_[i].load(std::memory_order_relaxed);
}

const TextureCache::Surface& TextureCache::create_surface(std::size_t id, float size_u, float size_v) const {
  auto s = std::make_unique<Surface>();
  std::size_t slots = 0;
  int level = 0;
  for (;; ++level) {
    Level& lv = s->levels[static_cast<std::size_t>(level)];
    lv.texel_m = std::ldexp(base_texel_m_, level);
    lv.inv_texel_m = std::ldexp(inv_base_texel_m_, -level);
    lv.texels_u = std::max(1, static_cast<int>(std::ceil(size_u * lv.inv_texel_m)));
    lv.texels_v = std::max(1, static_cast<int>(std::ceil(size_v * lv.inv_texel_m)));
    lv.tiles_u = (lv.texels_u + kTileTexels - 1) / kTileTexels;
    lv.tiles_v = (lv.texels_v + kTileTexels - 1) / kTileTexels;
    lv.x_max = static_cast<float>(lv.texels_u - 1);
    lv.y_max = static_cast<float>(lv.texels_v - 1);
    slots += static_cast<std::size_t>(lv.tiles_u) * static_cast<std::size_t>(lv.tiles_v);
    // The top level has a single texel each way (or the pyramid is as deep as it may be).
    if ((lv.texels_u == 1 && lv.texels_v == 1) || level + 1 == kMaxLevels) break;
  }
  s->top_level = level;
  s->slots = std::make_unique<Slot[]>(slots);
  std::size_t first = 0;
  for (int l = 0; l <= level; ++l) {
    Level& lv = s->levels[static_cast<std::size_t>(l)];
    lv.slots = s->slots.get() + first;
    first += static_cast<std::size_t>(lv.tiles_u) * static_cast<std::size_t>(lv.tiles_v);
  }
  Surface* expected = nullptr;
  if (surfaces_[id].compare_exchange_strong(expected, s.get(), std::memory_order_acq_rel, std::memory_order_acquire))
    return *s.release();
  return *expected;  // another thread created it first (identically)
}

const TextureCache::Tile* TextureCache::publish(std::unique_ptr<Tile> tile, uint64_t texels, Slot& slot) const {
  Tile* expected = nullptr;
  if (!slot.tile.compare_exchange_strong(expected, tile.get(), std::memory_order_acq_rel, std::memory_order_acquire))
    return expected;  // another thread baked the same texels first
  std::lock_guard<std::mutex> lock(mutex_);
  held_.push_back(&slot);
  texels_baked_ += texels;
  return tile.release();
}

void TextureCache::begin_pass() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++pass_;
  for (std::size_t i = 0; i < held_.size();) {
    Slot& slot = *held_[i];
    if (pass_ - slot.last_pass.load(std::memory_order_relaxed) > keep_passes_) {
      delete slot.tile.exchange(nullptr, std::memory_order_relaxed);
      ++tiles_freed_;
      held_[i] = held_.back();
      held_.pop_back();
    } else {
      ++i;
    }
  }
}

TextureCache::Stats TextureCache::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Stats s;
  s.tiles = held_.size();
  s.bytes = held_.size() * sizeof(Tile);
  s.texels_baked = texels_baked_;
  s.tiles_freed = tiles_freed_;
  return s;
}

}  // namespace agvslam::sim
