#pragma once
// Masks of segmented objects carried from frame to frame (paper 002, III.C): each object keeps corners of its own,
// LK follows them into the next image, and the object's mask moves with the similarity transform they give (their
// median shift when fewer than three are left). A segmentation that arrives late is carried the same way from
// the image it was computed on to the current one, in one LK step.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "agvslam/semantic/semantic_config.h"

namespace agvslam::semantic {

// One segmented object of a movable class, as seen in the current frame.
struct SemanticObject {
  int id = 0;                        // stable over frames while the object is carried or matched
  int class_id = 0;                  // the network's class id
  cv::Mat mask;                      // CV_8UC1, frame size, 255 = the object
  cv::Rect box;                      // bounding box of mask
  std::vector<cv::Point2f> corners;  // its own points, in the current frame
  cv::Point2f flow_px{0, 0};         // how far its corners moved into this frame (median), px
  bool flow_known = false;           // false: no corner followed it into this frame
  int frames_seen = 0;
  double evidence = 0;  // accumulated motion evidence (object_motion.h)
  bool moving = false;
};

// The connected components of the movable classes in `labels` (CV_8UC1 class ids), each at least
// min_object_pixels, as new objects (id 0) without corners.
std::vector<SemanticObject> extract_objects(const cv::Mat& labels, const std::vector<int>& movable_ids,
                                            int min_object_pixels);

// Seeds each object's corners on `grey` (the image its mask belongs to): Shi-Tomasi corners inside the eroded mask,
// topped up from a grid over the mask where the object has too few of them.
void seed_corners(const cv::Mat& grey, const PropagationConfig& config, std::vector<SemanticObject>& objects);

// Image pyramids for LK, built once per image.
std::vector<cv::Mat> lk_pyramid(const cv::Mat& grey, const PropagationConfig& config);

// Carries the objects from the image of `from` to that of `to`: corners tracked (forward-backward checked),
// masks warped, flow_px set. Objects that leave the image or shrink below min_object_pixels are dropped.
void carry_objects(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to, const PropagationConfig& config,
                   std::vector<SemanticObject>& objects);

// Intersection over union of two CV_8UC1 masks (0 when both are empty).
double mask_iou(const cv::Mat& a, const cv::Mat& b);

}  // namespace agvslam::semantic
