#pragma once
// People and vehicles that move through the warehouse.
//
// An actor follows a timed, piecewise-linear path on the floor (map frame, scenario time in seconds). Between
// two waypoints with the same position it stands still; its heading follows the direction of travel, turning
// smoothly around the waypoints, unless both waypoints of a stretch give a heading (then it turns linearly from
// one to the other: a vehicle reversing, a pallet riding on forks). Waypoints also say how far the actor's
// liftable part is raised (a forklift's forks, a carried pallet), interpolated linearly.
// A person is articulated: torso (box), head (sphere), two legs and two arms (capsules) that swing with the gait
// phase (one stride per ~1.4 m walked); a vehicle is a few oriented boxes (forklift: body, counterweight, overhead
// guard, mast, forks; AGV: a low platform with a load, or an automated tugger whose carts follow its track); a
// pallet is a pallet with its goods.
//
// "Moving" at an instant means the actor translates faster than 5 cm/s, turns faster than 3 degrees/s or lifts
// faster than 2 cm/s there; an actor standing still is present but not moving (its pixels are not in the motion
// mask).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "agvslam/sim/geometry.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

enum class ActorClass : uint8_t { kPerson, kForklift, kAgv, kPallet };
// "person", "forklift", "agv", "pallet" (objects.txt, scenario.json).
std::string to_string(ActorClass cls);

struct Waypoint {
  double t_s = 0;  // scenario time
  double x = 0, y = 0;
  // Heading (radians from +x) at this waypoint; NaN: the direction of travel.
  double yaw_rad = std::numeric_limits<double>::quiet_NaN();
  // How far the liftable part is raised, m: a forklift's forks above their travel height (0.12 m above the
  // floor; down to -0.08 to slide under a pallet), a pallet's base above the floor.
  double lift_m = 0;
};

// Goods on a pallet or a cart deck.
struct Load {
  enum class Kind : uint8_t { kNone, kWrapped, kCartons, kCrates };
  Kind kind = Kind::kNone;
  float height_m = 0.9f;  // above the pallet or deck
};

struct VehicleLook {
  float body_shade = 0.72f;  // albedo of the painted body (forklifts come yellow, orange, red, blue, grey, ...)
  Load load;                 // forklift: on its forks; pallet: on the pallet; tugger: on each cart
  uint8_t tugger_carts = 0;  // AGV: 0 a cart AGV carrying crates; n > 0 an automated tugger towing n carts
};

// How a person looks. Shades are albedos of a colour as the grey camera sees it. The default is a plain long-sleeved
// shirt without pockets, prints or folds (the least textured clothing).
struct PersonLook {
  float height_m = 1.75f;
  float build = 1.0f;  // width of shoulders and hips relative to an average body of this height
  float girth = 1.0f;  // depth of chest and belly, likewise
  float skin_shade = 0.6f, hair_shade = 0.15f;
  bool helmet = false;
  enum class Top : uint8_t { kTshirt, kLongSleeve, kJacket, kHoodie, kHiVisVest, kOveralls };
  Top top = Top::kLongSleeve;
  enum class Pattern : uint8_t { kPlain, kStripes, kChecks, kPlaid, kBlotches, kDots };
  Pattern pattern = Pattern::kPlain;
  float shirt_shade = 0.5f;       // the top
  float pattern_shade = 0.2f;     // the pattern's second colour, the trim
  float inner_shade = 0.7f;       // what shows under a vest or an open jacket
  float pattern_period_m = 0.1f;  // stripes, checks, dots
  enum Print : uint8_t { kChestLogo = 1, kBackPrint = 2, kFrontGraphic = 4, kNameBadge = 8 };
  uint8_t prints = 0;    // Print bits
  bool pockets = false;  // pockets, buttons, zips
  bool folds = false;    // creases of the fabric
  enum class Bottom : uint8_t { kWork, kJeans, kCargo, kHiVis };
  Bottom bottom = Bottom::kWork;
  float trousers_shade = 0.25f;
  float shoe_shade = 0.07f;
  enum class Carry : uint8_t { kNothing, kBox, kScanner, kPhone };
  Carry carry = Carry::kNothing;  // what the hands hold (a box in both, a scanner in the right, a phone at the ear)
  float arm_swing = 1.0f;         // relative to an average gait
};

// Derived per path segment [path[k], path[k+1]] by prepare_actor().
struct ActorSegment {
  double t0 = 0, t1 = 0, length_m = 0, dir_rad = 0;
  bool moving = false;
  double distance_before_m = 0;   // walked before this segment
  double run_t0 = 0, run_t1 = 0;  // the stretch of consecutive moving segments this one belongs to
};

struct Actor {
  int id = 1;  // > 0, unique in the scenario (the value in the object-id buffer)
  ActorClass cls = ActorClass::kPerson;
  std::string role;            // what it does in the scenario (for logs)
  std::vector<Waypoint> path;  // sorted by time; before the first / after the last it stands still
  double initial_yaw_rad = 0;  // heading before it first moves (and if it never moves)
  PersonLook look;
  VehicleLook vehicle;                 // forklifts, AGVs and pallets
  uint32_t seed = 0;                   // texture seed
  int carrier_id = 0;                  // the actor that carries this one at times (its forks), 0 = none
  std::vector<ActorSegment> segments;  // derived from `path` by prepare_actor() (recomputed when stale)
};

// Fills actor.segments from actor.path (call after changing the path; actor_state is faster with it).
void prepare_actor(Actor& actor);

struct ActorState {
  double x = 0, y = 0, yaw_rad = 0;
  double speed_mps = 0;
  bool moving = false;
  double gait_phase_rad = 0;  // persons only
  double gait_amplitude = 0;  // 0 standing .. 1 walking
  double lift_m = 0;          // see Waypoint::lift_m
  double distance_m = 0;      // travelled along the path so far
};

// The state of an actor at scenario time t_s.
ActorState actor_state(const Actor& actor, double t_s);
// Distance walked/driven along its path up to t_s.
double actor_distance_m(const Actor& actor, double t_s);
// Position and direction of travel at distance_m along the path (before its start: extended straight back from
// the first waypoint along the initial heading; beyond its end: the last waypoint). A tugger's carts follow its
// track this way.
void actor_track_point(const Actor& actor, double distance_m, double& x, double& y, double& heading_rad);

enum class PrimitiveShape : uint8_t { kBox, kSphere, kCapsule };

struct DynamicPrimitive {
  PrimitiveShape shape = PrimitiveShape::kBox;
  Material material = Material::kVehicleBody;
  V3 a;     // box centre, sphere centre or capsule start
  V3 b;     // capsule end
  V3 half;  // box half extents in the object's yaw frame
  float radius = 0;
  uint8_t part = 0;  // which body part (for texturing)
};

// One actor posed for one frame: its primitives in the map frame.
struct DynamicObject {
  int id = 0;
  ActorClass cls = ActorClass::kPerson;
  bool moving = false;
  V3 origin;  // on the floor, below the object's centre
  float cos_yaw = 1, sin_yaw = 0;
  V3 lo, hi;  // bounding box of all primitives
  std::vector<DynamicPrimitive> primitives;
  PersonLook look;
  VehicleLook vehicle;
  uint32_t seed = 0;
  float walk_phase = 0;  // gait phase (texture animation)

  // Map-frame vector expressed in the object's yaw frame (x forward, y left, z up).
  V3 to_local(const V3& p_map) const {
    const V3 d = p_map - origin;
    return {cos_yaw * d.x + sin_yaw * d.y, -sin_yaw * d.x + cos_yaw * d.y, d.z};
  }
  V3 to_map_dir(const V3& v_local) const {
    return {cos_yaw * v_local.x - sin_yaw * v_local.y, sin_yaw * v_local.x + cos_yaw * v_local.y, v_local.z};
  }
};

// Builds the posed primitives of an actor (reuses `out`'s storage). A tugger's carts are separate objects.
void pose_actor(const Actor& actor, const ActorState& state, DynamicObject& out);
// Trailing parts posed as their own objects with the actor's id: a tugger's carts.
int trailer_count(const Actor& actor);
// Distance (m) of trailer k's centre behind the actor's origin, along its track.
double trailer_offset_m(int k);
void pose_trailer(const Actor& actor, const ActorState& state, int k, DynamicObject& out);

// Radius of a vertical cylinder around the actor's origin that contains it (for clearance checks; trailers not
// included).
double actor_radius_m(ActorClass cls);

}  // namespace agvslam::sim
