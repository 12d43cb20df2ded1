#pragma once
// The stereo module's configuration (params/stereo.yaml): sections `sgbm` and `sparse`. Each section's keys,
// ranges, units and echo are one table in src/stereo/stereo_config.cpp (agvslam/core/param_table.h).

#include <string>
#include <vector>

#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/sparse_stereo.h"

namespace agvslam::stereo {

struct StereoConfig {
  SgbmConfig sgbm;
  SparseStereoConfig sparse;

  void validate(const std::string& source) const;
  // One line per section, for the start-up echo.
  std::vector<std::string> describe() const;
};

// Loads params/stereo.yaml over the defaults (absent keys keep their default). Throws InputError naming the
// file and the field for a missing file, bad YAML, an unknown key, or a value of the wrong type or range.
StereoConfig load_stereo_config(const std::string& path);

}  // namespace agvslam::stereo
