#pragma once
// The feature stage's configuration (params/features.yaml): sections `orb` (OrbExtractorConfig) and
// `stereo_matching` (StereoMatcherConfig). Each section's keys, ranges, units and echo are one table in
// src/features/features_config.cpp (agvslam/core/param_table.h).

#include <string>
#include <vector>

#include "agvslam/features/orb_extractor.h"
#include "agvslam/features/stereo_matcher.h"

namespace agvslam::features {

struct FeaturesConfig {
  OrbExtractorConfig orb;
  StereoMatcherConfig stereo_matching;

  void validate(const std::string& source) const;
  // One line per section, for the start-up echo.
  std::vector<std::string> describe() const;
};

// Loads params/features.yaml over the defaults (absent keys keep their default). Throws InputError naming the
// file and the field ("orb.n_features") for a missing file, bad YAML, an unknown section or key, or a value of
// the wrong type or out of range.
FeaturesConfig load_features_config(const std::string& path);

}  // namespace agvslam::features
