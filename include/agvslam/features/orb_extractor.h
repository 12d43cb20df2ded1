#pragma once
// ORB features of the tracker (paper 004 III.C: ORB-SLAM2's extractor, features only in static regions).
//
// An 8-level pyramid (scale 1.2), FAST corners distributed over each level by a quadtree (ORB-SLAM2's
// DistributeOctTree: split cells until there are as many nodes as features wanted on that level, keep the
// strongest corner per node, retry a cell with a lower FAST threshold where it has none), intensity-centroid
// orientation, and 256-bit rotated BRIEF descriptors (32 bytes, the bit pattern of OpenCV's ORB, so Hamming
// distances and a vocabulary trained on them agree). Keypoints are never placed inside the dynamic mask (dilated
// by mask_dilation_px at level 0 and scaled per level, so no descriptor patch reaches into a moving object).
//
// Contract used by the slam and place modules: the signatures below are what they call. Members may be added;
// change a signature only together with its callers.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::features {

// params/features.yaml, section `orb` (features::load_features_config).
struct OrbExtractorConfig {
  int n_features = 1200;         // per image (paper 004 uses ORB-SLAM2's 1200 for 752x480)
  double scale_factor = 1.2;     // between pyramid levels
  int n_levels = 8;
  int ini_fast_threshold = 20;   // FAST threshold for the first pass
  int min_fast_threshold = 7;    // retry in cells where the first pass found no corner
  int mask_dilation_px = 5;      // the dynamic mask grows by this (level-0 px) before it excludes keypoints

  void validate(const std::string& source) const;  // InputError(source, "orb.<field>", expected) when out of range
  std::string describe() const;                     // one line for the start-up echo
};

// Features of one image. Coordinates are level-0 pixels of the rectified image.
struct KeypointSet {
  std::vector<cv::KeyPoint> keypoints;  // pt: level-0 px; octave: pyramid level; angle: degrees; response: FAST
  cv::Mat descriptors;                  // keypoints.size() x 32, CV_8UC1
  void clear() {
    keypoints.clear();
    descriptors.release();
  }
};

class OrbExtractor {
 public:
  explicit OrbExtractor(const OrbExtractorConfig& config = {});
  const OrbExtractorConfig& config() const { return config_; }

  // image: CV_8UC1. dynamic_mask: CV_8UC1 of the image size, non-zero = dynamic (no keypoint there), or empty.
  // Reuses its buffers between calls (no per-frame allocation once sizes are stable).
  void extract(const cv::Mat& image, const cv::Mat& dynamic_mask, KeypointSet& out);

  // The pyramid of the last extracted image (level 0 is the image itself).
  const std::vector<cv::Mat>& pyramid() const { return pyramid_; }
  // Per level: scale_factor^level, its inverse, and their squares (ORB-SLAM2's mvLevelSigma2 / mvInvLevelSigma2).
  const std::vector<float>& scale_factors() const { return scale_factors_; }
  const std::vector<float>& inv_scale_factors() const { return inv_scale_factors_; }
  const std::vector<float>& level_sigma2() const { return level_sigma2_; }
  const std::vector<float>& inv_level_sigma2() const { return inv_level_sigma2_; }

 private:
  OrbExtractorConfig config_;
  std::vector<cv::Mat> pyramid_;
  std::vector<float> scale_factors_, inv_scale_factors_, level_sigma2_, inv_level_sigma2_;
  // Implementation buffers are added by the implementation.
};

// Hamming distance of two 32-byte descriptors.
int descriptor_distance(const uint8_t* a, const uint8_t* b);

}  // namespace agvslam::features
