#pragma once
// Two-motion carving of an outline (beyond paper 004).
//
// The disparity outline floods every surface connected to the object's points through smoothly varying disparity:
// a person crossing in front of a rack at the person's depth takes the rack's face with it, which no disparity step
// separates (the outline is then much larger than the person, and its IoU falls below the scoring's threshold).
// The image motion separates them where disparity cannot: the rack moved as a static surface does (the ego-motion
// T_cur_prev at its own disparity), the person moved with the person's tracks.
//
// The outline is cut into blocks of block_px. In each block, the outline's textured pixels (every sample_step_px,
// gradient >= min_gradient, with a disparity) are compared with the previous left image under two hypotheses:
//  - static: back-projected with their SGBM disparity and moved by the ego-motion;
//  - object: moved by the object's image motion (the median motion of its tracks), give or take search_px in x and y
//    (arms and legs swing; the best shift counts).
// The error of a hypothesis is the mean absolute difference of its samples with their mean removed (exposure). A
// block is static when the static hypothesis fits clearly better (its error <= max_static_ratio x the object's) and
// the object's motion clearly does not fit (its error >= min_object_error_dn), while the static one does (its error
// <= max_static_error_dn: with a wrong ego-motion, the nearer of two wrong shifts "fits better"): such a block is
// removed from the outline. Blocks where the hypotheses cannot be told apart (no texture, too few samples, a block
// straddling the object's edge) stay. Of what is left, the connected parts holding one of the object's points stay.
// Nothing is carved when the object's motion is within min_separation_px of a static point's at its depth (the
// caller passes the object's tracks' median offset from the ego-motion): the two hypotheses predict the same.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `motion_carve`.
struct MotionCarveConfig {
  bool enabled = true;
  int block_px = 12;                 // blocks of 12x12 px decide together
  int sample_step_px = 2;            // every 2nd pixel in x and y
  int search_px = 2;                 // the object's motion +- 2 px in x and y (integer shifts)
  double min_gradient = 3.0;         // grey levels per px: weaker texture cannot tell
  int min_samples = 6;               // per block
  double max_static_ratio = 0.75;    // static error <= 0.75 x the object's best error ...
  double min_object_error_dn = 4.0;  // ... and the object's best error >= 4 grey levels
  double max_static_error_dn = 8.0;  // ... and the static error itself <= 8 grey levels (the static warp must fit)
  double min_separation_px = 2.0;    // the object's tracks' median offset from the ego-motion, at least
  int seed_radius_px = 3;            // a connected part holds an object point within 3 px

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct MotionCarveStats {
  bool ran = false;        // the hypotheses were separable and the outline was tested
  int blocks_tested = 0;   // blocks with enough textured samples
  int blocks_static = 0;   // of those, static
  int pixels_removed = 0;  // outline pixels removed (static blocks and the parts cut off from the object's points)
};

// outline: CV_8UC1 ROI-local outline (non-zero = object), modified in place; disparity_px: CV_32FC1 of the same
// size (0 = none); origin: the ROI's top-left in the full image; cur_left/prev_left: CV_8UC1 full images;
// T_cur_prev: the ego-motion; object_motion_px: the object's image motion (current minus previous position);
// separation_px: its tracks' median offset from a static point's motion; object_points: its points (full image).
MotionCarveStats carve_by_motion(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera,
                                 double bf_px_m, const SE3d& T_cur_prev, cv::Point2f object_motion_px,
                                 double separation_px, const std::vector<cv::Point2f>& object_points,
                                 const cv::Mat& disparity_px, cv::Point origin, const MotionCarveConfig& config,
                                 cv::Mat& outline);

}  // namespace agvslam::dynamic
