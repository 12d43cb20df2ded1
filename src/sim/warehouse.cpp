#include "agvslam/sim/warehouse.h"

#include <algorithm>
#include <cmath>

#include "agvslam/sim/random.h"

namespace agvslam::sim {

void Warehouse::build_grid(float cell_m, float slab_m) {
  grid.cell_m = cell_m;
  grid.slab_m = slab_m;
  grid.nx = std::max(1, static_cast<int>(std::ceil(width_m / cell_m)));
  grid.ny = std::max(1, static_cast<int>(std::ceil(depth_m / cell_m)));
  grid.nz = std::max(1, static_cast<int>(std::ceil(height_m / slab_m)));
  const std::size_t n_cells = static_cast<std::size_t>(grid.nx) * static_cast<std::size_t>(grid.ny);
  const std::size_t nz = static_cast<std::size_t>(grid.nz);
  std::vector<std::vector<uint32_t>> lists(n_cells * nz);
  grid.cell_top_z.assign(n_cells, -kInfinity);
  auto cell_range = [](float lo, float hi, float size, int n, int& i0, int& i1) {
    i0 = std::clamp(static_cast<int>(std::floor(lo / size)), 0, n - 1);
    i1 = std::clamp(static_cast<int>(std::floor((hi - 1e-5f) / size)), 0, n - 1);
  };
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    int ix0, ix1, iy0, iy1, iz0, iz1;
    cell_range(boxes[b].lo.x, boxes[b].hi.x, cell_m, grid.nx, ix0, ix1);
    cell_range(boxes[b].lo.y, boxes[b].hi.y, cell_m, grid.ny, iy0, iy1);
    cell_range(boxes[b].lo.z, boxes[b].hi.z, slab_m, grid.nz, iz0, iz1);
    for (int iy = iy0; iy <= iy1; ++iy)
      for (int ix = ix0; ix <= ix1; ++ix) {
        const std::size_t c =
            static_cast<std::size_t>(iy) * static_cast<std::size_t>(grid.nx) + static_cast<std::size_t>(ix);
        grid.cell_top_z[c] = std::max(grid.cell_top_z[c], boxes[b].hi.z);
        for (int iz = iz0; iz <= iz1; ++iz)
          lists[c * nz + static_cast<std::size_t>(iz)].push_back(static_cast<uint32_t>(b));
      }
  }
  grid.slab_begin.assign(n_cells * nz + 1, 0);
  grid.box_index.clear();
  for (std::size_t i = 0; i < lists.size(); ++i) {
    grid.slab_begin[i] = static_cast<uint32_t>(grid.box_index.size());
    for (uint32_t b : lists[i]) grid.box_index.push_back(b);
  }
  grid.slab_begin[n_cells * nz] = static_cast<uint32_t>(grid.box_index.size());

  // Chebyshev distance to the nearest occupied cell (two-pass chamfer transform), capped at 255.
  const int nx = grid.nx, ny = grid.ny;
  std::vector<int> dist(n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) dist[c] = grid.cell_top_z[c] > -kInfinity ? 0 : 100000;
  auto at = [&](int x, int y) -> int& {
    return dist[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x)];
  };
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      int& d = at(x, y);
      if (x > 0) d = std::min(d, at(x - 1, y) + 1);
      if (y > 0) {
        d = std::min(d, at(x, y - 1) + 1);
        if (x > 0) d = std::min(d, at(x - 1, y - 1) + 1);
        if (x + 1 < nx) d = std::min(d, at(x + 1, y - 1) + 1);
      }
    }
  for (int y = ny - 1; y >= 0; --y)
    for (int x = nx - 1; x >= 0; --x) {
      int& d = at(x, y);
      if (x + 1 < nx) d = std::min(d, at(x + 1, y) + 1);
      if (y + 1 < ny) {
        d = std::min(d, at(x, y + 1) + 1);
        if (x + 1 < nx) d = std::min(d, at(x + 1, y + 1) + 1);
        if (x > 0) d = std::min(d, at(x - 1, y + 1) + 1);
      }
    }
  grid.empty_radius.resize(n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) grid.empty_radius[c] = static_cast<uint8_t>(std::min(dist[c], 255));
}

bool Warehouse::footprint_occupied(float x0, float y0, float x1, float y1, float margin, float max_z) const {
  for (const auto& b : boxes) {
    if (b.lo.z >= max_z) continue;
    if (b.hi.x + margin > x0 && b.lo.x - margin < x1 && b.hi.y + margin > y0 && b.lo.y - margin < y1) return true;
  }
  return false;
}

namespace {

struct Rect {
  float x0, y0, x1, y1;
  bool overlaps(const Rect& o, float margin = 0) const {
    return x1 + margin > o.x0 && x0 - margin < o.x1 && y1 + margin > o.y0 && y0 - margin < o.y1;
  }
};

// A rack row: bays along `a` (x when along_x, else y), depth along `b`.
struct RackRow {
  bool along_x = true;
  float a0 = 0, a1 = 0;                       // extent along the row
  float b0 = 0, b1 = 0;                       // extent across (depth)
  std::vector<std::pair<float, float>> gaps;  // cross-aisles (along-row intervals without racking)
  std::vector<float> level_z;                 // beam tops; level 0 (the floor) is implicit
  float top_z = 5.0f;
  float bay_m = 2.7f;
  bool loads_on_floor = true;
};

class Builder {
 public:
  Builder(Warehouse& w, uint64_t layout_seed)
      : w_(w), rng_(layout_seed, RngStream::kLayout), tex_(layout_seed, RngStream::kTextures) {}

  Rng& rng() { return rng_; }

  void add_box(float x0, float y0, float z0, float x1, float y1, float z1, Material m, uint8_t variant = 0) {
    StaticBox b;
    b.lo = {std::min(x0, x1), std::min(y0, y1), std::min(z0, z1)};
    b.hi = {std::max(x0, x1), std::max(y0, y1), std::max(z0, z1)};
    b.material = m;
    b.variant = variant;
    b.seed = tex_.next_u32();
    w_.boxes.push_back(b);
  }

  // Box given in row coordinates (a along the row, b across).
  void add_box_ab(const RackRow& row, float a0, float a1, float b0, float b1, float z0, float z1, Material m,
                  uint8_t variant = 0) {
    if (row.along_x)
      add_box(a0, b0, z0, a1, b1, z1, m, variant);
    else
      add_box(b0, a0, z0, b1, a1, z1, m, variant);
  }

  // A pallet with its load on [a0, a1] x [b0, b1] at height z (floor or shelf), at most max_h tall in total.
  void add_pallet_load(const RackRow& frame, float a0, float a1, float b0, float b1, float z, float max_h) {
    const float pallet_h = 0.144f;
    if (max_h < pallet_h + 0.1f) return;
    const double kind = rng_.uniform();
    // The pallet itself: variant 1 = planks run along a (fork openings on the b faces).
    add_box_ab(frame, a0, a1, b0, b1, z, z + pallet_h, Material::kPallet, frame.along_x ? 0 : 1);
    const float top = z + pallet_h;
    const float room = max_h - pallet_h;
    if (kind < 0.08) return;  // empty pallet
    if (kind < 0.35) {        // stretch-wrapped load
      const float h = std::min(room, static_cast<float>(rng_.uniform(0.55, 1.45)));
      const float inset = static_cast<float>(rng_.uniform(0.0, 0.05));
      add_box_ab(frame, a0 + inset, a1 - inset, b0 + inset, b1 - inset, top, top + h, Material::kWrappedLoad);
      return;
    }
    if (kind < 0.47) {  // stacked plastic crates
      const int na = (a1 - a0) > 1.0f ? 2 : 1;
      const int nb = (b1 - b0) > 1.0f ? 2 : 1;
      const float ca = (a1 - a0) / static_cast<float>(na), cb = (b1 - b0) / static_cast<float>(nb);
      const float crate_h = static_cast<float>(rng_.uniform(0.22, 0.34));
      for (int i = 0; i < na; ++i)
        for (int j = 0; j < nb; ++j) {
          const int layers = std::min(static_cast<int>(room / crate_h), rng_.uniform_int(1, 5));
          for (int k = 0; k < layers; ++k) {
            const float zz = top + static_cast<float>(k) * crate_h;
            add_box_ab(frame, a0 + ca * static_cast<float>(i) + 0.01f, a0 + ca * static_cast<float>(i + 1) - 0.01f,
                       b0 + cb * static_cast<float>(j) + 0.01f, b0 + cb * static_cast<float>(j + 1) - 0.01f, zz,
                       zz + crate_h - 0.005f, Material::kCrate);
          }
        }
      return;
    }
    // Cartons: a grid per layer with jitter, sometimes incomplete top layers.
    const int na = rng_.uniform_int(1, (a1 - a0) > 1.0f ? 3 : 2);
    const int nb = rng_.uniform_int(1, (b1 - b0) > 1.0f ? 3 : 2);
    const float ca = (a1 - a0) / static_cast<float>(na), cb = (b1 - b0) / static_cast<float>(nb);
    float zz = top;
    const int max_layers = rng_.uniform_int(1, 4);
    for (int layer = 0; layer < max_layers; ++layer) {
      const float h = static_cast<float>(rng_.uniform(0.22, 0.48));
      if (zz + h > z + max_h) break;
      const bool top_layer = layer == max_layers - 1;
      for (int i = 0; i < na; ++i)
        for (int j = 0; j < nb; ++j) {
          if (rng_.chance(top_layer ? 0.3 : 0.06)) continue;
          const float ja = static_cast<float>(rng_.uniform(0.005, 0.035));
          const float jb = static_cast<float>(rng_.uniform(0.005, 0.035));
          const float sa = static_cast<float>(rng_.uniform(-0.015, 0.015));
          const float sb = static_cast<float>(rng_.uniform(-0.015, 0.015));
          const float hh = h - static_cast<float>(rng_.uniform(0.0, 0.03));
          add_box_ab(frame, a0 + ca * static_cast<float>(i) + ja + sa, a0 + ca * static_cast<float>(i + 1) - ja + sa,
                     b0 + cb * static_cast<float>(j) + jb + sb, b0 + cb * static_cast<float>(j + 1) - jb + sb, zz,
                     zz + hh, Material::kCarton);
        }
      zz += h;
    }
  }

  void add_rack_row(const RackRow& row) {
    // Segments of racking between the gaps.
    std::vector<std::pair<float, float>> segments;
    float start = row.a0;
    std::vector<std::pair<float, float>> gaps = row.gaps;
    std::sort(gaps.begin(), gaps.end());
    for (const auto& g : gaps) {
      if (g.first > start + 0.5f) segments.emplace_back(start, std::min(g.first, row.a1));
      start = std::max(start, g.second);
    }
    if (row.a1 > start + 0.5f) segments.emplace_back(start, row.a1);

    const float upright_w = 0.08f, upright_d = 0.09f, beam_h = 0.12f, beam_d = 0.06f;
    const bool has_guard = rng_.chance(0.6);
    for (const auto& seg : segments) {
      const int n_bays = std::max(1, static_cast<int>(std::lround((seg.second - seg.first) / row.bay_m)));
      const float bay = (seg.second - seg.first) / static_cast<float>(n_bays);
      for (int k = 0; k <= n_bays; ++k) {
        const float a = std::clamp(seg.first + bay * static_cast<float>(k), seg.first + upright_w * 0.5f,
                                   seg.second - upright_w * 0.5f);
        const bool end_frame = k == 0 || k == n_bays;
        const uint8_t variant = (end_frame && has_guard) ? 1 : 0;  // 1: painted guard at the foot
        add_box_ab(row, a - upright_w * 0.5f, a + upright_w * 0.5f, row.b0, row.b0 + upright_d, 0, row.top_z,
                   Material::kRackUpright, variant);
        add_box_ab(row, a - upright_w * 0.5f, a + upright_w * 0.5f, row.b1 - upright_d, row.b1, 0, row.top_z,
                   Material::kRackUpright, variant);
        // Horizontal bracing of the side frame.
        for (float zb = 0.35f; zb < row.top_z - 0.3f; zb += 1.1f)
          add_box_ab(row, a - 0.018f, a + 0.018f, row.b0 + upright_d, row.b1 - upright_d, zb, zb + 0.035f,
                     Material::kRackBrace);
      }
      for (int k = 0; k < n_bays; ++k) {
        const float left = seg.first + bay * static_cast<float>(k) + upright_w * 0.5f;
        const float right = seg.first + bay * static_cast<float>(k + 1) - upright_w * 0.5f;
        // Levels: 0 = floor, then the beams.
        for (std::size_t level = 0; level <= row.level_z.size(); ++level) {
          const float z = level == 0 ? 0.0f : row.level_z[level - 1];
          if (level > 0) {
            add_box_ab(row, left, right, row.b0, row.b0 + beam_d, z - beam_h, z, Material::kRackBeam);
            add_box_ab(row, left, right, row.b1 - beam_d, row.b1, z - beam_h, z, Material::kRackBeam);
            add_box_ab(row, left, right, row.b0 + beam_d, row.b1 - beam_d, z - 0.035f, z - 0.005f,
                       Material::kShelfDeck);
          }
          if (level == 0 && !row.loads_on_floor) continue;
          const float next = level < row.level_z.size() ? row.level_z[level] - beam_h - 0.08f : z + 1.3f;
          const float max_h = next - z;
          const int n_pallets = std::max(1, static_cast<int>((right - left - 0.1f) / 0.86f));
          const float slot = (right - left) / static_cast<float>(n_pallets);
          for (int p = 0; p < n_pallets; ++p) {
            if (rng_.chance(0.16)) continue;
            const float pa =
                left + slot * (static_cast<float>(p) + 0.5f) + static_cast<float>(rng_.uniform(-0.03, 0.03));
            const float pb = 0.5f * (row.b0 + row.b1) + static_cast<float>(rng_.uniform(-0.03, 0.03));
            const float half_depth = 0.5f * (row.b1 - row.b0) + 0.05f;  // pallets overhang the beams a little
            add_pallet_load(row, pa - 0.4f, pa + 0.4f, pb - half_depth, pb + half_depth, z + (level == 0 ? 0 : 0.0f),
                            max_h);
          }
        }
      }
    }
  }

  RackRow make_row(bool along_x, float a0, float a1, float b0, float b1) {
    RackRow row;
    row.along_x = along_x;
    row.a0 = a0;
    row.a1 = a1;
    row.b0 = b0;
    row.b1 = b1;
    const int levels = rng_.uniform_int(3, 4);
    float z = static_cast<float>(rng_.uniform(1.3, 1.6));
    for (int i = 0; i < levels; ++i) {
      row.level_z.push_back(z);
      z += static_cast<float>(rng_.uniform(1.25, 1.55));
    }
    row.top_z = row.level_z.back() + static_cast<float>(rng_.uniform(0.8, 1.1));
    return row;
  }

  // Floor-standing goods (no rack) at a free spot inside `area`, avoiding the reserved rectangles.
  bool place_floor_item(const Rect& area, const std::vector<Rect>& reserved) {
    for (int attempt = 0; attempt < 40; ++attempt) {
      const bool along_x = rng_.chance(0.5);
      const int kind = rng_.uniform_int(0, 9);
      float sx = along_x ? 1.2f : 0.8f, sy = along_x ? 0.8f : 1.2f;
      if (kind >= 8) {  // a 2 x 1 block of pallets side by side
        if (along_x)
          sy *= 2.0f;
        else
          sx *= 2.0f;
      }
      const float x0 = static_cast<float>(rng_.uniform(area.x0, area.x1 - sx));
      const float y0 = static_cast<float>(rng_.uniform(area.y0, area.y1 - sy));
      const Rect r{x0, y0, x0 + sx, y0 + sy};
      if (r.x0 < area.x0 || r.y0 < area.y0 || r.x1 > area.x1 || r.y1 > area.y1) continue;
      bool blocked = false;
      for (const auto& res : reserved)
        if (r.overlaps(res, 0.15f)) blocked = true;
      if (blocked || w_.footprint_occupied(r.x0, r.y0, r.x1, r.y1, 0.12f)) continue;
      RackRow frame;
      frame.along_x = true;
      if (kind <= 2) {  // stack of empty pallets
        const int n = rng_.uniform_int(3, 12);
        add_box(r.x0, r.y0, 0, r.x1, r.y1, 0.144f * static_cast<float>(n), Material::kPalletStack, along_x ? 0 : 1);
      } else if (kind >= 8) {
        const float mx = along_x ? 0 : 0.8f, my = along_x ? 0.8f : 0;
        add_pallet_load(frame, r.x0, r.x0 + (along_x ? 1.2f : 0.8f), r.y0, r.y0 + (along_x ? 0.8f : 1.2f), 0,
                        static_cast<float>(rng_.uniform(0.9, 2.0)));
        add_pallet_load(frame, r.x0 + mx, r.x1, r.y0 + my, r.y1, 0, static_cast<float>(rng_.uniform(0.9, 2.0)));
      } else {
        const float h = static_cast<float>(rng_.uniform(0.8, 2.1));
        add_pallet_load(frame, r.x0, r.x1, r.y0, r.y1, 0, h);
        // Sometimes a second loaded pallet on top of a wrapped one.
        const StaticBox& last = w_.boxes.back();
        if (last.material == Material::kWrappedLoad && last.hi.z < 1.3f && rng_.chance(0.5))
          add_pallet_load(frame, r.x0, r.x1, r.y0, r.y1, last.hi.z, 1.2f);
      }
      return true;
    }
    return false;
  }

 private:
  Warehouse& w_;
  Rng rng_;
  Rng tex_;
};

}  // namespace

Warehouse generate_warehouse(uint64_t layout_seed) {
  Warehouse w;
  Builder b(w, layout_seed);
  Rng& rng = b.rng();
  WarehouseLayout& L = w.layout;
  w.floor_seed = rng.next_u32();
  w.wall_seed = rng.next_u32();
  w.ceiling_seed = rng.next_u32();

  // ---- Randomised structure -------------------------------------------------------------------------------
  const float bay = 2.7f;
  const float row_x0 = 2.0f;
  const int g1 = rng.uniform_int(1, 2);
  const int g2 = g1 == 2 ? 4 : rng.uniform_int(3, 4);
  const int g3 = 6;
  auto bay_interval = [&](int k) {
    return std::make_pair(row_x0 + bay * static_cast<float>(k), row_x0 + bay * static_cast<float>(k + 1));
  };
  L.line_cross_aisles_x.clear();
  for (int g : {g1, g2, g3}) L.line_cross_aisles_x.push_back(row_x0 + bay * (static_cast<float>(g) + 0.5f));
  L.line_cross_half_width_m = 0.5 * bay;
  L.line_exit_x = row_x0 + bay * 8.5f;
  L.loop_cross_x = rng.uniform(29.9, 30.9);
  L.stage_x = rng.uniform(9.5, 11.5);
  const float cross = static_cast<float>(L.loop_cross_x);
  const float cross_hw = static_cast<float>(L.loop_cross_half_width_m);

  // ---- Rack rows ----------------------------------------------------------------------------------------------
  {  // South row along the wall, both faces open (aisle and service corridor).
    RackRow row = b.make_row(true, row_x0, row_x0 + 12 * bay, 1.9f, 3.0f);
    for (int g : {g1, g2, g3, 8}) row.gaps.push_back(bay_interval(g));
    b.add_rack_row(row);
  }
  {  // North side of the main aisle: two rows back to back.
    RackRow row = b.make_row(true, row_x0, row_x0 + 7 * bay, 6.2f, 7.3f);
    for (int g : {g1, g2, g3}) row.gaps.push_back(bay_interval(g));
    b.add_rack_row(row);
    RackRow back = row;
    back.b0 = 7.3f;
    back.b1 = 8.4f;
    b.add_rack_row(back);
  }
  {  // Loop: inner double block (split by the cross-aisle), outer rows north and south, west row.
    for (float y0 : {15.1f, 16.2f}) {
      RackRow row = b.make_row(true, 27.6f, 33.2f, y0, y0 + 1.1f);
      row.gaps.push_back({cross - cross_hw, cross + cross_hw});
      row.bay_m = 2.5f;
      b.add_rack_row(row);
    }
    RackRow south = b.make_row(true, 23.0f, 35.9f, 9.9f, 11.0f);
    south.gaps.push_back({cross - cross_hw, cross + cross_hw});
    b.add_rack_row(south);
    RackRow north = b.make_row(true, 23.0f, 35.9f, 21.4f, 22.5f);
    north.gaps.push_back({cross - cross_hw, cross + cross_hw});
    b.add_rack_row(north);
    RackRow west = b.make_row(false, 12.0f, 20.1f, 21.9f, 23.0f);
    b.add_rack_row(west);
  }
  {  // Along the north wall of the staging area.
    RackRow row = b.make_row(true, row_x0, row_x0 + 7 * bay, 24.6f, 25.7f);
    b.add_rack_row(row);
  }

  // ---- Reserved floor (routes, aisles, walkways) ----------------------------------------------------------------
  std::vector<Rect> reserved = {
      {1.0f, 3.1f, 37.3f, 6.0f},    // main aisle (the line route and the view along it)
      {0.0f, 8.45f, 39.6f, 9.85f},  // north service corridor
      {0.0f, 0.0f, 40.0f, 1.85f},   // south service corridor
      {static_cast<float>(L.loop_x0) - 1.5f, static_cast<float>(L.loop_y0) - 1.5f, static_cast<float>(L.loop_x1) + 1.5f,
       static_cast<float>(L.loop_y1) + 1.5f},                           // loop ring
      {cross - cross_hw - 0.1f, 8.4f, cross + cross_hw + 0.1f, 25.9f},  // loop cross-aisle
      {21.5f, 23.2f, 39.0f, 24.8f},                                     // walkway north of the loop
      {21.5f, 20.2f, 36.0f, 21.35f},                                    // strip in front of the north outer row
      {36.0f, 8.4f, 38.2f, 25.2f},                                      // east vehicle lane
      {static_cast<float>(L.stage_x) - 4.5f, 10.0f, static_cast<float>(L.stage_x) + 4.5f, 21.5f},   // scene1 view
      {static_cast<float>(L.stage_x) - 10.5f, 14.6f, static_cast<float>(L.stage_x) + 2.5f, 21.0f},  // scene1 walk
  };
  for (double x : L.line_cross_aisles_x)
    reserved.push_back({static_cast<float>(x) - 1.3f, 0.0f, static_cast<float>(x) + 1.3f, 9.9f});
  reserved.push_back({static_cast<float>(L.line_exit_x) - 1.3f, 0.0f, static_cast<float>(L.line_exit_x) + 1.3f, 9.9f});

  // ---- Pillars --------------------------------------------------------------------------------------------------
  for (float py : {12.4f, 20.6f, 7.2f})
    for (float px : {4.0f, 12.0f, 20.0f, 28.0f, 36.0f, 39.0f}) {
      const Rect r{px - 0.2f, py - 0.2f, px + 0.2f, py + 0.2f};
      bool blocked = false;
      for (const auto& res : reserved)
        if (r.overlaps(res, 0.3f)) blocked = true;
      if (blocked || w.footprint_occupied(r.x0, r.y0, r.x1, r.y1, 0.3f)) continue;
      b.add_box(r.x0, r.y0, 0, r.x1, r.y1, w.height_m, Material::kPillar);
    }

  // ---- Floor-standing goods ------------------------------------------------------------------------------------
  const float stage_x = static_cast<float>(L.stage_x);
  const std::vector<std::pair<Rect, int>> areas = {
      {{0.4f, 21.6f, 21.4f, 24.3f}, 16},            // staging area: block-stacked goods behind the walkway
      {{0.4f, 10.0f, stage_x - 4.6f, 14.5f}, 7},    // ... left of the stationary AGV's view
      {{stage_x + 4.6f, 10.0f, 21.4f, 24.3f}, 14},  // ... right of it
      {{0.4f, 10.0f, 21.4f, 24.3f}, 10},            // ... anywhere free
      {{21.2f, 6.0f, 39.7f, 8.4f}, 10},             // east of the north rows
      {{37.3f, 3.0f, 39.7f, 6.2f}, 3},              // end of the main aisle, against the east wall
      {{38.2f, 9.9f, 39.8f, 25.8f}, 9},             // along the east wall
      {{34.5f, 1.9f, 39.8f, 3.05f}, 3},             // south-east corner
      {{21.4f, 24.9f, 39.8f, 25.8f}, 5},            // north wall beside the loop
  };
  for (const auto& [area, count] : areas)
    for (int i = 0; i < count; ++i) b.place_floor_item(area, reserved);

  // ---- Floor marks -----------------------------------------------------------------------------------------------
  using FK = FloorMark::Kind;
  auto mark = [&](float x0, float y0, float x1, float y1, FK kind, float shade = 0.82f) {
    w.floor_marks.push_back({std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1), kind, shade});
  };
  const float ly = static_cast<float>(L.line_y);
  mark(1.0f, ly - 1.45f, 37.0f, ly - 1.37f, FK::kSolid);  // aisle edge lines
  mark(1.0f, ly + 1.37f, 37.0f, ly + 1.45f, FK::kSolid);
  mark(1.0f, ly - 0.04f, 37.0f, ly + 0.04f, FK::kDashedX, 0.86f);  // dashed guide line
  for (double x : L.line_cross_aisles_x) {                         // stop lines where cross-aisles meet the main aisle
    const float cx = static_cast<float>(x);
    mark(cx - 1.2f, ly + 1.55f, cx + 1.2f, ly + 1.65f, FK::kSolid, 0.9f);
    mark(cx - 1.2f, ly - 1.65f, cx + 1.2f, ly - 1.55f, FK::kSolid, 0.9f);
  }
  {  // pedestrian crossing (zebra) at one cross-aisle
    const float cx = static_cast<float>(L.line_cross_aisles_x[1]);
    for (int i = 0; i < 6; ++i) {
      const float y0 = ly - 1.3f + 0.45f * static_cast<float>(i);
      mark(cx - 0.9f, y0, cx + 0.9f, y0 + 0.22f, FK::kSolid, 0.88f);
    }
  }
  {  // loop lanes: lines 1.8 m either side of the centre line, and a hatched zone at the start
    const float x0 = static_cast<float>(L.loop_x0), x1 = static_cast<float>(L.loop_x1);
    const float y0 = static_cast<float>(L.loop_y0), y1 = static_cast<float>(L.loop_y1);
    mark(x0 - 1.0f, y0 - 1.85f, x1 + 1.0f, y0 - 1.77f, FK::kSolid);
    mark(x0 - 1.0f, y1 + 1.77f, x1 + 1.0f, y1 + 1.85f, FK::kSolid);
    mark(x1 + 1.45f, y0 - 1.0f, x1 + 1.53f, y1 + 1.0f, FK::kSolid);
    mark(x0 + 1.2f, y0 - 0.04f, x1 - 1.2f, y0 + 0.04f, FK::kDashedX, 0.86f);
    mark(x0 + 1.2f, y1 - 0.04f, x1 - 1.2f, y1 + 0.04f, FK::kDashedX, 0.86f);
    mark(x1 - 0.04f, y0 + 1.2f, x1 + 0.04f, y1 - 1.2f, FK::kDashedY, 0.86f);
    mark(x0 - 0.04f, y0 + 1.2f, x0 + 0.04f, y1 - 1.2f, FK::kDashedY, 0.86f);
    mark(cross - 0.7f, y0 + 1.5f, cross + 0.7f, y0 + 1.95f, FK::kHatched);
    mark(cross - 0.7f, y1 - 1.95f, cross + 0.7f, y1 - 1.5f, FK::kHatched);
  }
  {  // staging area: parking boxes and a hatched keep-clear zone
    const float sx = static_cast<float>(L.stage_x);
    mark(sx - 0.6f, 10.15f, sx + 0.6f, 10.23f, FK::kSolid);
    mark(sx - 0.64f, 10.15f, sx - 0.56f, 11.6f, FK::kSolid);
    mark(sx + 0.56f, 10.15f, sx + 0.64f, 11.6f, FK::kSolid);
    mark(sx - 3.5f, 12.6f, sx - 1.5f, 13.8f, FK::kHatched);
    mark(sx + 1.0f, 18.2f, sx + 3.6f, 19.0f, FK::kHatched);
    mark(1.0f, 14.3f, 21.0f, 14.38f, FK::kSolid);
    mark(1.0f, 21.3f, 21.0f, 21.38f, FK::kSolid);
  }
  mark(36.05f, 9.0f, 36.13f, 25.0f, FK::kSolid);  // east lane
  mark(38.07f, 9.0f, 38.15f, 25.0f, FK::kSolid);

  // ---- Wall features -------------------------------------------------------------------------------------------
  const float wall_len[4] = {w.width_m, w.depth_m, w.width_m, w.depth_m};
  for (int wall = 0; wall < 4; ++wall) {
    std::vector<std::pair<float, float>> used;
    auto free_span = [&](float u0, float u1) {
      for (const auto& s : used)
        if (u1 + 0.3f > s.first && u0 - 0.3f < s.second) return false;
      return true;
    };
    auto add = [&](WallFeature::Kind kind, float width, float z0, float z1, int tries) {
      for (int t = 0; t < tries; ++t) {
        const float u0 = static_cast<float>(rng.uniform(0.5, wall_len[wall] - width - 0.5));
        if (!free_span(u0, u0 + width)) continue;
        used.emplace_back(u0, u0 + width);
        WallFeature f;
        f.wall = wall;
        f.u0 = u0;
        f.u1 = u0 + width;
        f.z0 = z0;
        f.z1 = z1;
        f.kind = kind;
        f.seed = rng.next_u32();
        w.wall_features.push_back(f);
        return;
      }
    };
    using WK = WallFeature::Kind;
    if (wall == 1 || wall == 2) {
      for (int i = 0; i < 2; ++i)
        add(WK::kRollerDoor, static_cast<float>(rng.uniform(3.2, 4.2)), 0.0f, static_cast<float>(rng.uniform(4.0, 4.8)),
            20);
    }
    const int n_posters = rng.uniform_int(4, 7);
    for (int i = 0; i < n_posters; ++i) {
      const float pw = static_cast<float>(rng.uniform(0.5, 1.2));
      const float z0 = static_cast<float>(rng.uniform(1.3, 2.2));
      add(WK::kPoster, pw, z0, z0 + pw * static_cast<float>(rng.uniform(0.7, 1.45)), 20);
    }
    const int n_signs = rng.uniform_int(3, 6);
    for (int i = 0; i < n_signs; ++i) {
      const float sw = static_cast<float>(rng.uniform(0.3, 0.7));
      const float z0 = static_cast<float>(rng.uniform(1.8, 3.2));
      add(WK::kSign, sw, z0, z0 + sw * static_cast<float>(rng.uniform(0.5, 1.0)), 20);
    }
    const int n_cabinets = rng.uniform_int(1, 3);
    for (int i = 0; i < n_cabinets; ++i) {
      const float cw = static_cast<float>(rng.uniform(0.4, 0.9));
      const float z0 = static_cast<float>(rng.uniform(0.9, 1.4));
      add(WK::kCabinet, cw, z0, z0 + static_cast<float>(rng.uniform(0.5, 1.0)), 20);
    }
    const int n_windows = rng.uniform_int(2, 5);
    for (int i = 0; i < n_windows; ++i) add(WK::kWindow, static_cast<float>(rng.uniform(1.5, 3.0)), 5.4f, 6.6f, 20);
  }

  w.build_grid(0.75f);
  return w;
}

}  // namespace agvslam::sim
