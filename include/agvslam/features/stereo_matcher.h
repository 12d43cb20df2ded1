#pragma once
// Depth of left-image keypoints from the rectified right image (ORB-SLAM2's ComputeStereoMatches, or a
// faster equivalent: the right image's row band around each keypoint, the best match by descriptor or by
// block matching at the keypoint's pyramid level, sub-pixel refinement by a parabola through the SAD costs,
// and rejection of outliers in the distribution of the matching costs).
//
// Contract used by the slam module: the signatures below are what it calls. Members may be added; change a
// signature only together with its callers.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/features/orb_extractor.h"

namespace agvslam::features {

// How the right-image match of a left keypoint is found.
//   kBlockMatching: SAD of the keypoint's window at its pyramid level along the same row of the right image's
//     pyramid over the whole disparity range [bf / max_depth, bf / min_depth], best and second-best minimum
//     (uniqueness test), a minimum curvature of the costs at the best (texture along the row), parabola through
//     the costs around the best. No right-image features are extracted.
//     The window is 2 h + 1 rows by 2 h + 1 columns rounded up to a multiple of 4 (12 for h = 5), starting h
//     columns left of the keypoint, so that the SAD runs four columns at a time.
//   kDescriptor: ORB-SLAM2's ComputeStereoMatches: ORB features of the right image, best descriptor within the
//     row band and the disparity range, then SAD refinement (+-sad_search_px, window 2 h + 1) and a parabola.
// Both reject matches whose SAD is above outlier_factor * median over the image (ORB-SLAM2: 1.5 * 1.4).
enum class StereoMethod : uint8_t { kBlockMatching, kDescriptor };
const char* to_string(StereoMethod method);
bool parse_stereo_method(const std::string& text, StereoMethod& out);

// params/features.yaml, section `stereo_matching` (features::load_features_config).
struct StereoMatcherConfig {
  double min_depth_m = 0.3;          // nearer matches are rejected (disparity above bf / min_depth)
  double max_depth_m = 60.0;         // farther matches get no depth (they still track as monocular points)
  int sad_half_window = 5;           // 11x11 window for the sub-pixel refinement (ORB-SLAM2's w = 5)
  int sad_search_px = 5;             // +-5 px around the descriptor match (ORB-SLAM2's L = 5)
  int max_descriptor_distance = 75;  // ORB-SLAM2's (TH_HIGH + TH_LOW) / 2
  StereoMethod method = StereoMethod::kBlockMatching;
  double uniqueness_ratio = 0.9;  // block matching: best SAD <= ratio * best SAD >= 2 px (level px) away
  double min_curvature = 1.0;     // block matching: SAD rise 1 px off the minimum, per window pixel (grey levels)
  double outlier_factor = 2.1;    // reject SAD > factor * median SAD of the image's matches (ORB-SLAM2 1.5 * 1.4)

  // InputError(source, "stereo_matching.<field>", expected) when out of range; both from the table of
  // params/features.yaml's settings (features_config.cpp).
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

  // The right image's pyramid of the last call (block matching) or the right extractor's (descriptor).
  const std::vector<cv::Mat>& right_pyramid() const;
  // Wall time of the last call (ms): right pyramid (or right ORB extraction), matching.
  double t_right_ms() const { return t_right_ms_; }
  double t_match_ms() const { return t_match_ms_; }
  // The SAD kernel block matching uses on this CPU ("avx2", "sse41" or "scalar").
  const char* sad_kernel_name() const { return sad_kernel_name_; }

 private:
  void match_blocks(const OrbExtractor& left, const KeypointSet& keypoints, StereoDepth& out);
  void match_descriptors(const OrbExtractor& left, const KeypointSet& keypoints, StereoDepth& out);
  void reject_outliers(StereoDepth& out);
  void build_right_pyramid(const OrbExtractor& left, const cv::Mat& right);
  using SadKernel = void (*)(const uint8_t* const*, const uint8_t* const*, int, int, int, uint16_t*);
  static constexpr int kRightPadding = 64;

  StereoMatcherConfig config_;
  StereoCalibration calibration_;
  double min_disparity_px_ = 0, max_disparity_px_ = 0;  // level 0, from max_depth_m / min_depth_m
  std::vector<cv::Mat> right_pyramid_;                  // views into right_padded_
  std::vector<cv::Mat> right_padded_;
  std::vector<LinearExactResizer> right_resizers_;
  SadKernel sad_kernel_ = nullptr;  // best for this CPU (SSE4.1 / AVX2 / scalar)
  const char* sad_kernel_name_ = "scalar";
  std::optional<OrbExtractor> right_extractor_;  // kDescriptor only
  KeypointSet right_keypoints_;
  std::vector<std::vector<int>> row_index_;           // kDescriptor: right keypoints per level-0 row
  std::vector<uint16_t> costs_;                       // SAD per candidate of one keypoint (block matching)
  std::vector<int32_t> descriptor_costs_;             // SAD per offset (descriptor method)
  std::vector<std::pair<int32_t, int>> match_costs_;  // (SAD, keypoint) of the accepted matches
  double t_right_ms_ = 0, t_match_ms_ = 0;
};

}  // namespace agvslam::features
