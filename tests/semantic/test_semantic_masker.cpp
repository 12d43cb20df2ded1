// The semantic stage beside tracking: a slow segmentation never stalls process(), a late result is carried to the
// frame it is applied to, a result older than max_late_frames is dropped, and fusion follows fusion.mode.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "agvslam/core/clock.h"
#include "agvslam/semantic/semantic_masker.h"
#include "sim_sequence.h"

namespace agvslam::semantic {
namespace {

// Scene1 frames 112-127: a person walks in front of the stationary AGV. The "network" is the ground truth
// (class 5 on the person), delivered after `delay`.
struct MaskerRun {
  SemanticStats stats;
  double max_process_ms = 0;
  double mean_iou = 0;  // segmented objects (moving or not) against the ground truth, frames with a result
  int frames_with_objects = 0;
  bool kept_after_first = true;  // once the first result is in, every later frame has objects
};

MaskerRun run(test::SimSequence& seq, SemanticConfig config, std::chrono::milliseconds delay) {
  // No detector here: the motion test has no points, so nothing would be "moving"; the objects are scored.
  config.fusion.mode = FusionMode::kSemantic;
  for (int i = 112; i < 128; ++i) seq.frame(i);  // rendered before the worker reads them
  SemanticMasker masker(config, [&seq, delay](const cv::Mat& grey) {
    std::this_thread::sleep_for(delay);
    for (int i = 112; i < 128; ++i) {
      if (seq.frame(i).left.data == grey.data || cv::norm(seq.frame(i).left, grey, cv::NORM_INF) == 0) {
        return seq.labels(i);
      }
    }
    return cv::Mat(cv::Mat::zeros(grey.size(), CV_8UC1));
  });
  MaskerRun r;
  double iou_sum = 0;
  for (int i = 112; i < 128; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const SemanticFrame& f = masker.process(static_cast<std::size_t>(i), seq.frame(i).left, nullptr, FrameCues{});
    r.max_process_ms = std::max(r.max_process_ms, ms_since(t0));
    if (r.frames_with_objects > 0 && f.objects.empty()) r.kept_after_first = false;
    if (!f.objects.empty()) {
      cv::Mat all = cv::Mat::zeros(seq.frame(i).left.size(), CV_8UC1);
      for (const SemanticObject& o : f.objects) all |= o.mask;
      iou_sum += mask_iou(all, seq.labels(i) == 5);
      ++r.frames_with_objects;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the camera's next frame
  }
  r.stats = masker.stats();
  r.mean_iou = r.frames_with_objects ? iou_sum / r.frames_with_objects : 0;
  std::printf(
      "delay %d ms: requests %lu, segmented %lu, late %lu, stale %lu, frames with objects %d, mean IoU %.3f, "
      "max process %.1f ms\n",
      static_cast<int>(delay.count()), static_cast<unsigned long>(r.stats.requests),
      static_cast<unsigned long>(r.stats.segmented), static_cast<unsigned long>(r.stats.late_results),
      static_cast<unsigned long>(r.stats.stale_results), r.frames_with_objects, r.mean_iou, r.max_process_ms);
  return r;
}

TEST(SemanticMasker, SlowSegmentationNeverStallsAndLateResultsAreCarried) {
  test::SimSequence seq("scene1");
  const MaskerRun r = run(seq, SemanticConfig{}, std::chrono::milliseconds(150));
  // Results that arrive late prove that process() went on without them; its time is the carrying (a result up to
  // 10 frames late is carried through each of them: tens of ms on a loaded machine), never the 150 ms wait.
  EXPECT_GT(r.stats.late_results, 0u);
  EXPECT_LT(r.max_process_ms, 150.0);
  // The first result comes back about 150 / 21 = 7 frames late (more on a loaded machine); from then on every frame
  // has the person.
  EXPECT_GE(r.frames_with_objects, 4);
  EXPECT_TRUE(r.kept_after_first);
  // How far results are carried depends on when they arrive (0.65-0.77 measured on a loaded machine); the carrying
  // itself is scored in test_mask_propagation.cpp.
  EXPECT_GE(r.mean_iou, 0.55);
}

TEST(SemanticMasker, ResultOlderThanTheLimitIsDropped) {
  test::SimSequence seq("scene1");
  SemanticConfig config;
  config.propagation.max_late_frames = 0;  // only a result for the very frame it is applied to counts
  const MaskerRun r = run(seq, config, std::chrono::milliseconds(150));
  EXPECT_GT(r.stats.stale_results, 0u);
  EXPECT_EQ(r.stats.late_results, 0u);
  EXPECT_EQ(r.frames_with_objects, 0);
}

TEST(SemanticMasker, SynchronousModeUsesEachFramesOwnResult) {
  test::SimSequence seq("scene1");
  SemanticConfig config;
  config.fusion.synchronous = true;
  const MaskerRun r = run(seq, config, std::chrono::milliseconds(30));
  EXPECT_EQ(r.stats.late_results, 0u);
  EXPECT_EQ(r.stats.segmented, r.stats.requests);
  EXPECT_GE(r.mean_iou, 0.8);
}

TEST(SemanticMasker, FusionModes) {
  test::SimSequence seq("scene1");
  seq.frame(112);
  dynamic::DetectorResult geometry;
  geometry.mask.image = cv::Mat::zeros(seq.frame(112).left.size(), CV_8UC1);
  geometry.mask.image(cv::Rect(0, 0, 40, 40)).setTo(255);
  for (FusionMode mode : {FusionMode::kUnion, FusionMode::kSemantic, FusionMode::kGeometry}) {
    SemanticConfig config;
    config.fusion.mode = mode;
    config.fusion.synchronous = true;
    SemanticMasker masker(config, [&seq](const cv::Mat&) { return seq.labels(112); });
    const SemanticFrame& f = masker.process(112, seq.frame(112).left, &geometry, FrameCues{});
    // Without points nothing is found moving, so only the detector's pixels can be in the fused mask.
    EXPECT_EQ(cv::countNonZero(f.moving_mask), 0) << to_string(mode);
    EXPECT_EQ(cv::countNonZero(f.fused_mask), mode == FusionMode::kSemantic ? 0 : 1600) << to_string(mode);
    EXPECT_FALSE(f.objects.empty());
  }
}

}  // namespace
}  // namespace agvslam::semantic

namespace agvslam::semantic {
namespace {

// A segmented person whose points move joins the detector's object where they overlap (the detector outlined its
// upper half): one instance for the whole person; a second moving person the detector missed gets its own.
TEST(SemanticMasker, UnionJoinsTheDetectorsObject) {
  const cv::Size size(320, 240);
  const cv::Rect person_a(40, 40, 40, 120), person_b(200, 60, 30, 100);
  cv::Mat labels = cv::Mat::zeros(size, CV_8UC1);
  labels(person_a).setTo(5);
  labels(person_b).setTo(5);
  cv::Mat grey(size, CV_8UC1);
  cv::randu(grey, 0, 255);  // texture for LK
  SemanticConfig config;
  config.fusion.synchronous = true;
  config.fusion.mask_dilation_px = 0;
  config.keyframes.every_n_frames = 1;
  SemanticMasker masker(config, [labels](const cv::Mat&) { return labels; });

  dynamic::DetectorResult geometry;
  geometry.mask.instances = cv::Mat::zeros(size, CV_8UC1);
  const cv::Rect upper_a(person_a.x, person_a.y, person_a.width, person_a.height / 2);
  for (int frame = 0; frame < 3; ++frame) {
    geometry.mask.instances.setTo(0);
    geometry.mask.instances(upper_a).setTo(1);
    geometry.mask.image = geometry.mask.instances > 0;
    geometry.mask.regions = {upper_a};
    geometry.points.clear();
    for (const cv::Rect& box : {person_a, person_b}) {
      for (int k = 0; k < 6; ++k) {
        dynamic::TrackedPoint p;
        p.tracked = true;
        p.cur_px = p.prev_px = cv::Point2f(box.x + 5.f + 5.f * k, box.y + 10.f + 15.f * k);
        p.reprojection_px = 5;  // far beyond the static points' offsets
        geometry.points.push_back(p);
      }
    }
    for (int k = 0; k < 30; ++k) {
      dynamic::TrackedPoint p;
      p.tracked = true;
      p.cur_px = p.prev_px = cv::Point2f(100.f + 3.f * k, 200.f);
      p.reprojection_px = 0.3;
      geometry.points.push_back(p);
    }
    masker.process(static_cast<std::size_t>(frame), grey, &geometry, FrameCues{});
  }
  masker.apply_fusion(geometry.mask);
  EXPECT_EQ(cv::countNonZero(geometry.mask.instances(person_a) != 1), 0) << "person a should be one instance";
  EXPECT_EQ(cv::countNonZero(geometry.mask.instances(person_b) != 2), 0) << "person b should be an instance of its own";
  ASSERT_EQ(geometry.mask.regions.size(), 2u);
  EXPECT_EQ(geometry.mask.regions[0], person_a);
  EXPECT_EQ(geometry.mask.regions[1], person_b);
}

}  // namespace
}  // namespace agvslam::semantic
