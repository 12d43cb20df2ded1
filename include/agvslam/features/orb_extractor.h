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

#include "agvslam/features/linear_resize.h"
#include "agvslam/features/orb_blur.h"
#include "agvslam/features/quadtree_distribution.h"

namespace agvslam::features {

// How the per-image feature budget is shared among pyramid levels: geometrically, level l getting a share
// proportional to (1/scale_factor)^(2 l) (its area) or to (1/scale_factor)^l (its side, as
// ORB-SLAM2 and OpenCV's ORB do).
enum class LevelAllocation : uint8_t { kArea, kSide };
const char* to_string(LevelAllocation allocation);
bool parse_level_allocation(const std::string& text, LevelAllocation& out);

// params/features.yaml, section `orb` (features::load_features_config).
struct OrbExtractorConfig {
  int n_features = 1200;      // per image (paper 004 uses ORB-SLAM2's 1200 for 752x480)
  double scale_factor = 1.2;  // between pyramid levels
  int n_levels = 8;
  int ini_fast_threshold = 20;  // FAST threshold for the first pass
  int min_fast_threshold = 7;   // retry in cells where the first pass found no corner
  int mask_dilation_px = 8;     // the dynamic mask grows by this (level-0 px) before it excludes keypoints
  int cell_size_px = 30;        // side of the FAST cells whose emptiness triggers the retry (ORB-SLAM2's W = 30)
  LevelAllocation level_allocation = LevelAllocation::kArea;

  // Features wanted on each level (n_levels values summing to n_features).
  std::vector<int> features_per_level() const;

  // InputError(source, "orb.<field>", expected) when out of range; one line for the start-up echo. Both from the
  // table of params/features.yaml's settings (features_config.cpp).
  void validate(const std::string& source) const;
  std::string describe() const;
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

// Per-call figures of OrbExtractor::extract (for tests, benchmarks and the tracker's statistics).
struct OrbExtractorStats {
  int candidates = 0;         // FAST corners outside the mask, all levels, before the quadtree
  int masked_candidates = 0;  // corners dropped because they lie within the dilated dynamic mask
  int retry_cells = 0;        // cells without a corner at ini_fast_threshold (they take min_fast_threshold ones)
  std::vector<int> keypoints_per_level;
  // Wall time of each stage (ms): pyramid, mask, FAST + cells, quadtree, orientation, blur, descriptors.
  double t_pyramid_ms = 0, t_mask_ms = 0, t_fast_ms = 0, t_distribute_ms = 0, t_orientation_ms = 0, t_blur_ms = 0,
         t_descriptor_ms = 0;
};

// Constants of ORB-SLAM2's extractor (and OpenCV's ORB with patchSize = 31).
inline constexpr int kOrbPatchSize = 31;      // BRIEF patch side at the keypoint's level
inline constexpr int kOrbHalfPatchSize = 15;  // radius of the intensity-centroid disc
inline constexpr int kOrbEdgeThreshold = 19;  // keypoints stay this far (level px) from every level's border
inline constexpr int kOrbDescriptorBytes = 32;

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

  // Features wanted per level (config().features_per_level()).
  const std::vector<int>& features_per_level() const { return features_per_level_; }
  // Size of each level for an image of `image_size` (OpenCV ORB's rounding: cvRound(cols / scale)).
  cv::Size level_size(cv::Size image_size, int level) const;
  // Builds the pyramid of `image` exactly as extract() does (cascaded bilinear INTER_LINEAR_EXACT, OpenCV ORB's
  // levels), reusing the Mats in `levels`. Used for the right image by the stereo matcher.
  void build_pyramid(const cv::Mat& image, std::vector<cv::Mat>& levels) const;

  const OrbExtractorStats& stats() const { return stats_; }
  // The quadtree nodes of the last call at `level` (level px; filled only when set_collect_nodes(true)).
  void set_collect_nodes(bool collect) { collect_nodes_ = collect; }
  const std::vector<cv::Rect>& nodes(int level) const { return level_nodes_.at(static_cast<std::size_t>(level)); }

 private:
  struct Candidate {
    int16_t x, y;   // level px
    int16_t score;  // FAST score
    int16_t cell;
  };
  static constexpr int kBlurBorder = 3;  // reflected border around each left level (the 7x7 blur's radius)
  void build_bordered_pyramid(const cv::Mat& image);
  void prepare_mask(const cv::Mat& dynamic_mask, cv::Size image_size);
  bool masked(float x0_px, float y0_px, int level) const;
  void detect_level(int level);
  void compute_orientation(int level, std::size_t first, std::vector<cv::KeyPoint>& keypoints) const;
  void compute_descriptors(const std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) const;

  OrbExtractorConfig config_;
  std::vector<cv::Mat> pyramid_;              // views into bordered_
  std::vector<cv::Mat> bordered_;             // each level with a kBlurBorder reflected border
  std::vector<LinearExactResizer> resizers_;  // level l - 1 -> l
  std::vector<float> scale_factors_, inv_scale_factors_, level_sigma2_, inv_level_sigma2_;
  std::vector<int> features_per_level_;
  std::vector<int> umax_;         // half-width of each row of the orientation disc
  std::vector<cv::Mat> blurred_;  // Gaussian 7x7, sigma 2 of each level (the descriptor image)
  OrbBlur blur_;
  cv::Mat mask_binary_;    // dynamic_mask as 0 / 255
  cv::Mat mask_integral_;  // integral image of (dynamic_mask != 0), level 0; empty = no mask
  bool mask_active_ = false;
  cv::Mat strength_;  // FAST strength of the current level (a view of strength_buffer_)
  std::vector<uint8_t> strength_buffer_;
  std::vector<int> maxima_;            // columns of the local maxima of one strength row
  std::vector<Candidate> candidates_;  // corners of the current level
  std::vector<int> cell_counts_;
  std::vector<QuadtreeCandidate> quadtree_input_;
  std::vector<int> kept_;
  QuadtreeDistributor distributor_;
  bool collect_nodes_ = false;
  std::vector<std::vector<cv::Rect>> level_nodes_;
  OrbExtractorStats stats_;
};

// Computes rotated-BRIEF descriptors of `keypoints` (level-0 coordinates, octave = level, angle in degrees) on
// `blurred_pyramid` (each level Gaussian-blurred 7x7, sigma 2, as OpenCV's ORB does) into `descriptors`
// (rows = keypoints.size(), 32 bytes). Bit-exact with cv::ORB::compute for keypoints whose pattern stays inside
// the level (at least kOrbEdgeThreshold px from its border). `scale_factors`: scale of each level.
void compute_orb_descriptors(const std::vector<cv::Mat>& blurred_pyramid, const std::vector<float>& scale_factors,
                             const std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors);

// Hamming distance of two 32-byte descriptors.
int descriptor_distance(const uint8_t* a, const uint8_t* b);

}  // namespace agvslam::features
