// PointTracks on its own: tracks started on a rendered corridor, followed into the next frame and tested, points
// added beside them, and the tracks that continue.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/detector.h"
#include "agvslam/dynamic/point_tracks.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
using namespace agvslam::dynamic::testing;

// Frame 0 starts the tracks; frame 1 (camera and box moved) follows and tests them into `result`.
struct TrackedPair {
  StereoFrame f0, f1;
  cv::Mat gt_mask;
  DetectorResult result;
  DynamicPoints dynamic;
  std::size_t started = 0;  // tracks started on frame 0
};

void track_pair(PointTracks& tracks, const CorridorScene& scene, const Eigen::Vector3d& box_motion_m,
                TrackedPair& out) {
  out.f0 = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), true, 0);
  DetectorResult first;
  tracks.build_pyramid(out.f0.left, first.timings);
  tracks.replenish(out.f0, first, false);
  out.started = tracks.tracks().size();
  tracks.end_frame();
  out.f1 = scene.render_frame(camera_pose(0.03, 0, 0.10, 0.5), box_motion_m, true, 1, &out.gt_mask);
  out.result.has_previous = true;
  tracks.build_pyramid(out.f1.left, out.result.timings);
  tracks.track_and_test(out.f1, out.result);
  tracks.collect_points(out.result, out.dynamic);
}

TEST(PointTracks, StartsTracksOnTheFirstFrame) {
  const CorridorScene scene;
  const DynamicDetectorConfig c;
  PointTracks tracks(point_tracks_config(c), scene.calibration(), stereo::SparseStereoConfig{});
  EXPECT_FALSE(tracks.has_tracks());
  const StereoFrame f0 = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), false, 0);
  DetectorResult r;
  tracks.build_pyramid(f0.left, r.timings);
  tracks.replenish(f0, r, false);
  EXPECT_TRUE(tracks.has_tracks());
  EXPECT_GT(tracks.tracks().size(), 250u);
  EXPECT_LE(static_cast<int>(tracks.tracks().size()), c.tracking.max_tracks);
  EXPECT_EQ(tracks.history().size(), tracks.tracks().size());
  tracks.end_frame();
  EXPECT_EQ(tracks.previous_size(), f0.left.size());
  tracks.reset();
  EXPECT_FALSE(tracks.has_tracks());
}

TEST(PointTracks, FlagsTheTracksOnAMovingBox) {
  const CorridorScene scene;
  PointTracks tracks(point_tracks_config(DynamicDetectorConfig{}), scene.calibration(), stereo::SparseStereoConfig{});
  TrackedPair pair;
  track_pair(tracks, scene, Eigen::Vector3d(0.15, 0, 0), pair);
  const DetectorResult& r = pair.result;
  ASSERT_EQ(r.points.size(), pair.started);
  EXPECT_TRUE(r.epipolar.valid);
  EXPECT_TRUE(r.depth.valid);
  EXPECT_GE(r.lk_levels, 0);
  cv::Mat near_box;
  cv::dilate(pair.gt_mask, near_box, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(21, 21)));
  int on_box = 0, off_box = 0, tracked = 0;
  for (const TrackedPoint& p : r.points) {
    tracked += p.tracked;
    if (!p.dynamic) continue;
    const bool near = mask_at(near_box, p.cur_px) != 0;
    (near ? on_box : off_box) += 1;
  }
  EXPECT_GT(tracked, 250);
  EXPECT_GE(on_box, 5);
  EXPECT_LE(off_box, 3);
  // The dynamic points are listed with their rows.
  ASSERT_EQ(static_cast<int>(pair.dynamic.size()), r.dynamic_point_count());
  for (std::size_t k = 0; k < pair.dynamic.size(); ++k) {
    const TrackedPoint& p = r.points[static_cast<std::size_t>(pair.dynamic.index[k])];
    EXPECT_TRUE(p.dynamic);
    EXPECT_EQ(pair.dynamic.px[k], p.cur_px);
  }
}

TEST(PointTracks, TestsAndAppendsAPointAddedBesideTheTracks) {
  const CorridorScene scene;
  PointTracks tracks(point_tracks_config(DynamicDetectorConfig{}), scene.calibration(), stereo::SparseStereoConfig{});
  TrackedPair pair;
  track_pair(tracks, scene, Eigen::Vector3d(0.15, 0, 0), pair);
  DetectorResult& r = pair.result;
  // A static track with a disparity: as it was, it passes the frame's tests; found 8 px lower, the depth test flags it.
  const TrackedPoint* still = nullptr;
  for (const TrackedPoint& p : r.points) {
    if (p.tracked && !p.dynamic && p.cur_disparity_px > 0 && p.prev_disparity_px > 0 && p.reprojection_px >= 0 &&
        p.reprojection_px < 0.3) {
      still = &p;
      break;
    }
  }
  ASSERT_NE(still, nullptr);
  const TrackedPoint same = tracks.test_new_point(r, still->prev_px, still->cur_px, still->prev_disparity_px,
                                                  still->cur_disparity_px, -1, false);
  EXPECT_FALSE(same.dynamic);
  EXPECT_TRUE(same.densified);
  EXPECT_NEAR(same.reprojection_px, still->reprojection_px, 1e-9);
  const TrackedPoint moved = tracks.test_new_point(r, still->prev_px, still->cur_px + cv::Point2f(0, 8),
                                                   still->prev_disparity_px, still->cur_disparity_px, -1, false);
  EXPECT_TRUE(moved.dynamic_depth);
  EXPECT_TRUE(moved.dynamic);
  // The multi-frame verdict comes from the caller.
  EXPECT_TRUE(tracks
                  .test_new_point(r, still->prev_px, still->cur_px, still->prev_disparity_px, still->cur_disparity_px,
                                  2.5, true)
                  .dynamic);
  const std::size_t rows = r.points.size(), dynamic = pair.dynamic.size();
  tracks.append_new_point(moved, r, pair.dynamic);
  EXPECT_EQ(r.points.size(), rows + 1);
  EXPECT_EQ(tracks.history().size(), rows + 1);
  ASSERT_EQ(pair.dynamic.size(), dynamic + 1);
  EXPECT_EQ(pair.dynamic.index.back(), static_cast<int>(rows));
}

TEST(PointTracks, TheTracksThatHeldContinueAndNewCornersFillTheRest) {
  const CorridorScene scene;
  const DynamicDetectorConfig c;
  PointTracks tracks(point_tracks_config(c), scene.calibration(), stereo::SparseStereoConfig{});
  TrackedPair pair;
  track_pair(tracks, scene, Eigen::Vector3d(0.15, 0, 0), pair);
  std::vector<cv::Point2f> held;
  for (const TrackedPoint& p : pair.result.points) {
    if (p.tracked) held.push_back(p.cur_px);
  }
  tracks.replenish(pair.f1, pair.result, false);
  const std::vector<cv::Point2f>& next = tracks.tracks();
  ASSERT_GE(next.size(), held.size());
  EXPECT_LE(static_cast<int>(next.size()), c.tracking.max_tracks);
  for (std::size_t i = 0; i < held.size(); ++i) EXPECT_EQ(next[i], held[i]) << i;
  // New corners keep their distance from the tracks that held.
  const double min_d = c.tracking.min_track_distance_px;
  for (std::size_t i = held.size(); i < next.size(); ++i) {
    for (const cv::Point2f& h : held) EXPECT_GE(cv::norm(next[i] - h), min_d - 1e-6);
  }
  EXPECT_EQ(tracks.history().size(), next.size());
}

}  // namespace
}  // namespace agvslam::dynamic
