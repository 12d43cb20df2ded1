// Densifier on its own: a small far box holds too few tracks for a ROI; the densifier adds corners of the previous
// frame around them, tracked and tested like the tracks.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/densifier.h"
#include "agvslam/dynamic/detector.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
using namespace agvslam::dynamic::testing;

DynamicDetectorConfig sparse_config() {
  DynamicDetectorConfig c;
  c.features.target_count = 120;
  return c;
}

struct Tracked {
  StereoFrame f0, f1;
  cv::Mat gt_mask;
  DetectorResult result;
  DynamicPoints dynamic;
};

Tracked track_two_frames(PointTracks& tracks, const CorridorScene& scene) {
  Tracked t;
  t.f0 = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), true, 0);
  DetectorResult first;
  tracks.build_pyramid(t.f0.left, first.timings);
  tracks.replenish(t.f0, first, false);
  tracks.end_frame();
  t.f1 = scene.render_frame(camera_pose(0.0, 0, 0.08), Eigen::Vector3d(-0.12, -0.06, 0), true, 1, &t.gt_mask);
  t.result.has_previous = true;
  tracks.build_pyramid(t.f1.left, t.result.timings);
  tracks.track_and_test(t.f1, t.result);
  tracks.collect_points(t.result, t.dynamic);
  return t;
}

TEST(Densifier, AddsTestedPointsAroundASmallGroup) {
  const CorridorScene scene = small_far_box_scene();
  const DynamicDetectorConfig c = sparse_config();
  PointTracks tracks(point_tracks_config(c), scene.calibration(), stereo::SparseStereoConfig{});
  Tracked t = track_two_frames(tracks, scene);
  const std::size_t rows = t.result.points.size();
  const std::vector<cv::Point2f> existing = tracks.tracks();
  ASSERT_LT(static_cast<int>(t.dynamic.size()), c.grouping.min_points) << "the box should hold too few tracks";
  ASSERT_GE(static_cast<int>(t.dynamic.size()), c.densify.min_seeds);

  Densifier densifier(c.densify, densifier_context(c), scene.calibration());
  densifier.densify(t.f1, t.f0.left, t.f0.right, tracks, t.dynamic, t.result);
  ASSERT_GT(t.result.points.size(), rows);
  EXPECT_EQ(tracks.history().size(), t.result.points.size());
  cv::Mat near_box;
  cv::dilate(t.gt_mask, near_box, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(11, 11)));
  int on_box = 0, dynamic_off_box = 0;
  const double min_d = c.densify.min_distance_px;
  for (std::size_t i = rows; i < t.result.points.size(); ++i) {
    const TrackedPoint& p = t.result.points[i];
    EXPECT_TRUE(p.densified);
    EXPECT_EQ(p.age, 1);
    for (const cv::Point2f& q : existing) EXPECT_GE(cv::norm(p.prev_px - q), min_d - 1e-6);
    const bool near = mask_at(near_box, p.cur_px) != 0;
    on_box += near && p.dynamic;
    dynamic_off_box += !near && p.dynamic;
  }
  EXPECT_GE(on_box, 3);
  EXPECT_LE(dynamic_off_box, 2);
  // The dynamic ones joined the frame's dynamic points: now enough for a ROI.
  EXPECT_GE(static_cast<int>(t.dynamic.size()), c.grouping.min_points);
  EXPECT_EQ(static_cast<int>(t.dynamic.size()), t.result.dynamic_point_count());
}

TEST(Densifier, TooFewSeedsAddNothing) {
  const CorridorScene scene = small_far_box_scene();
  DynamicDetectorConfig c = sparse_config();
  PointTracks tracks(point_tracks_config(c), scene.calibration(), stereo::SparseStereoConfig{});
  Tracked t = track_two_frames(tracks, scene);
  const std::size_t rows = t.result.points.size();
  c.densify.min_seeds = static_cast<int>(t.dynamic.size()) + 1;
  Densifier densifier(c.densify, densifier_context(c), scene.calibration());
  densifier.densify(t.f1, t.f0.left, t.f0.right, tracks, t.dynamic, t.result);
  EXPECT_EQ(t.result.points.size(), rows);
}

TEST(Densifier, OptionsAreValidatedUnderTheirSection) {
  DensifyOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.multiframe_levels = -2;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "densify.multiframe_levels");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
