#pragma once
// Dense motion check of superpixels (beyond paper 004; the idea of paper 001's reprojection offsets, applied to
// every pixel instead of feature points). Under the hypothesis that a superpixel is a static surface, its pixels
// (back-projected with the superpixel's disparity plane) must reappear in the previous left image where the
// ego-motion T_cur_prev puts them. The intensity differences of that warp, with their mean removed (exposure
// changes), divided by the mean image gradient, estimate how far (px) the content is from where a static surface
// would be: ~0.2-0.4 px for a static textured surface (noise, disparity error), more for an object that moved.
// A textured superpixel whose apparent motion is small "moves with the background"; the region search then keeps
// it out of the dynamic outline (a shelf beside a person at the same depth, which no occlusion boundary separates).
//
// The same measure on a whole outlined region (mask_mode disparity) with its per-pixel SGBM disparity confirms it:
// a region whose content moved as a static surface would, both frame to frame and against the multi-frame
// reference (where one is available), is not dynamic (a few tracks at a depth edge or on repetitive racking made it).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/dynamic/disparity_plane.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `photometric`.
struct PhotometricCheckConfig {
  bool enabled = true;
  double max_motion_px = 1.0;  // apparent motion below this: the superpixel moves with the background
  double min_gradient = 6.0;   // grey levels per px: weaker texture cannot tell (undecided, not vetoed)
  int sample_step_px = 2;      // every 2nd pixel in x and y
  int min_samples = 12;        // fewer usable samples: undecided
  // Region check (mask_mode disparity): a region is static when its apparent motion is at most max_motion_px
  // against the previous frame and at most multiframe_max_motion_px against the multi-frame reference (larger:
  // the depth error of the warp grows with the baseline), sampling its pixels at least region_inset_px inside its
  // outline (SGBM's disparity is unreliable at the edge).
  double multiframe_max_motion_px = 1.2;
  // The multi-frame reference can only keep a region (static frame to frame) whose median disparity is at least
  // this (px; 0 = any): farther regions it keeps are false (see params/dynamic.yaml).
  double multiframe_min_disparity_px = 10;
  // ... and one farther than that stays when the sparse multi-frame test flagged its tracks (outline.aggregate_
  // multiframe_*): frame to frame the check cannot see less than max_motion_px, which an oncoming vehicle 8-12 m
  // away moves along the epipolar lines, while its LK-verified tracks are off over the longer baseline. Off by
  // default: on the simulator's scene2/3 it also keeps far false regions (params/dynamic.yaml).
  bool far_multiframe_tracks = false;
  int region_inset_px = 2;

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct SuperpixelMotion {
  int samples = 0;
  double mean_gradient = 0;        // grey levels per px
  double apparent_motion_px = -1;  // -1: not measured
  bool moves_with_background = false;
};

// labels: CV_32SC1 superpixels (0 .. planes.size()-1) of a ROI whose top-left pixel is `origin` in the full
// image; planes in full-image coordinates; cur_left/prev_left: CV_8UC1 full images; bf_px_m: baseline * fx.
void check_superpixel_motion(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera,
                             double bf_px_m, const SE3d& T_cur_prev, const cv::Mat& labels, cv::Point origin,
                             const std::vector<DisparityPlane>& planes, const PhotometricCheckConfig& config,
                             std::vector<SuperpixelMotion>& motion);

// The apparent motion of the pixels of `mask` (CV_8UC1, non-zero = region; ROI-local, origin = the ROI's top-left
// in the full image) warped with their own disparity (disparity_px, CV_32FC1 of the ROI, 0 = none) into ref_left
// by T_cur_ref. Sampled every sample_step_px; apparent_motion_px = -1 when fewer than min_samples pixels with
// enough gradient; moves_with_background when <= max_motion_px (the caller's threshold).
SuperpixelMotion region_motion(const cv::Mat& cur_left, const cv::Mat& ref_left, const PinholeCamera& camera,
                               double bf_px_m, const SE3d& T_cur_ref, const cv::Mat& mask, const cv::Mat& disparity_px,
                               cv::Point origin, const PhotometricCheckConfig& config, double max_motion_px);

}  // namespace agvslam::dynamic
