#pragma once
// Depth of left-image keypoints from the rectified right image (ORB-SLAM2's ComputeStereoMatches, or a
// faster equivalent: the right image's row band around each keypoint, the best match by descriptor or by
// block matching at the keypoint's pyramid level, sub-pixel refinement by a parabola through the SAD costs,
// and rejection of outliers in the distribution of the matching costs).
//
// Contract used by the slam module: the signatures below are what it calls. Members may be added; change a
// signature only together with its callers.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/features/orb_extractor.h"

namespace agvslam::features {

// params/features.yaml, section `stereo_matching` (features::load_features_config).
struct StereoMatcherConfig {
  double min_depth_m = 0.3;        // nearer matches are rejected (disparity above bf / min_depth)
  double max_depth_m = 60.0;       // farther matches get no depth (they still track as monocular points)
  int sad_half_window = 5;         // 11x11 window for the sub-pixel refinement (ORB-SLAM2's w = 5)
  int sad_search_px = 5;           // +-5 px around the descriptor match (ORB-SLAM2's L = 5)
  int max_descriptor_distance = 75;  // ORB-SLAM2's (TH_HIGH + TH_LOW) / 2

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct StereoDepth {
  std::vector<float> u_right_px;  // per left keypoint: x of the match in the right image, -1 = none
  std::vector<float> depth_m;     // per left keypoint: bf / (u_left - u_right), -1 = none
  int matched = 0;
};

class StereoMatcher {
 public:
  StereoMatcher(const StereoMatcherConfig& config, const StereoCalibration& calibration);
  const StereoMatcherConfig& config() const { return config_; }

  // left: the extractor that produced `keypoints` from the left image (its pyramid and scales are used);
  // right: the rectified right image (CV_8UC1, same size). Fills `out` with one entry per keypoint.
  void match(const OrbExtractor& left, const KeypointSet& keypoints, const cv::Mat& right, StereoDepth& out);

 private:
  StereoMatcherConfig config_;
  StereoCalibration calibration_;
  // Implementation state (a right-image extractor, buffers) is added by the implementation.
};

}  // namespace agvslam::features
