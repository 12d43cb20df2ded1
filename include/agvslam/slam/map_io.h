#pragma once
// Saved maps: a versioned binary file with a checksum, written atomically.
//
// Layout (little-endian; IEEE floats):
//   header, 64 bytes
//      0  char[8]  magic "AGVSMAP\0"
//      8  u32      format version (kMapFormatVersion)
//     12  u32      header size (64)
//     16  u64      payload size in bytes (the file is exactly 64 + this)
//     24  u32      CRC-32 (zlib's, ISO-HDLC) of the payload
//     28  u32      flags (0)
//     32  u64      vocabulary identity (place::Vocabulary::identity(); 0 = a map without bag of words)
//     40  u64      keyframe count
//     48  u64      map point count
//     56  u32      direct-index level of the keyframes' bag of words
//     60  u32      CRC-32 of header bytes 0..59
//   payload
//      camera      f64 fx fy cx cy baseline_m, i32 width height, i32 pyramid levels, f64 scale factor
//      counters    u64 next keyframe id, next map point id, origin keyframe id
//      keyframes   (ascending id) u64 id, frame id, i64 t_ns, f64[12] T_c_w (3x4 row-major), u32 N,
//                  N x {f32 x y size angle response, i32 octave class_id}, N x 32 descriptor bytes, N x f32
//                  u_right, N x f32 depth, N x u64 map point id (all ones = none, all ones but the last bit =
//                  a retired keypoint that saw an object which moved: version 2), u64 parent id (all ones =
//                  none), u8 flags (1 origin, 2 protected from culling, 4 spanning-tree parent still to be
//                  chosen), u32 + ids of loop edges, u32 + (u64 id, i32 weight) covisibility connections,
//                  u32 + (u64 id, i32 weight) ordered covisible neighbours
//      map points  (ascending id) u64 id, first keyframe id, first frame id, f64[3] position, f64[3] normal,
//                  32 descriptor bytes, f32 min/max distance, u64 reference keyframe id, i32 visible, found,
//                  u32 + (u64 keyframe id, i32 keypoint index) observations
//      removed     u32 + (u64 keyframe id, u64 parent id, f64[12] T_c_parent): culled keyframes, so that poses
//                  stored relative to them still resolve
// The bag-of-words vectors are not stored: they are recomputed with the vocabulary whose identity the header
// names (a map made with another vocabulary is refused). Children lists follow from the parents.
//
// Writing (save_map_file): a temporary file "<path>.tmp" in the same folder, written and fsync'ed, renamed over
// <path>, then the folder is fsync'ed; a crash at any point leaves either the previous file or the new one, never
// a mixture. Reading checks, in order: size, magic, header checksum, version, payload size, payload checksum, the
// vocabulary identity and the camera, then every cross-reference (ids, keypoint indices); any failure is an
// InputError naming the file, the field and what was expected.

#include <cstdint>
#include <functional>
#include <string>

#include "agvslam/slam/frame.h"
#include "agvslam/slam/map.h"

namespace agvslam::slam {

inline constexpr uint32_t kMapFormatVersion = 2;
// Version 1 files (before retired keypoints) read the same way.
inline constexpr uint32_t kMapFormatOldestReadable = 1;
inline constexpr std::size_t kMapHeaderBytes = 64;

// What a map file must agree with to be loaded (and what is written into it).
struct MapFileContext {
  double fx = 0, fy = 0, cx = 0, cy = 0, baseline_m = 0;
  int width = 0, height = 0;
  int n_levels = 0;
  double scale_factor = 0;
  uint64_t vocabulary_id = 0;  // 0: no vocabulary
  int direct_index_level = 0;

  static MapFileContext from(const FrameGeometry& geometry, uint64_t vocabulary_id, int direct_index_level);
  std::string describe() const;
};

// What a file's header says (after its checks).
struct MapFileSummary {
  uint32_t version = 0;
  uint64_t payload_bytes = 0;
  uint32_t payload_crc32 = 0;
  uint64_t vocabulary_id = 0;
  uint64_t keyframes = 0, map_points = 0;
  int direct_index_level = 0;
};

// The whole file's bytes for `map` (the map mutex must be held by the caller).
std::string encode_map(const Map& map, const MapFileContext& context);

// Parses and checks a file's bytes into `map`, which must be empty (keyframes use `geometry`, which must match
// `expected`). Throws InputError(source, field, expected) and leaves `map` empty on any error. The keyframes'
// bag of words is not computed here (the caller has the vocabulary).
MapFileSummary decode_map(const std::string& bytes, const std::string& source, const MapFileContext& expected,
                          const FrameGeometryPtr& geometry, Map& map);

// Checks the header and the payload checksum only.
MapFileSummary check_map_file(const std::string& bytes, const std::string& source);

// Fault injection for tests: called at each stage of a write with the bytes written so far ("open", "chunk" after
// each chunk of chunk_bytes, "written", "fsync", "renamed", "done").
struct MapWriteHooks {
  std::function<void(const char* stage, std::size_t bytes_written)> on_stage;
  std::size_t chunk_bytes = std::size_t(1) << 20;
};

// Writes atomically (see above). Throws InputError(path, "", ...) when the folder is missing or not writable;
// the previous file at `path` is then untouched.
void save_map_file(const std::string& path, const std::string& bytes, const MapWriteHooks& hooks = {});

// Reads a whole file; InputError(path, "", ...) when it cannot be read.
std::string read_map_file(const std::string& path);

}  // namespace agvslam::slam
