#pragma once
// params/semantic.yaml: the segmentation network and what runs around it (keyframe choice, mask propagation, the
// per-object motion test, fusion with the geometric detector). Loaded through core's parameter tables
// (src/semantic/semantic_config.cpp); every key is optional, the defaults are the member initialisers below.

#include <string>
#include <vector>

namespace agvslam::semantic {

// Section `model`: any PSPNet-style ONNX network that maps one image to per-class scores.
struct ModelConfig {
  // Relative: to the working directory here, to the YAML file's folder when read from one.
  std::string path = "params/models/pspnet_mnv2.onnx";
  int input_width = 288;   // px: the network's fixed input size; the frame is resized to it (INTER_AREA)
  int input_height = 192;  // px
  int input_channels = 1;  // 1: the grey image; 3: grey copied to B, G, R (networks trained on colour)
  double mean = 127.5;     // grey levels: the network sees (pixel - mean) * scale
  double scale = 1.0 / 127.5;
  std::string movable_classes = "5 6 7";  // the class ids that can move (person, forklift, AGV of the simulator)

  // movable_classes as numbers (validate() has checked it parses).
  std::vector<int> movable_ids() const;
  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `keyframes`: which frames are segmented (paper 002's rules).
struct KeyframeConfig {
  int every_n_frames = 5;       // frames: at most this many between two requests
  int min_dynamic_points = 5;   // a frame after one with fewer dynamic points is segmented (0: rule off)
  bool on_new_keyframe = true;  // segment the SLAM's new keyframes

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `propagation`: masks carried between segmented frames by LK on the objects' own corners.
struct PropagationConfig {
  int max_points_per_object = 40;  // corners tracked per object
  int lk_window_px = 21;           // px: LK window side
  int lk_levels = 4;               // pyramid levels: a late result may be several frames behind
  double max_fb_error_px = 1.0;    // px: forward-backward check of a track
  int min_object_pixels = 120;     // px: smaller components of a movable class are segmentation noise
  int max_late_frames = 10;        // frames: an older result is dropped, not warped
  double min_match_iou = 0.3;      // a new segmentation's object continues the carried one it overlaps this much

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Section `motion`: is a segmented object moving against the ego-motion? (paper 001)
struct MotionConfig {
  int min_points = 4;              // tested points an object needs for the point vote; fewer: mask displacement
  double static_sigmas = 3.0;      // a point moves when its reprojection offset exceeds the static points' median
                                   // by this many robust sigmas
  double min_offset_px = 1.5;      // px: ... and at least this much
  double moving_fraction = 0.35;   // the object's frame vote is "moving" when this fraction of its points move
  double far_min_offset_px = 1.0;  // px per frame: mask displacement beyond the static prediction that counts
  double decay = 0.8;              // evidence kept from one frame to the next
  double enter_evidence = 1.5;     // accumulated evidence above which the object is moving
  double exit_evidence = 0.3;      // ... and below which it is standing again

  void validate(const std::string& source) const;
  std::string describe() const;
};

enum class FusionMode { kUnion, kSemantic, kGeometry };

// Section `fusion` and the worker.
struct FusionConfig {
  FusionMode mode = FusionMode::kUnion;  // union: geometry OR moving segmented objects
  int mask_dilation_px = 3;              // px: grows the moving objects' masks (segmentation edges are soft)
  bool synchronous = false;              // wait for each segmentation (offline evaluation; deterministic)

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct SemanticConfig {
  ModelConfig model;
  KeyframeConfig keyframes;
  PropagationConfig propagation;
  MotionConfig motion;
  FusionConfig fusion;

  void validate(const std::string& source) const;
  std::vector<std::string> describe() const;
};

std::string to_string(FusionMode mode);

// Loads params/semantic.yaml over the defaults; a relative model.path becomes relative to the file's folder.
// InputError naming the file and field for a missing file, an unknown key, or a value of the wrong type or out of
// range (the model file itself is checked by Segmenter).
SemanticConfig load_semantic_config(const std::string& path);

}  // namespace agvslam::semantic
