#pragma once
// Camera, sensor and rendering settings of the simulator (params/sim.yaml). Defaults are in the struct;
// the YAML file overrides any subset of them:
//
//   camera:    width, height, fx, fy, cx, cy, baseline_m, height_above_floor_m, rate_hz
//   sensor:    noise_sigma_dn, exposure_variation, exposure_spread, vignetting
//   rendering: max_depth_m, antialias_edges, haze_distance_m, png_compression, lighting_variation
//   vehicle:   vibration_deg
//
// fy <= 0 means fy = fx; cx, cy < 0 mean the image centre ((width - 1) / 2, (height - 1) / 2). Each section's
// keys, ranges, units and echo are one table in src/sim/sim_config.cpp (agvslam/core/param_table.h).

#include <string>
#include <vector>

#include "agvslam/core/camera.h"

namespace agvslam::sim {

struct SimConfig {
  // Camera (rectified stereo pair, identical intrinsics, right camera at +baseline along x).
  int width = 752;
  int height = 480;
  double fx = 460.0;
  double fy = -1.0;  // <= 0: same as fx
  double cx = -1.0;  // < 0: (width - 1) / 2
  double cy = -1.0;  // < 0: (height - 1) / 2
  double baseline_m = 0.12;
  double camera_height_m = 0.5;  // optical centre above the floor
  double rate_hz = 20.0;

  // Sensor.
  double noise_sigma_dn = 2.0;       // Gaussian read noise, grey levels (digital numbers)
  double exposure_variation = 0.04;  // amplitude of the smooth global gain variation (0.04 = +-4 %)
  double exposure_spread = 0.1;      // a sequence's exposure is drawn from its seed in [1 - s, 1 + s]
  double vignetting = 0.10;          // relative brightness loss in the image corners

  // Rendering.
  double max_depth_m = 60.0;         // disparity 0 beyond this depth
  bool antialias_edges = true;       // 2 extra samples on silhouette pixels (ground truth: pixel centres)
  double haze_distance_m = 140.0;    // e-folding distance of a faint atmospheric haze (<= 0: none)
  int png_compression = 1;           // zlib level 0..9 for the written PNGs
  double lighting_variation = 0.25;  // relative spread of the key light's strength (the ambient light's: half of
                                     // it), drawn from the layout seed with the key light's direction (0: fixed)

  // Vehicle.
  double vibration_deg = 0.25;  // amplitude of the camera's pitch/roll vibration at full speed

  double fy_px() const { return fy > 0 ? fy : fx; }
  double cx_px() const { return cx >= 0 ? cx : 0.5 * (width - 1); }
  double cy_px() const { return cy >= 0 ? cy : 0.5 * (height - 1); }

  // The rectified calibration this configuration produces.
  StereoCalibration calibration() const;
  // Throws InputError(source, field, expectation) for an invalid value.
  void validate(const std::string& source) const;
  // One line per setting, for start-up logs.
  std::vector<std::string> describe() const;
  // Same settings with the image scaled by `factor` (focal length and principal point scaled too).
  SimConfig scaled(double factor) const;
};

// Loads a params/sim.yaml file over the defaults. Throws InputError naming the file and the key for a missing
// file, a syntax error, an unknown key or a value of the wrong type or range.
SimConfig load_sim_config(const std::string& path);

}  // namespace agvslam::sim
