#pragma once
// Images for the feature tests: a simulator frame rendered in-process (with ground-truth disparity), a rectified
// EuRoC frame and the shared stereo pairs with ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/core/camera.h"
#include "agvslam/sim/simulator.h"

namespace agvslam::features::testing {

struct SimPair {
  cv::Mat left, right;
  cv::Mat disparity_px;  // CV_32F ground truth, 0 = none
  cv::Mat mask;          // moving objects
  StereoCalibration calibration;
};

// Frame `frame` of a simulator scenario (752x480, fx 460 px, baseline 0.12 m), rendered here.
inline SimPair render_sim(const std::string& scenario, int frame, uint64_t seed = 1) {
  sim::ScenarioOptions options;
  options.name = scenario;
  options.seed = seed;
  const sim::SimConfig config;
  const sim::Simulator simulator(config, options);
  sim::SimFrame rendered;
  simulator.render_frame(frame, rendered, 2);
  SimPair p;
  p.left = rendered.left.clone();
  p.right = rendered.right.clone();
  rendered.disparity_u16.convertTo(p.disparity_px, CV_32F, 1.0 / 256.0);
  p.mask = rendered.mask.clone();
  p.calibration = simulator.calibration();
  return p;
}

// A calibration with the given focal length and baseline for an image of `size` (no rectification needed).
inline StereoCalibration calibration_for(cv::Size size, double fx, double baseline_m) {
  StereoCalibration c;
  c.left.fx = c.left.fy = fx;
  c.left.cx = 0.5 * size.width;
  c.left.cy = 0.5 * size.height;
  c.left.width = size.width;
  c.left.height = size.height;
  c.baseline_m = baseline_m;
  return c;
}

}  // namespace agvslam::features::testing
