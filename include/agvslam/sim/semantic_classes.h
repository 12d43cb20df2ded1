#pragma once
// Semantic classes of the simulator's class labels (class_0/NNNNNN.png: one id per pixel of the left image, at the
// pixel centre, like the other ground truth). The ids are fixed; scenario.json lists them.
//
//   0 background  the ceiling (roof, trusses, light fittings) and anything not hit
//   1 floor       the floor with its painted marks and dock levellers
//   2 wall        the walls and what is fixed to them (doors, windows, posters, signs, cabinets), building pillars
//   3 rack        rack uprights, beams, braces and shelf decks
//   4 pallet/box  pallets, pallet stacks, cartons, wrapped loads and crates, wherever they are: on the floor, on a
//                 shelf, on a fork lift truck's forks, on an AGV or in a person's hands
//   5 person
//   6 forklift
//   7 agv         automated vehicles (cart AGVs, tugger trains)
//
// class_0 says what a surface is; instance_0 says which actor it belongs to. So a load on a forklift is pallet/box
// in class_0 and carries the forklift's id in instance_0, its driver is person with the forklift's id, and a
// pallet that an actor carries (scenario `pallet`) is pallet/box with its own id, in mask_0 only while it moves.

#include <cstdint>

#include "agvslam/sim/actors.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

enum class SemanticClass : uint8_t {
  kBackground = 0,
  kFloor = 1,
  kWall = 2,
  kRack = 3,
  kPalletBox = 4,
  kPerson = 5,
  kForklift = 6,
  kAgv = 7,
};
constexpr int kSemanticClassCount = 8;

// "background", "floor", "wall", "rack", "pallet/box", "person", "forklift", "agv".
inline const char* semantic_class_name(SemanticClass cls) {
  static constexpr const char* kNames[kSemanticClassCount] = {"background", "floor",  "wall",     "rack",
                                                              "pallet/box", "person", "forklift", "agv"};
  const int i = static_cast<int>(cls);
  return i < kSemanticClassCount ? kNames[i] : "unknown";
}

// Goods: what is pallet/box wherever it is.
constexpr bool is_goods(Material m) {
  return m == Material::kCarton || m == Material::kPallet || m == Material::kPalletStack ||
         m == Material::kWrappedLoad || m == Material::kCrate;
}

// Class of a static box of the warehouse.
constexpr SemanticClass static_box_class(Material m) {
  if (is_goods(m)) return SemanticClass::kPalletBox;
  switch (m) {
    case Material::kRackUpright:
    case Material::kRackBeam:
    case Material::kRackBrace:
    case Material::kShelfDeck:
      return SemanticClass::kRack;
    case Material::kDockLeveller:
      return SemanticClass::kFloor;
    default:
      return SemanticClass::kWall;  // pillars and anything else built in
  }
}

// A person's body and clothes (also a forklift driver's).
constexpr bool is_person_part(Material m) {
  return m == Material::kPersonShirt || m == Material::kPersonTrousers || m == Material::kPersonSkin ||
         m == Material::kPersonHead;
}

// Class of a part of an actor: goods are pallet/box, a person's body is person (a forklift's driver too),
// everything else is the actor's own class.
constexpr SemanticClass actor_part_class(ActorClass actor, Material part) {
  if (is_goods(part)) return SemanticClass::kPalletBox;
  if (is_person_part(part)) return SemanticClass::kPerson;
  switch (actor) {
    case ActorClass::kPerson:
      return SemanticClass::kPerson;
    case ActorClass::kForklift:
      return SemanticClass::kForklift;
    case ActorClass::kAgv:
      return SemanticClass::kAgv;
    case ActorClass::kPallet:
      return SemanticClass::kPalletBox;
  }
  return SemanticClass::kBackground;
}

}  // namespace agvslam::sim
