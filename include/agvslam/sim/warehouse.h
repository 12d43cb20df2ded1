#pragma once
// The static warehouse: a closed hall (analytic floor, walls and ceiling) filled with axis-aligned boxes
// (rack uprights, beams, decks, pallets, cartons, wrapped loads, crates, pillars), plus painted floor marks and
// wall features. Boxes are indexed by a 2-D uniform grid over the floor whose cells list their boxes sorted by
// height, so the ray caster walks the grid with a DDA and only tests boxes at the ray's height.
//
// Map frame (internal to the simulator): x east, y north, z up, floor at z = 0; the hall is
// [0, width] x [0, depth] x [0, height]. The layout is generated from its own seed (RngStream::kLayout and
// kTextures), independent of the people and vehicles.

#include <array>
#include <cstdint>
#include <vector>

#include "agvslam/sim/geometry.h"

namespace agvslam::sim {

enum class Material : uint8_t {
  kFloor,
  kWall,
  kCeiling,
  kRackUpright,
  kRackBeam,
  kRackBrace,
  kShelfDeck,
  kCarton,
  kPallet,
  kPalletStack,
  kWrappedLoad,
  kCrate,
  kPillar,
  kDockLeveller,
  // Actors.
  kPersonShirt,
  kPersonTrousers,
  kPersonSkin,
  kPersonHead,
  kVehicleBody,
  kVehicleDark,
  kVehicleMetal,
  kVehicleGuard,
  kTyre,
};

struct StaticBox {
  V3 lo, hi;
  Material material = Material::kCarton;
  uint8_t variant = 0;  // material-specific (e.g. which face is the aisle side)
  uint32_t seed = 0;    // texture seed
};

// A painted rectangle on the floor (lane lines, hatched zones, stop lines).
struct FloorMark {
  enum class Kind : uint8_t { kSolid, kDashedX, kDashedY, kHatched };
  float x0, y0, x1, y1;
  Kind kind = Kind::kSolid;
  float shade = 0.82f;  // albedo of the paint
};

// A feature on one of the four walls: u = horizontal coordinate along the wall (m), z = height.
struct WallFeature {
  enum class Kind : uint8_t { kRollerDoor, kPoster, kSign, kCabinet, kWindow, kPipe };
  int wall = 0;  // 0: y = 0 (south), 1: x = width (east), 2: y = depth (north), 3: x = 0 (west)
  float u0, u1, z0, z1;
  Kind kind = Kind::kPoster;
  uint32_t seed = 0;
};

// Where the scenarios drive and walk (all in the map frame, metres).
struct WarehouseLayout {
  // Main aisle for the straight-line scenarios: the AGV drives along +x at y = line_y from x = line_x_start.
  double line_y = 4.6;
  double line_x_start = 3.0;
  double line_length_m = 13.6;
  double line_max_start_offset_m = 3.0;
  std::vector<double> line_cross_aisles_x;  // centres of the cross-aisles through the rows beside the aisle
  double line_cross_half_width_m = 1.35;
  double north_corridor_y = 9.15;  // service corridors parallel to the main aisle
  double south_corridor_y = 0.95;
  double line_exit_x = 24.95;  // a cross-aisle through the south row, beyond the rows on the north side

  // Loop: a rounded rectangle (corner arcs of loop_corner_radius_m) around an inner rack block.
  double loop_x0 = 26.0, loop_y0 = 13.0, loop_x1 = 34.8, loop_y1 = 19.4;
  double loop_corner_radius_m = 1.0;
  double loop_cross_x = 30.4;  // cross-aisle through the inner block (crosses both long legs)
  double loop_cross_half_width_m = 0.8;
  double loop_outer_north_y = 21.0;  // walkable strip in front of the north outer row
  double loop_north_area_y = 24.0;   // open strip between the north outer row and the north wall
  double east_lane_x = 37.1;         // vehicle lane east of the loop

  // Open staging area (scene1): the stationary AGV stands at (stage_x, stage_y) looking north (+y).
  double stage_x = 10.5, stage_y = 10.8;
  double stage_cross_y = 16.0;  // where people cross in front of it
};

// 2-D grid over the floor; each cell's boxes are listed per height slab (a box is listed in every slab it
// overlaps), so a near-horizontal ray only tests the boxes at its height. Empty cells store their Chebyshev
// distance (in cells) to the nearest occupied cell, letting the traversal jump across open floor.
struct FloorGrid {
  float cell_m = 0.5f;
  float slab_m = 0.5f;
  int nx = 0, ny = 0, nz = 0;
  std::vector<uint32_t> slab_begin;  // size nx * ny * nz + 1 (CSR offsets into box_index), index (cell * nz + slab)
  std::vector<uint32_t> box_index;
  std::vector<float> cell_top_z;      // highest box top in the cell (-inf when empty)
  std::vector<uint8_t> empty_radius;  // 0: occupied; k: every cell within Chebyshev distance k - 1 is empty
};

struct Warehouse {
  float width_m = 40.0f, depth_m = 26.0f, height_m = 8.0f;
  std::vector<StaticBox> boxes;
  std::vector<FloorMark> floor_marks;
  std::vector<WallFeature> wall_features;
  uint32_t floor_seed = 1, wall_seed = 2, ceiling_seed = 3;
  WarehouseLayout layout;
  FloorGrid grid;

  // (Re)builds the grid from `boxes`.
  void build_grid(float cell_m = 0.5f, float slab_m = 0.5f);
  // True if the floor rectangle (with `margin`) overlaps any box lower than max_z.
  bool footprint_occupied(float x0, float y0, float x1, float y1, float margin, float max_z = 1e9f) const;
};

// Generates the warehouse for a layout seed (deterministic; the grid is built).
Warehouse generate_warehouse(uint64_t layout_seed);

}  // namespace agvslam::sim
