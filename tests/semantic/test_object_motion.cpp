// Moving or not per object (paper 001): a walking person's points move against the ego-motion, a standing
// person's do not; evidence accumulates over frames; a far object with few points is judged by its mask's shift.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "agvslam/semantic/object_motion.h"

namespace agvslam::semantic {
namespace {

const cv::Size kFrame(752, 480);

SemanticObject person(cv::Rect box) {
  SemanticObject o;
  o.class_id = 5;
  o.mask = cv::Mat::zeros(kFrame, CV_8UC1);
  o.mask(box).setTo(255);
  o.box = box;
  return o;
}

// One frame's points: static ones over the image with reprojection offsets of stereo noise (|N(0, 0.4)| px), and
// `inside` points in `box` offset by `object_offset_px` (plus the same noise).
std::vector<dynamic::TrackedPoint> frame_points(std::mt19937& rng, cv::Rect box, int inside, double object_offset_px) {
  std::normal_distribution<double> noise(0.0, 0.4);
  std::uniform_real_distribution<float> ux(0, kFrame.width - 1), uy(0, kFrame.height - 1);
  std::vector<dynamic::TrackedPoint> points;
  auto add = [&](cv::Point2f at, double offset) {
    dynamic::TrackedPoint p;
    p.tracked = true;
    p.prev_px = at;
    p.cur_px = at;
    p.cur_disparity_px = p.prev_disparity_px = 20;
    p.reprojection_px = std::abs(offset + noise(rng));
    points.push_back(p);
  };
  for (int i = 0; i < 200; ++i) {
    const cv::Point2f at(ux(rng), uy(rng));
    if (!box.contains(at)) add(at, 0.0);
  }
  std::uniform_real_distribution<float> bx(box.x, box.x + box.width - 1), by(box.y, box.y + box.height - 1);
  for (int i = 0; i < inside; ++i) add({bx(rng), by(rng)}, object_offset_px);
  return points;
}

TEST(ObjectMotion, WalkingPersonIsMaskedStandingPersonKeepsItsFeatures) {
  const MotionConfig config;
  ObjectMotionTest test(config);
  std::mt19937 rng(38);
  const cv::Rect walker_box(100, 150, 60, 180), stander_box(500, 150, 60, 180);
  std::vector<SemanticObject> walker{person(walker_box)}, stander{person(stander_box)};
  for (int frame = 0; frame < 10; ++frame) {
    const auto w =
        test.update(frame_points(rng, walker_box, 12, 4.0), nullptr, walker);  // a 4 px step against the static
    const auto s = test.update(frame_points(rng, stander_box, 12, 0.0), nullptr, stander);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_TRUE(w[0].measured);
    EXPECT_FALSE(w[0].from_mask);
    EXPECT_EQ(w[0].tested_points, 12);
    // One frame of evidence is not enough: the hysteresis waits for a second agreeing frame.
    EXPECT_EQ(walker[0].moving, frame >= 1) << frame;
    EXPECT_FALSE(stander[0].moving) << frame;
    EXPECT_LT(s[0].moving_points, 4) << frame;
  }
  // The walker stops: it is unmasked once its evidence has decayed, not on the first quiet frame.
  int frames_to_stop = 0;
  while (walker[0].moving && frames_to_stop < 50) {
    test.update(frame_points(rng, walker_box, 12, 0.0), nullptr, walker);
    ++frames_to_stop;
  }
  EXPECT_FALSE(walker[0].moving);
  EXPECT_GT(frames_to_stop, 3);
  EXPECT_LT(frames_to_stop, 20);
}

TEST(ObjectMotion, DetectorFlagsCountAsMovingPoints) {
  ObjectMotionTest test{MotionConfig{}};
  std::mt19937 rng(7);
  const cv::Rect box(300, 200, 50, 100);
  std::vector<SemanticObject> objects{person(box)};
  for (int frame = 0; frame < 3; ++frame) {
    auto points = frame_points(rng, box, 10, 0.0);
    for (auto& p : points) {
      if (box.contains(p.cur_px)) p.dynamic_epipolar = true;
    }
    test.update(points, nullptr, objects);
  }
  EXPECT_TRUE(objects[0].moving);
}

TEST(ObjectMotion, ThresholdFollowsTheStaticSpread) {
  ObjectMotionTest test{MotionConfig{}};
  EXPECT_DOUBLE_EQ(test.static_threshold_px({}), MotionConfig{}.min_offset_px);
  // Median 2, MAD 1: 2 + 3 * 1.4826 px.
  EXPECT_NEAR(test.static_threshold_px({1, 2, 3, 1, 2, 3, 2}), 2 + 3 * 1.4826, 1e-5);
}

TEST(ObjectMotion, FarObjectJudgedByItsMaskShift) {
  ObjectMotionTest test{MotionConfig{}};
  std::mt19937 rng(3);
  const cv::Rect box(400, 200, 12, 30);  // a far person: no tested points of its own
  std::vector<SemanticObject> far_walker{person(box)}, far_stander{person(box)}, no_depth{person(box)};
  // The floor where it stands is at the static points' disparity (20 px).
  dynamic::DisparityPlane floor;
  floor.c = 20;
  floor.valid = true;
  for (int frame = 0; frame < 4; ++frame) {
    // The camera pans: every static point shifts 3 px to the left.
    auto points = frame_points(rng, box, 0, 0.0);
    for (auto& p : points) p.prev_px.x = p.cur_px.x + 3.0f;
    far_walker[0].flow_known = far_stander[0].flow_known = no_depth[0].flow_known = true;
    no_depth[0].flow_px = {0.f, 0.f};
    far_walker[0].flow_px = {-3.0f + 2.5f, 0.f};  // walks 2.5 px per frame against the pan
    far_stander[0].flow_px = {-3.2f, 0.1f};       // moves with the static background
    const auto w = test.update(points, &floor, far_walker);
    const auto s = test.update(points, &floor, far_stander);
    const auto n = test.update(points, nullptr, no_depth);
    EXPECT_FALSE(n[0].measured) << "without a depth there is no static shift to compare with";
    EXPECT_TRUE(w[0].from_mask);
    EXPECT_NEAR(w[0].mask_offset_px, 2.5, 1e-3);
    EXPECT_LT(s[0].mask_offset_px, 0.5);
  }
  EXPECT_TRUE(far_walker[0].moving);
  EXPECT_FALSE(far_stander[0].moving);
}

}  // namespace
}  // namespace agvslam::semantic
