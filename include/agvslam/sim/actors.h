#pragma once
// People and vehicles that move through the warehouse.
//
// An actor follows a timed, piecewise-linear path on the floor (map frame, scenario time in seconds). Between
// two waypoints with the same position it stands still; its heading follows the direction of travel, turning
// smoothly around the waypoints. A person is articulated: torso (box), head (sphere), two legs and two arms
// (capsules) that swing with the gait phase (one stride per ~1.4 m walked); a vehicle is a few oriented boxes
// (forklift: body, counterweight, overhead guard, mast, forks; AGV: a low platform with a load).
//
// "Moving" at an instant means the actor's speed there is above 5 cm/s; an actor standing still is present
// but not moving (its pixels are not in the motion mask).

#include <cstdint>
#include <string>
#include <vector>

#include "agvslam/sim/geometry.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

enum class ActorClass : uint8_t { kPerson, kForklift, kAgv };
std::string to_string(ActorClass cls);

struct Waypoint {
  double t_s = 0;  // scenario time
  double x = 0, y = 0;
};

struct PersonLook {
  float height_m = 1.75f;
  float shirt_shade = 0.5f, trousers_shade = 0.25f, skin_shade = 0.6f, hair_shade = 0.15f;
  uint8_t shirt_pattern = 0;  // 0 plain, 1 horizontal stripes, 2 checks, 3 hi-vis vest
  bool helmet = false;
};

// Derived per path segment [path[k], path[k+1]] by prepare_actor().
struct ActorSegment {
  double t0 = 0, t1 = 0, length_m = 0, dir_rad = 0;
  bool moving = false;
  double distance_before_m = 0;  // walked before this segment
  double run_t0 = 0, run_t1 = 0; // the stretch of consecutive moving segments this one belongs to
};

struct Actor {
  int id = 1;  // > 0, unique in the scenario (the value in the object-id buffer)
  ActorClass cls = ActorClass::kPerson;
  std::string role;                // what it does in the scenario (for logs)
  std::vector<Waypoint> path;      // sorted by time; before the first / after the last it stands still
  double initial_yaw_rad = 0;      // heading before it first moves (and if it never moves)
  PersonLook look;
  uint32_t seed = 0;               // texture seed
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
};

// The state of an actor at scenario time t_s.
ActorState actor_state(const Actor& actor, double t_s);
// Distance walked/driven along its path up to t_s.
double actor_distance_m(const Actor& actor, double t_s);

enum class PrimitiveShape : uint8_t { kBox, kSphere, kCapsule };

struct DynamicPrimitive {
  PrimitiveShape shape = PrimitiveShape::kBox;
  Material material = Material::kVehicleBody;
  V3 a;        // box centre, sphere centre or capsule start
  V3 b;        // capsule end
  V3 half;     // box half extents in the object's yaw frame
  float radius = 0;
  uint8_t part = 0;  // which body part (for texturing)
};

// One actor posed for one frame: its primitives in the map frame.
struct DynamicObject {
  int id = 0;
  ActorClass cls = ActorClass::kPerson;
  bool moving = false;
  V3 origin;                    // on the floor, below the object's centre
  float cos_yaw = 1, sin_yaw = 0;
  V3 lo, hi;                    // bounding box of all primitives
  std::vector<DynamicPrimitive> primitives;
  PersonLook look;
  uint32_t seed = 0;
  float walk_phase = 0;         // gait phase (texture animation)

  // Map-frame vector expressed in the object's yaw frame (x forward, y left, z up).
  V3 to_local(const V3& p_map) const {
    const V3 d = p_map - origin;
    return {cos_yaw * d.x + sin_yaw * d.y, -sin_yaw * d.x + cos_yaw * d.y, d.z};
  }
  V3 to_map_dir(const V3& v_local) const {
    return {cos_yaw * v_local.x - sin_yaw * v_local.y, sin_yaw * v_local.x + cos_yaw * v_local.y, v_local.z};
  }
};

// Builds the posed primitives of an actor (reuses `out`'s storage).
void pose_actor(const Actor& actor, const ActorState& state, DynamicObject& out);

// Radius of a vertical cylinder around the actor's origin that contains it (for clearance checks).
double actor_radius_m(ActorClass cls);

}  // namespace agvslam::sim
