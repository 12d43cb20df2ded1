#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/eval/detection_scoring.h"

namespace agvslam::eval {
namespace {

cv::Mat blank() { return cv::Mat::zeros(200, 300, CV_8UC1); }

TEST(DetectionScoring, ExactDetectionIsATruePositiveWithIouOne) {
  cv::Mat gt = blank(), det = blank();
  gt(cv::Rect(10, 20, 40, 80)).setTo(255);
  det(cv::Rect(10, 20, 40, 80)).setTo(255);
  const auto s = score_detections(det, gt, {{7, cv::Rect(10, 20, 40, 80)}});
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.false_negatives, 0);
  ASSERT_EQ(s.matched_iou.size(), 1u);
  EXPECT_DOUBLE_EQ(s.matched_iou[0], 1.0);
  EXPECT_EQ(s.detections[0].matched_object_id, 7);
}

TEST(DetectionScoring, IouBelowHalfIsAFalsePositiveAndAFalseNegative) {
  cv::Mat gt = blank(), det = blank();
  gt(cv::Rect(0, 0, 100, 100)).setTo(255);  // 10000 px
  det(cv::Rect(0, 0, 100, 45)).setTo(255);  // 4500 px inside: IoU 0.45
  auto s = score_detections(det, gt, {{1, cv::Rect(0, 0, 100, 100)}});
  EXPECT_EQ(s.true_positives, 0);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_EQ(s.false_negatives, 1);
  det(cv::Rect(0, 0, 100, 55)).setTo(255);  // IoU 0.55
  s = score_detections(det, gt, {{1, cv::Rect(0, 0, 100, 100)}});
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_NEAR(s.matched_iou[0], 0.55, 1e-12);
}

TEST(DetectionScoring, ObjectPixelsAreTheMaskInsideTheBoxAndMatchingIsOneToOne) {
  cv::Mat gt = blank(), det = blank();
  gt(cv::Rect(20, 20, 30, 100)).setTo(255);   // person A
  gt(cv::Rect(150, 30, 30, 100)).setTo(255);  // person B
  det(cv::Rect(22, 20, 30, 100)).setTo(255);  // A, shifted 2 px
  det(cv::Rect(250, 10, 20, 20)).setTo(255);  // nothing there
  const std::vector<GroundTruthObject> objects = {{1, cv::Rect(20, 20, 30, 100)}, {2, cv::Rect(150, 30, 30, 100)}};
  const auto s = score_detections(det, gt, objects);
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_EQ(s.false_negatives, 1);
  ASSERT_EQ(s.missed_object_ids.size(), 1u);
  EXPECT_EQ(s.missed_object_ids[0], 2);
  EXPECT_NEAR(s.matched_iou[0], 28.0 / 32.0, 1e-12);
  EXPECT_EQ(s.pixels_ground_truth, 6000);
  EXPECT_EQ(s.pixels_detected, 3400);
  EXPECT_EQ(s.pixels_intersection, 2800);
}

TEST(DetectionScoring, WithInstancesAnObjectBehindAnotherIsOnlyItsOwnPixels) {
  // Person 2 walks behind person 1: its box overlaps person 1's, but only its own pixels are visible.
  cv::Mat gt = blank(), det = blank(), instances = blank();
  instances(cv::Rect(100, 40, 60, 120)).setTo(2);  // person 2, 7200 px in its box ...
  instances(cv::Rect(60, 20, 80, 160)).setTo(1);   // ... of which person 1 in front hides 40 x 120 px
  gt.setTo(255, instances > 0);
  // The detector outlines each person exactly, as two instances.
  det.setTo(1, instances == 1);
  det.setTo(2, instances == 2);
  const std::vector<GroundTruthObject> objects = {{1, cv::Rect(60, 20, 80, 160)}, {2, cv::Rect(100, 40, 60, 120)}};
  auto s = score_detection_instances(det, gt, objects, {}, instances);
  EXPECT_EQ(s.true_positives, 2);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.false_negatives, 0);
  ASSERT_EQ(s.matched_iou.size(), 2u);
  EXPECT_DOUBLE_EQ(s.matched_iou[0], 1.0);
  EXPECT_DOUBLE_EQ(s.matched_iou[1], 1.0);
  // Without instances person 2 is every moving pixel in its box (7200 px), its own 2400 px give IoU 1/3: missed.
  s = score_detection_instances(det, gt, objects);
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_EQ(s.false_negatives, 1);
  ASSERT_EQ(s.missed_object_ids.size(), 1u);
  EXPECT_EQ(s.missed_object_ids[0], 2);
  // A detection merging both people matches neither well with instances: person 1 (12800 px) at IoU 12800/15200.
  cv::Mat merged = blank();
  merged.setTo(1, instances > 0);
  s = score_detection_instances(merged, gt, objects, {}, instances);
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_negatives, 1);
  ASSERT_EQ(s.matched_iou.size(), 1u);
  EXPECT_NEAR(s.matched_iou[0], 12800.0 / 15200.0, 1e-12);
  // Instances of another size are refused.
  EXPECT_THROW(score_detection_instances(det, gt, objects, {}, cv::Mat::zeros(10, 10, CV_8UC1)), std::invalid_argument);
}

TEST(DetectionScoring, SmallObjectsAreDontCareEitherWay) {
  cv::Mat gt = blank(), det = blank();
  gt(cv::Rect(10, 10, 10, 20)).setTo(255);  // 200 px < 400: don't care
  DetectionScoringConfig cfg;
  auto s = score_detections(det, gt, {{1, cv::Rect(10, 10, 10, 20)}}, cfg);
  EXPECT_EQ(s.false_negatives, 0);
  EXPECT_EQ(s.ignored_objects, 1);
  det(cv::Rect(8, 8, 14, 24)).setTo(255);  // detected loosely (IoU 0.6): not a TP, not an FP
  s = score_detections(det, gt, {{1, cv::Rect(10, 10, 10, 20)}}, cfg);
  EXPECT_EQ(s.true_positives, 0);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.ignored_detections, 1);
  cfg.min_object_pixels = 0;  // every object counts
  s = score_detections(det, gt, {{1, cv::Rect(10, 10, 10, 20)}}, cfg);
  EXPECT_EQ(s.true_positives, 1);
}

TEST(DetectionScoring, WithoutObjectListTheMaskComponentsAreTheObjects) {
  cv::Mat gt = blank(), det = blank();
  gt(cv::Rect(10, 10, 40, 40)).setTo(255);
  gt(cv::Rect(100, 10, 40, 40)).setTo(255);
  det(cv::Rect(10, 10, 40, 40)).setTo(255);
  const auto s = score_detections(det, gt, {});
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_negatives, 1);
  EXPECT_EQ(s.false_positives, 0);
}

TEST(DetectionScoring, InstancesInPiecesCountAsOneDetection) {
  cv::Mat gt = blank(), instances = blank();
  gt(cv::Rect(10, 10, 40, 100)).setTo(255);
  instances(cv::Rect(10, 10, 40, 48)).setTo(1);  // one region, outline in two pieces
  instances(cv::Rect(10, 62, 40, 48)).setTo(1);
  instances(cv::Rect(200, 10, 20, 20)).setTo(2);  // a second region on static background
  const auto s = score_detection_instances(instances, gt, {{3, cv::Rect(10, 10, 40, 100)}});
  EXPECT_EQ(s.true_positives, 1);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_NEAR(s.matched_iou[0], 96.0 / 100.0, 1e-12);
  // As a plain mask the two pieces are two components, each under IoU 0.5: one FN and three FPs.
  const auto m = score_detections(instances > 0, gt, {{3, cv::Rect(10, 10, 40, 100)}});
  EXPECT_EQ(m.true_positives, 0);
  EXPECT_EQ(m.false_positives, 3);
  EXPECT_EQ(m.false_negatives, 1);
}

TEST(DetectionScoring, SequenceTotalsFollowEquations12To14) {
  DetectionScore total;
  FrameDetectionScore a;
  a.true_positives = 3;
  a.false_positives = 1;
  a.false_negatives = 0;
  a.matched_iou = {0.9, 0.8, 0.7};
  FrameDetectionScore b;
  b.true_positives = 1;
  b.false_negatives = 1;
  b.matched_iou = {0.6};
  total.add(a);
  total.add(b);
  EXPECT_EQ(total.frames(), 2);
  EXPECT_DOUBLE_EQ(total.precision(), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(total.recall(), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(total.mean_iou(), 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(total.false_positives_per_100_frames(), 50.0);
}

TEST(DetectionScoring, MismatchedMasksAreRejected) {
  EXPECT_THROW(score_detections(cv::Mat::zeros(10, 10, CV_8UC1), cv::Mat::zeros(10, 11, CV_8UC1), {}),
               std::invalid_argument);
}

}  // namespace
}  // namespace agvslam::eval
