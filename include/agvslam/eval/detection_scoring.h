#pragma once
// Object-level scoring of dynamic-region masks as in paper 004 (eqs. 12-14).
//
// Ground-truth objects: the moving objects of a frame, each the pixels of the ground-truth moving mask inside
// its box (the simulator's objects.txt) that carry its id in the ground-truth instance image where one is given
// (instance_0/: where two objects' boxes overlap, e.g. a person walking behind another, each object is only its
// own visible pixels); without boxes, the 8-connected components of the ground-truth mask.
// Detected objects: the 8-connected components of the detected mask, or the instances of a label image (a
// detector's regions, one object each even when its outline is in pieces). A detection and an object match when
// their IoU (eq. 14) is >= min_iou, one to one, best IoU first. TP = matched objects, FP = detections matching
// no object, FN = objects matching no detection; P = TP/(TP+FP) (eq. 12), R = TP/(TP+FN) (eq. 13); the mean
// IoU is over the matched pairs.
//
// "Don't care" objects (as in the KITTI benchmarks): a moving object with fewer than min_object_pixels visible
// moving pixels (a person far away or nearly hidden) counts neither as FN nor, when detected, as TP; a
// detection lying mostly (>= half its pixels) on such an object is not an FP either. Pixel-level precision,
// recall and IoU of the whole mask are reported alongside.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace agvslam::eval {

struct DetectionScoringConfig {
  double min_iou = 0.5;          // match threshold (paper 004: IoU >= 0.5)
  int min_object_pixels = 400;   // smaller ground-truth objects are "don't care" (0 = every object counts)
  int min_detection_pixels = 0;  // smaller detected components are dropped before matching (0 = none)
};

struct GroundTruthObject {
  int id = 0;
  cv::Rect box;  // the object's pixels are the ground-truth mask's non-zero pixels inside this box
};

struct DetectedObject {
  cv::Rect box;
  int pixels = 0;
  int matched_object_id = -1;  // -1: false positive (or ignored)
  double iou = 0;
  bool ignored = false;  // on a "don't care" object, or below min_detection_pixels
};

struct FrameDetectionScore {
  int true_positives = 0, false_positives = 0, false_negatives = 0;
  int ignored_objects = 0, ignored_detections = 0;
  std::vector<double> matched_iou;
  std::vector<DetectedObject> detections;
  std::vector<int> missed_object_ids;
  int64_t pixels_detected = 0, pixels_ground_truth = 0, pixels_intersection = 0;
};

// detected_mask, gt_mask: CV_8UC1 of one size, non-zero = dynamic. objects: the frame's moving objects; when
// empty, the connected components of gt_mask are the objects. gt_instances: empty, or CV_8UC1 of the same size
// holding each pixel's object id (objects' ids; used only with objects).
FrameDetectionScore score_detections(const cv::Mat& detected_mask, const cv::Mat& gt_mask,
                                     const std::vector<GroundTruthObject>& objects,
                                     const DetectionScoringConfig& config = {}, const cv::Mat& gt_instances = {});

// Same with the detected objects given as an instance label image (CV_8UC1 or CV_32SC1, 0 = none, each other
// value one detected object, which may consist of several pieces).
FrameDetectionScore score_detection_instances(const cv::Mat& detection_labels, const cv::Mat& gt_mask,
                                              const std::vector<GroundTruthObject>& objects,
                                              const DetectionScoringConfig& config = {},
                                              const cv::Mat& gt_instances = {});

// Totals over a sequence.
class DetectionScore {
 public:
  void add(const FrameDetectionScore& frame);

  int frames() const { return frames_; }
  int true_positives() const { return tp_; }
  int false_positives() const { return fp_; }
  int false_negatives() const { return fn_; }
  int ignored_objects() const { return ignored_objects_; }
  // 1 when there is nothing to count (no detections / no objects).
  double precision() const { return tp_ + fp_ > 0 ? static_cast<double>(tp_) / (tp_ + fp_) : 1.0; }
  double recall() const { return tp_ + fn_ > 0 ? static_cast<double>(tp_) / (tp_ + fn_) : 1.0; }
  double mean_iou() const { return tp_ > 0 ? iou_sum_ / tp_ : 0.0; }
  double false_positives_per_100_frames() const { return frames_ > 0 ? 100.0 * fp_ / frames_ : 0.0; }
  double pixel_precision() const;
  double pixel_recall() const;
  double pixel_iou() const;

 private:
  int frames_ = 0, tp_ = 0, fp_ = 0, fn_ = 0, ignored_objects_ = 0;
  double iou_sum_ = 0;
  int64_t pix_det_ = 0, pix_gt_ = 0, pix_inter_ = 0;
};

}  // namespace agvslam::eval
