// BandSegmenter: the static segment of a point without depth (exact cases), and a textured box stepping into
// view at the left border of a standing camera in the corridor test scene, rendered exactly (synthetic_scene.h).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/band_segmenter.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
using namespace agvslam::dynamic::testing;

// The corridor test scene's camera (fx 460 px) and baseline (0.12 m).
const CorridorScene& corridor() {
  static const CorridorScene scene;
  return scene;
}
PinholeCamera camera() { return corridor().camera; }
double bf() { return camera().fx * corridor().baseline_m; }

// T_cur_prev of a previous camera at T_prev_cur (the motion maps previous-frame points into the current frame).
SE3d motion_from_prev_cur(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  SE3d T_prev_cur = SE3d::Identity();
  T_prev_cur.linear() = R;
  T_prev_cur.translation() = t;
  return T_prev_cur.inverse();
}

TEST(BandSegmenter, StaticSegmentOfAPointWithoutDepth) {
  const BandSegmenter band;
  const PinholeCamera cam = camera();
  // A standing camera, or one turning on the spot: every depth lands on the same previous pixel.
  EXPECT_NEAR(band.static_segment_length(cam, bf(), SE3d::Identity(), 10, 200), 0.0, 1e-9);
  const Eigen::Matrix3d yaw = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(band.static_segment_length(cam, bf(), motion_from_prev_cur(yaw, Eigen::Vector3d::Zero()), 10, 200), 0.0,
              1e-9);
  // 1 cm sideways: disparities 0..64 spread over fx * 64 * 0.01 / bf = 5.33 px.
  const SE3d sideways = motion_from_prev_cur(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.01, 0, 0));
  EXPECT_NEAR(band.static_segment_length(cam, bf(), sideways, 10, 200), 460.0 * 64 * 0.01 / bf(), 1e-6);
  // On the segment (disparity 32: half way) the distance is 0; 2 px across it, 2 px; 3 px beyond its end, 3 px.
  const double half = 460.0 * 32 * 0.01 / bf();
  EXPECT_NEAR(band.static_segment_distance(cam, bf(), sideways, {10, 200}, {static_cast<float>(10 + half), 200}), 0.0,
              1e-4);
  EXPECT_NEAR(band.static_segment_distance(cam, bf(), sideways, {10, 200}, {static_cast<float>(10 + half), 202}), 2.0,
              1e-4);
  const double end = 460.0 * 64 * 0.01 / bf();
  EXPECT_NEAR(band.static_segment_distance(cam, bf(), sideways, {10, 200}, {static_cast<float>(10 + end + 3), 200}),
              3.0, 1e-3);
}

// The corridor's left image with its box (0.5 m wide, 2.5 m ahead) whose right side is at image column right_px;
// gt: 255 on the box.
cv::Mat render_left(double right_px, const SE3d& T_w_c, std::size_t index, cv::Mat* gt = nullptr) {
  const CorridorScene& scene = corridor();
  const double z = 2.5;
  TexturedRect box = scene.box;
  box.width_m = 0.5;
  box.origin = {(right_px - scene.camera.cx) * z / scene.camera.fx - box.width_m, -1.1, z};
  std::vector<TexturedRect> rects = scene.statics;
  rects.push_back(box);
  RenderOutput out;
  render(rects, scene.camera, T_w_c, out);
  add_noise(out.grey, 1.5, 300 + index);
  if (gt) *gt = out.id == 1;
  return out.grey;
}

struct BandRun {
  BandResult result;
  cv::Mat gt, found;  // the box's pixels in the strip, the regions' pixels
};

// The two renders (the box's right side at right0_px, then at right1_px seen from T_w_c1; T_w_c0 = identity, so
// T_w_c1.inverse() is the motion T_cur_prev mapping frame-0 points into frame 1) with their LK pyramids.
struct TwoFrames {
  cv::Mat gt, prev, cur;  // gt: the box's pixels in the current image (declared first: cur's render fills it)
  LkTracker tracker;
  std::vector<cv::Mat> prev_pyramid, cur_pyramid;
  TwoFrames(double right0_px, double right1_px, const SE3d& T_w_c1)
      : prev(render_left(right0_px, SE3d::Identity(), 0)), cur(render_left(right1_px, T_w_c1, 1, &gt)) {
    tracker.build_pyramid(prev, prev_pyramid);
    tracker.build_pyramid(cur, cur_pyramid);
  }
};

BandRun run_band(double right0_px, double right1_px, const SE3d& T_w_c1, const BandSegmenterConfig& config = {},
                 const std::vector<cv::Point2f>& track_prev = {}, const std::vector<cv::Point2f>& track_cur = {}) {
  BandRun run;
  TwoFrames f(right0_px, right1_px, T_w_c1);
  run.gt = f.gt;
  BandSegmenter band(config);
  band.segment(f.cur, f.prev, f.cur_pyramid, f.prev_pyramid, f.tracker, -1, camera(), bf(), T_w_c1.inverse(),
               cv::Mat::zeros(f.cur.size(), CV_8UC1), track_prev, track_cur, run.result);
  run.gt.colRange(config.strip_px, run.gt.cols).setTo(0);
  run.found = cv::Mat::zeros(f.cur.size(), CV_8UC1);
  for (const BandRegion& r : run.result.regions) run.found(r.rect).setTo(255, r.mask);
  return run;
}

TEST(BandSegmenter, FindsABoxSteppingIntoViewWhileTheCameraStands) {
  // The box's right side moves from 26 to 34 px (2 cm at 2.5 m is 3.7 px; 8 px is a brisk step at 20 Hz): it lies
  // wholly in the band x < d (d = 22 px at 2.5 m), where no stereo outline can reach.
  const BandRun run = run_band(26, 34, SE3d::Identity());
  ASSERT_TRUE(run.result.ran);
  EXPECT_NEAR(run.result.static_segment_px, 0.0, 1e-6);
  EXPECT_GE(run.result.seeds.size(), 2u);
  ASSERT_FALSE(run.result.regions.empty());
  const double overlap = iou(run.found, run.gt);
  const int false_px = cv::countNonZero(run.found & ~run.gt);
  EXPECT_GE(overlap, 0.7) << "box px " << cv::countNonZero(run.gt) << ", found " << cv::countNonZero(run.found);
  EXPECT_LT(false_px, cv::countNonZero(run.gt) / 10);
  // Nearly every seed lies on the box (LK on a weak corner of the noisy wall can slip by more than the offset).
  std::size_t on_box = 0;
  for (const BandSeed& s : run.result.seeds) on_box += run.gt.at<uint8_t>(cvRound(s.cur_px.y), cvRound(s.cur_px.x)) > 0;
  EXPECT_GE(on_box * 10, run.result.seeds.size() * 8);
  std::printf("box stepping in: %zu seeds of %d corners, %zu regions, IoU %.3f, %d false px of %d box px\n",
              run.result.seeds.size(), run.result.corners, run.result.regions.size(), overlap, false_px,
              cv::countNonZero(run.gt));
}

TEST(BandSegmenter, TheCallersTracksInTheStripAreTestedAsTheyAre) {
  // Tracks the detector has already (here: a column of points on the box, which moved 8 px right, and one on the
  // wall beside it, which stood; and one outside the strip) are seeds or not by their own motion; their cells are
  // not searched for corners again.
  std::vector<cv::Point2f> prev, cur;
  for (float y = 80; y <= 300; y += 20) {
    cur.push_back({20, y});
    prev.push_back({12, y});
  }
  cur.push_back({50, 200});
  prev.push_back({50, 200});
  cur.push_back({300, 200});
  prev.push_back({290, 200});
  BandSegmenterConfig all_seeds;  // keep every seed (by default the 16 farthest off their segments)
  all_seeds.max_seeds = 1000;
  const BandRun with_tracks = run_band(26, 34, SE3d::Identity(), all_seeds, prev, cur);
  const BandRun without = run_band(26, 34, SE3d::Identity(), all_seeds);
  EXPECT_EQ(with_tracks.result.tracks, 13);
  EXPECT_LT(with_tracks.result.corners, without.result.corners);
  int from_tracks = 0;
  for (const BandSeed& seed : with_tracks.result.seeds) {
    if (seed.cur_px.x == 20.0f) {
      ++from_tracks;
      EXPECT_NEAR(seed.offset_px, 8.0, 1e-3);
    }
    EXPECT_NE(seed.cur_px, cv::Point2f(50, 200));
  }
  EXPECT_EQ(from_tracks, 12);
  EXPECT_GE(iou(with_tracks.found, with_tracks.gt), 0.9);
}

TEST(BandSegmenter, NothingMovingGivesNoRegion) {
  const BandRun run = run_band(34, 34, SE3d::Identity());
  ASSERT_TRUE(run.result.ran);
  EXPECT_GT(run.result.corners, 50);
  EXPECT_LE(run.result.seeds.size(), 1u);
  EXPECT_TRUE(run.result.regions.empty());
}

TEST(BandSegmenter, TurningOnTheSpotStillSegments) {
  // A 1 degree yaw moves the whole image by ~8 px, the static segments stay points: the box is found, but for its
  // leftmost ~8 px, which the previous image did not see (no hypothesis can be tested there).
  SE3d T_w_c1 = SE3d::Identity();
  T_w_c1.linear() = Eigen::AngleAxisd(-1.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const BandRun run = run_band(26, 34, T_w_c1);
  ASSERT_TRUE(run.result.ran);
  EXPECT_LT(run.result.static_segment_px, 1e-6);
  EXPECT_GE(iou(run.found, run.gt), 0.5);
}

TEST(BandSegmenter, SkipsFramesWhereTheCameraTranslates) {
  // Driving forward 5 cm: a static point 0.9 m away moves by ~20 px more than one at infinity at the border, so any
  // few px of motion could be a static point at some depth: the frame is left alone.
  const BandRun run = run_band(26, 34, camera_pose(0, 0, 0.05));
  EXPECT_FALSE(run.result.ran);
  EXPECT_GT(run.result.static_segment_px, BandSegmenterConfig{}.max_static_segment_px);
  EXPECT_TRUE(run.result.regions.empty());
  BandSegmenterConfig off;
  off.enabled = false;
  EXPECT_FALSE(run_band(26, 34, SE3d::Identity(), off).result.ran);
}

// BandSegmenter::driving_seeds between the two renders (T_w_c0 = identity); gt: the box's pixels in the current image.
struct DrivingRun {
  bool ran = false;
  std::vector<BandSeed> seeds;
  cv::Mat gt;
  std::size_t on_box() const {
    std::size_t n = 0;
    for (const BandSeed& s : seeds) n += gt.at<uint8_t>(cvRound(s.cur_px.y), cvRound(s.cur_px.x)) > 0;
    return n;
  }
};

DrivingRun run_driving(double right0_px, double right1_px, const SE3d& T_w_c1, const BandSegmenterConfig& config = {},
                       const std::vector<cv::Point2f>& track_cur = {}) {
  DrivingRun run;
  TwoFrames f(right0_px, right1_px, T_w_c1);
  run.gt = f.gt;
  BandSegmenter band(config);
  run.ran = band.driving_seeds(f.cur, f.cur_pyramid, f.prev_pyramid, f.tracker, -1, camera(), bf(), T_w_c1.inverse(),
                               track_cur, run.seeds);
  return run;
}

TEST(BandSegmenter, WhileDrivingABoxSteppingInAgainstTheFlowGivesSeeds) {
  // Driving forward 5 cm: static points at the left border move left by up to ~20 px (the nearer, the more), along
  // their segments; the box steps 8 px right, which no static point at any depth does.
  const DrivingRun run = run_driving(26, 34, camera_pose(0, 0, 0.05));
  ASSERT_TRUE(run.ran);
  ASSERT_GE(run.seeds.size(), 3u);
  EXPECT_GE(run.on_box() * 10, run.seeds.size() * 9) << run.on_box() << " of " << run.seeds.size() << " on the box";
  for (const BandSeed& s : run.seeds) {
    EXPECT_GT(s.offset_px, BandSegmenterConfig{}.driving_seed_offset_px);
    EXPECT_LT(s.cur_px.x, BandSegmenterConfig{}.strip_px);
  }
  std::printf("driving, box stepping in: %zu seeds, %zu on the box\n", run.seeds.size(), run.on_box());
}

TEST(BandSegmenter, WhileDrivingStaticTextureGivesNoSeeds) {
  const DrivingRun run = run_driving(34, 34, camera_pose(0, 0, 0.05));
  ASSERT_TRUE(run.ran);
  // The box stood: its corners moved as static points at its depth do, like the wall's.
  EXPECT_LE(run.seeds.size(), 1u);
}

TEST(BandSegmenter, WhileDrivingCellsHoldingATrackAreNotSearched) {
  // Tracks over the whole strip: no cell is left to search.
  std::vector<cv::Point2f> tracks;
  for (float y = 2; y < 480; y += 12)
    for (float x = 2; x < 64; x += 12) tracks.push_back({x, y});
  const DrivingRun run = run_driving(26, 34, camera_pose(0, 0, 0.05), {}, tracks);
  EXPECT_TRUE(run.ran);
  EXPECT_TRUE(run.seeds.empty());
}

TEST(BandSegmenter, DrivingSeedsLeaveStandingFramesToSegment) {
  // Standing (segment() runs on such frames) or switched off: no driving seeds.
  EXPECT_FALSE(run_driving(26, 34, SE3d::Identity()).ran);
  BandSegmenterConfig off;
  off.driving_seed_offset_px = 0;
  const DrivingRun run = run_driving(26, 34, camera_pose(0, 0, 0.05), off);
  EXPECT_FALSE(run.ran);
  EXPECT_TRUE(run.seeds.empty());
}

TEST(BandSegmenter, RejectsAnInvalidConfiguration) {
  BandSegmenterConfig c;
  c.min_seeds = 5;
  c.max_seeds = 3;
  EXPECT_THROW(BandSegmenter{c}, InputError);
  BandSegmenterConfig d;
  d.driving_seed_offset_px = -1;
  EXPECT_THROW(BandSegmenter{d}, InputError);
}

}  // namespace
}  // namespace agvslam::dynamic
