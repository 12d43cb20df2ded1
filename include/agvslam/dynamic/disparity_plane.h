#pragma once
// Disparity planes d = a x + b y + c per superpixel (paper 004, III.B, eq. 8), fitted by RANSAC (three-point
// samples) to reject SGBM outliers, then refitted by least squares on the inliers. x, y are full-image pixel
// coordinates.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `planes`.
struct PlaneFitConfig {
  int ransac_iterations = 50;  // upper bound; stops earlier at `confidence`
  double confidence = 0.99;
  double inlier_threshold_px = 1.0;  // |d - plane| for an inlier
  int min_valid_pixels = 12;         // fewer pixels with a disparity: no plane
  double min_valid_fraction = 0.2;   // ... or fewer than this fraction of the superpixel
  double min_inlier_fraction = 0.5;  // of the valid pixels, else no plane
  int max_samples = 400;             // larger superpixels are subsampled for the fit
  uint32_t seed = 1;                 // RANSAC random generator seed (results are reproducible)

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct DisparityPlane {
  double a = 0, b = 0, c = 0;  // d = a x + b y + c
  bool valid = false;
  int support = 0;  // pixels with a disparity used for the fit
  int inliers = 0;
  double rms_px = 0;  // RMS residual of the inliers after the refit

  double disparity_at(double x, double y) const { return a * x + b * y + c; }
};

// RANSAC + least-squares plane through samples (x, y, d). rng_state: xorshift state, advanced.
DisparityPlane fit_disparity_plane(const std::vector<cv::Point3f>& samples, const PlaneFitConfig& config,
                                   uint32_t& rng_state);

// One plane per superpixel. labels: CV_32SC1 (0 .. count-1) of a ROI whose top-left pixel is `origin` in
// the full image; disparity_px: CV_32FC1 of the same size (<= 0 = none). planes is resized to count.
// sample_step > 1 uses every sample_step-th pixel in x and y (e.g. 2 for a disparity map upsampled from half
// resolution, whose 2x2 blocks repeat one value).
void fit_superpixel_planes(const cv::Mat& labels, int count, const cv::Mat& disparity_px, cv::Point origin,
                           const PlaneFitConfig& config, std::vector<DisparityPlane>& planes, int sample_step = 1);

}  // namespace agvslam::dynamic
