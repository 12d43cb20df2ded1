#pragma once
// Deterministic, platform-independent random numbers for the simulator.
//
// Everything random in a sequence comes from integer hashing (splitmix64 / a 32-bit avalanche hash), never
// from <random> distributions, whose output differs between standard libraries. Independent streams
// (layout, textures, actors, sensor noise, ...) are derived from (seed, stream tag), so changing the actors'
// seed never changes the warehouse, and vice versa.

#include <cmath>
#include <cstdint>

namespace agvslam::sim {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline uint64_t hash64(uint64_t a, uint64_t b) { return splitmix64(a ^ splitmix64(b + 0x632be59bd9b4e019ULL)); }
inline uint64_t hash64(uint64_t a, uint64_t b, uint64_t c) { return hash64(hash64(a, b), c); }

// 32-bit avalanche hash (good bit mixing, cheap: used per pixel and per noise lattice point).
inline uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}
inline uint32_t hash32(uint32_t a, uint32_t b) { return hash32(a ^ hash32(b + 0x9e3779b9U)); }
inline uint32_t hash32(uint32_t a, uint32_t b, uint32_t c) { return hash32(hash32(a, b), c); }

// Maps a hash to [0, 1) with 24 bits.
inline float unit_from_hash(uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

// Tags of the independent random streams.
enum class RngStream : uint64_t {
  kLayout = 0x4c41594f5554ULL,    // warehouse structure and placement
  kTextures = 0x54455854ULL,      // per-surface texture seeds
  kActors = 0x4143544f5253ULL,    // people and vehicles: paths, timing, appearance
  kVehicle = 0x56454849434cULL,   // the camera-carrying AGV: vibration
  kSensor = 0x53454e534f52ULL,    // image noise and exposure
  kAppearance = 0x4150504541ULL,  // an actor's clothing, pose and colours (seeded by its texture seed)
  kLighting = 0x4c49474854ULL,    // the hall's lighting (seeded by the layout seed)
};

class Rng {
 public:
  Rng(uint64_t seed, RngStream stream) : state_(hash64(seed, static_cast<uint64_t>(stream))) {}
  explicit Rng(uint64_t state) : state_(state) {}

  uint64_t next_u64() {
    state_ += 0x9e3779b97f4a7c15ULL;
    uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  uint32_t next_u32() { return static_cast<uint32_t>(next_u64() >> 32); }
  // Uniform in [0, 1) with 53 bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [lo, hi] (inclusive).
  int uniform_int(int lo, int hi) {
    const uint64_t span = static_cast<uint64_t>(static_cast<int64_t>(hi) - static_cast<int64_t>(lo) + 1);
    return lo + static_cast<int>(next_u64() % span);
  }
  bool chance(double p) { return uniform() < p; }
  // Standard normal (Box-Muller on our own uniforms).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  // A child stream (for a sub-object whose randomness must not depend on how many numbers came before).
  Rng fork(uint64_t tag) { return Rng(hash64(next_u64(), tag)); }

 private:
  uint64_t state_;
};

}  // namespace agvslam::sim
