// Masks carried between segmented frames by LK, scored against the simulator's ground-truth masks: a person
// walking in front of the stationary AGV (scene1) and one crossing ahead of the driving AGV (scene2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "agvslam/semantic/mask_propagation.h"
#include "sim_sequence.h"

namespace agvslam::semantic {
namespace {

struct Carried {
  double iou_chained = 0;   // carried frame by frame
  double iou_one_step = 0;  // carried in one LK step (a late result)
  double iou_stale = 0;     // the segmentation left where it was
};

// The person segmented (from the ground truth) at `first`, carried to `first + gap`; IoU against the ground truth
// there.
Carried carry(test::SimSequence& seq, int first, int gap) {
  const PropagationConfig config;
  std::vector<SemanticObject> chained = extract_objects(seq.labels(first), {5}, config.min_object_pixels);
  EXPECT_FALSE(chained.empty());
  if (chained.empty()) return {};
  // The largest piece of the person (an occluder may split it).
  std::sort(chained.begin(), chained.end(), [](const SemanticObject& a, const SemanticObject& b) {
    return cv::countNonZero(a.mask) > cv::countNonZero(b.mask);
  });
  chained.resize(1);
  seed_corners(seq.frame(first).left, config, chained);
  std::vector<SemanticObject> one_step = chained;
  const cv::Mat stale = chained.front().mask.clone();
  std::vector<cv::Mat> from = lk_pyramid(seq.frame(first).left, config);
  const std::vector<cv::Mat> start = from;
  for (int i = first + 1; i <= first + gap; ++i) {
    std::vector<cv::Mat> to = lk_pyramid(seq.frame(i).left, config);
    carry_objects(from, to, config, chained);
    from = to;
  }
  carry_objects(start, from, config, one_step);
  const cv::Mat truth = seq.labels(first + gap) == 5;  // all of the person's pixels: the stale mask is a piece too
  Carried c;
  c.iou_chained = chained.empty() ? 0 : mask_iou(chained.front().mask, truth);
  c.iou_one_step = one_step.empty() ? 0 : mask_iou(one_step.front().mask, truth);
  c.iou_stale = mask_iou(stale, truth);
  std::printf("frames %d -> %d: IoU chained %.3f, one step %.3f, not carried %.3f\n", first, first + gap, c.iou_chained,
              c.iou_one_step, c.iou_stale);
  return c;
}

TEST(MaskPropagation, WalkingPersonStationaryAgv) {
  test::SimSequence seq("scene1");
  const Carried c = carry(seq, 112, 5);
  EXPECT_GE(c.iou_chained, 0.75);
  EXPECT_GE(c.iou_one_step, 0.75);
  EXPECT_GT(c.iou_chained, c.iou_stale + 0.1);
}

TEST(MaskPropagation, CrossingPersonDrivingAgv) {
  test::SimSequence seq("scene2");
  // The first frame with the crossing person well in view (from the posed actors, so the test follows the
  // scenario's timeline).
  int first = -1;
  for (int i = 1; i < seq.simulator().frame_count() && first < 0; i += 4) {
    std::vector<sim::DynamicObject> objects;
    seq.simulator().pose_objects(i, objects);
    const Eigen::Isometry3d T_cam_map = seq.simulator().T_map_cam(i).inverse();
    for (const sim::DynamicObject& o : objects) {
      const Eigen::Vector3d p = T_cam_map * Eigen::Vector3d(o.origin.x, o.origin.y, o.origin.z);
      const double u = 460.0 * p.x() / p.z() + 375.5;
      if (o.cls == sim::ActorClass::kPerson && o.moving && p.z() > 1.5 && p.z() < 6 && u > 250 && u < 500) first = i;
    }
  }
  ASSERT_GT(first, 0);
  // At 2 m the crossing person's legs swing tens of pixels per frame, which no rigid warp follows: the carried mask
  // is far better than the stale one, and the next segmentation (every 5 frames) renews it.
  const Carried one = carry(seq, first, 1);
  EXPECT_GE(one.iou_chained, 0.65);
  EXPECT_GT(one.iou_chained, one.iou_stale + 0.05);
  const Carried five = carry(seq, first, 5);
  EXPECT_GE(five.iou_chained, 0.45);
  EXPECT_GE(five.iou_one_step, 0.45);
  EXPECT_GT(five.iou_chained, five.iou_stale + 0.3);
}

}  // namespace
}  // namespace agvslam::semantic
