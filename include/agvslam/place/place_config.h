#pragma once
// The place module's configuration (params/place.yaml, section `vocabulary`); its table is in
// src/place/place_config.cpp (agvslam/core/param_table.h).

#include <string>

namespace agvslam::place {

struct PlaceConfig {
  // Vocabulary file; a relative path is relative to the folder of the YAML file it was read from.
  std::string vocabulary_file = "vocabulary/agvslam_orb_k10l5.bin";
  // Depth of the direct index's nodes (FeatureVector::level) for keyframe-to-keyframe matching: 2 keeps
  // ORB-SLAM2's grouping (it uses 4 levels above the leaves of its 6-level tree), ~100 groups of ~12 features.
  int direct_index_level = 2;

  void validate(const std::string& source) const;  // InputError(source, "vocabulary.<key>", expected)
  std::string describe() const;
};

// Loads params/place.yaml over the defaults and resolves vocabulary_file against the YAML file's folder. Throws
// InputError naming the file and the field for a missing file, bad YAML, an unknown key or a bad value.
PlaceConfig load_place_config(const std::string& path);

}  // namespace agvslam::place
