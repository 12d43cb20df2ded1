#pragma once
// How far a ground-truth moving object moved in the image against where a static object would be: the measure of
// how visible its motion is to a detector that compares tracks with the ego-motion's prediction.
//
// The object's pixels with ground-truth disparity in the earlier frame are lifted to 3-D, moved with the camera
// motion T_now_then and projected into the current frame: their mean is where the object's centroid would be if
// it stood still. The offset is the distance from there to the centroid of its pixels now. It is meaningful only
// when the object's visible part kept its size (an object entering the view, or passing behind another, shifts its
// centroid without moving): the result is invalid when the visible pixel count changed by more than
// max_visible_change (relative), or when either frame holds fewer than min_pixels of it.

#include <opencv2/core.hpp>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"

namespace agvslam::eval {

struct ObjectMotionConfig {
  int min_pixels = 200;              // pixels with ground-truth disparity in each frame
  double max_visible_change = 0.25;  // now / then within [1 / (1 + c), 1 + c]
};

struct ObjectImageMotion {
  bool valid = false;
  double offset_px = -1;     // centroid now - predicted static centroid, |.| in px
  double visible_ratio = 0;  // pixels now / pixels then (with disparity)
  int pixels_then = 0, pixels_now = 0;
};

// instances_*: CV_8UC1 object ids (0 = none); disparity_*_px: CV_32FC1, 0 = none; T_now_then maps points of the
// earlier camera frame into the current one (T_w_now^-1 * T_w_then).
ObjectImageMotion ground_truth_image_motion(const cv::Mat& instances_then, const cv::Mat& disparity_then_px,
                                            const cv::Mat& instances_now, const cv::Mat& disparity_now_px,
                                            int object_id, const PinholeCamera& camera, double bf_px_m,
                                            const SE3d& T_now_then, const ObjectMotionConfig& config = {});

}  // namespace agvslam::eval
