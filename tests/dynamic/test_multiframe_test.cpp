// TrackHistory bookkeeping, and MultiFrameTest on exact tracks of a rendered corridor: a box that keeps its
// distance ahead of a forward-driving camera (invisible frame to frame) is dynamic over 0.3 m of travel; static
// points are not, nor is a static track with a one-frame stereo mismatch or one that slid a few pixels.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/dynamic/multiframe_test.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
using namespace agvslam::dynamic::testing;

TEST(TrackHistory, KeepsTheLastObservationsOfEachTrack) {
  TrackHistory h(4);
  h.add({1, 1}, 5.0f);
  h.add({2, 2}, 6.0f);
  h.next_frame({{1.5f, 1}, {2.5f, 2}}, {5.1f, 6.1f}, {1, 0});
  cv::Point2f p;
  float d = 0;
  ASSERT_TRUE(h.observation(0, 0, p, d));
  EXPECT_EQ(p, cv::Point2f(1.5f, 1));
  EXPECT_FLOAT_EQ(d, 5.1f);
  ASSERT_TRUE(h.observation(0, 1, p, d));
  EXPECT_EQ(p, cv::Point2f(1, 1));
  EXPECT_FLOAT_EQ(d, 5.0f);
  EXPECT_FALSE(h.observation(0, 2, p, d));  // the track is one frame old
  EXPECT_EQ(h.age(0), 1);
  EXPECT_EQ(h.consistent_steps(0), 1);
  EXPECT_EQ(h.consistent_steps(1), 0);

  // A track born now with an observation one frame back (a densified track).
  h.add({3, 3}, 7.0f);
  h.add_earlier(1, {2.9f, 3}, 6.9f);
  EXPECT_EQ(h.age(2), 1);
  ASSERT_TRUE(h.observation(2, 1, p, d));
  EXPECT_EQ(p, cv::Point2f(2.9f, 3));

  // The middle track ends; the others keep their order and histories.
  h.retain({1, 0, 1});
  ASSERT_EQ(h.size(), 2u);
  ASSERT_TRUE(h.observation(1, 1, p, d));
  EXPECT_EQ(p, cv::Point2f(2.9f, 3));
  ASSERT_TRUE(h.observation(0, 1, p, d));
  EXPECT_EQ(p, cv::Point2f(1, 1));

  // Three more frames: the ring (depth 4) keeps 3 frames back; a break in consistency restarts the count.
  for (int k = 1; k <= 3; ++k) {
    h.next_frame({{1.5f + k, 1}, {3.0f + k, 3}}, {5.0f + k, 7.0f + k}, {1, static_cast<uint8_t>(k == 2 ? 0 : 1)});
  }
  EXPECT_EQ(h.age(0), 3);
  ASSERT_TRUE(h.observation(0, 3, p, d));
  EXPECT_EQ(p, cv::Point2f(1.5f, 1));
  EXPECT_FALSE(h.observation(0, 4, p, d));
  EXPECT_EQ(h.consistent_steps(0), 3);
  EXPECT_EQ(h.consistent_steps(1), 1);
  h.clear();
  EXPECT_EQ(h.size(), 0u);
}

// Exact tracks of 3-D points seen by a camera driving +z at 0.06 m per frame (20 Hz: 1.2 m/s); the box (id 1)
// drives along at the same speed.
struct WalkerRun {
  static constexpr int kFrames = 13;
  static constexpr double kStep = 0.06;
  CorridorScene scene;
  TrackHistory history{13};
  MultiFrameTest test;
  std::vector<Eigen::Vector3d> points_w;  // at frame 0
  std::vector<int> on_box;
  std::vector<cv::Mat> cur_pyramid;
  int slid = -1, mismatched = -1;  // indices of the two doctored static tracks
  // How the box's tracks are marked in the step 2 frames before the last (TrackHistory::next_frame).
  uint8_t box_step_consistency = TrackHistory::kStepConsistent;

  // The rendered frames, once for all tests.
  StereoFrame frame(int k) const {
    static std::vector<StereoFrame> frames;
    if (frames.empty()) {
      for (int j = 0; j < kFrames; ++j) {
        frames.push_back(scene.render_frame(camera_pose(0, 0, kStep * j), Eigen::Vector3d(0, 0, kStep * j), true,
                                            static_cast<std::size_t>(j)));
      }
    }
    return frames[static_cast<std::size_t>(k)];
  }

  explicit WalkerRun(const MultiFrameTestConfig& config = {}, uint8_t box_step = TrackHistory::kStepConsistent)
      : test(config), box_step_consistency(box_step) {
    // Static points on the back wall (left of where the box hides it), the left wall and the pillar; points on
    // the box. Only points in view over the whole run.
    std::vector<Eigen::Vector3d> candidates;
    std::vector<int> candidate_on_box;
    for (double x = -2.2; x <= -0.7; x += 0.25) {
      for (double y = -2.5; y <= 0.2; y += 0.3) {
        candidates.emplace_back(x, y, 8.0);
        candidate_on_box.push_back(0);
      }
    }
    for (double z = 4.0; z <= 6.5; z += 0.5) {
      for (double y = -2.0; y <= 0.2; y += 0.4) {
        candidates.emplace_back(-2.5, y, z);
        candidate_on_box.push_back(0);
      }
    }
    for (double x = 1.7; x <= 2.35; x += 0.2) {
      for (double y = -2.0; y <= 0.2; y += 0.4) {
        candidates.emplace_back(x, y, 5.0);
        candidate_on_box.push_back(0);
      }
    }
    for (double x = -0.1; x <= 0.7; x += 0.1) {
      for (double y = -1.0; y <= 0.4; y += 0.2) {
        candidates.emplace_back(x, y, 3.0);
        candidate_on_box.push_back(1);
      }
    }
    const PinholeCamera& cam = scene.camera;
    auto in_view = [&](const Eigen::Vector3d& X) {
      const double u = cam.fx * X.x() / X.z() + cam.cx, v = cam.fy * X.y() / X.z() + cam.cy;
      return X.z() > 0.5 && u >= 20 && v >= 20 && u < cam.width - 20 && v < cam.height - 20;
    };
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const Eigen::Vector3d last =
          candidates[i] - Eigen::Vector3d(0, 0, candidate_on_box[i] ? 0.0 : kStep * (kFrames - 1));
      if (!in_view(candidates[i]) || !in_view(last)) continue;
      points_w.push_back(candidates[i]);
      on_box.push_back(candidate_on_box[i]);
    }
    slid = 3;
    mismatched = 7;
    LkTracker tracker;
    const double bf = scene.camera.fx * scene.baseline_m;
    for (int k = 0; k < kFrames; ++k) {
      const SE3d T_w_c = camera_pose(0, 0, kStep * k);
      const Eigen::Vector3d box_offset(0, 0, kStep * k);
      const StereoFrame f = frame(k);
      std::vector<cv::Point2f> px(points_w.size());
      std::vector<float> d(points_w.size());
      std::vector<uint8_t> consistent(points_w.size(), TrackHistory::kStepConsistent);
      if (k == kFrames - 1 - 2) {
        for (std::size_t i = 0; i < points_w.size(); ++i) {
          if (on_box[i]) consistent[i] = box_step_consistency;
        }
      }
      for (std::size_t i = 0; i < points_w.size(); ++i) {
        const Eigen::Vector3d X = T_w_c.inverse() * (points_w[i] + (on_box[i] ? box_offset : Eigen::Vector3d::Zero()));
        px[i] = cv::Point2f(static_cast<float>(scene.camera.fx * X.x() / X.z() + scene.camera.cx),
                            static_cast<float>(scene.camera.fy * X.y() / X.z() + scene.camera.cy));
        d[i] = static_cast<float>(bf / X.z());
      }
      // Frame 7 (the reference of the last frame, 5 frames back): the "slid" track is 4 px off where its point
      // is, and the "mismatched" one has a wrong disparity, which the next frame's per-frame test notices.
      if (k == kFrames - 1 - 5) {
        px[static_cast<std::size_t>(slid)].x += 4.0f;
        d[static_cast<std::size_t>(mismatched)] += 6.0f;
      }
      if (k == kFrames - 1 - 4) consistent[static_cast<std::size_t>(mismatched)] = 0;
      if (k == 0) {
        for (std::size_t i = 0; i < px.size(); ++i) history.add(px[i], d[i]);
        test.add_frame(SE3d::Identity(), false, f.left);
      } else {
        history.next_frame(px, d, consistent);
        test.add_frame(camera_pose(0, 0, kStep * k).inverse() * camera_pose(0, 0, kStep * (k - 1)), true, f.left);
      }
      if (k == kFrames - 1) tracker.build_pyramid(f.left, cur_pyramid);
    }
  }
};

TEST(MultiFrameTest, FindsABoxKeepingItsDistanceAheadAndNoStaticPoint) {
  WalkerRun run;
  MultiFrameResult r;
  run.test.run(run.scene.camera, run.scene.camera.fx * run.scene.baseline_m, run.history,
               std::vector<uint8_t>(run.history.size(), 1), run.cur_pyramid, LkTrackerConfig{}, r);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.frames_back, 5);  // the newest frame >= 0.3 m back
  EXPECT_NEAR(r.translation_m, 0.30, 1e-6);
  EXPECT_NEAR(r.T_cur_ref.translation().z(), -0.30, 0.01);
  int box = 0, box_dynamic = 0, static_dynamic = 0;
  for (std::size_t i = 0; i < run.points_w.size(); ++i) {
    if (run.on_box[i]) {
      ++box;
      box_dynamic += r.test.dynamic[i];
    } else {
      static_dynamic += r.test.dynamic[i];
    }
  }
  // The box keeps its disparity (~18.4 px) where a static surface would have come 0.3 m closer (20.4 px): every
  // box point is off in disparity, the ones away from the focus of expansion in position too.
  EXPECT_GE(box_dynamic, box * 9 / 10) << box_dynamic << " of " << box;
  EXPECT_EQ(static_dynamic, 0);
  // The mismatched track does not take part; the slid one is re-found by the verification and is static.
  EXPECT_LT(r.test.reprojection_px[static_cast<std::size_t>(run.mismatched)], 0);
  EXPECT_FALSE(r.test.dynamic[static_cast<std::size_t>(run.slid)]);
  EXPECT_GE(r.test.reprojection_px[static_cast<std::size_t>(run.slid)], 0);
  EXPECT_LT(r.test.reprojection_px[static_cast<std::size_t>(run.slid)], 1.0);
}

TEST(TrackHistory, CountsStepsTheDepthTestPassedApartFromStepsOnlyTheStereoAgreedOn) {
  TrackHistory h(6);
  h.add({1, 1}, 5.0f);
  h.add({2, 2}, 6.0f);
  const std::vector<cv::Point2f> px = {{1, 1}, {2, 2}};
  const std::vector<float> d = {5.0f, 6.0f};
  constexpr uint8_t ok = TrackHistory::kStepConsistent, stereo = TrackHistory::kStepStereoOnly;
  h.next_frame(px, d, {ok, ok});
  h.next_frame(px, d, {stereo, ok});                     // track 0: the per-frame test flagged it, its stereo agreed
  h.next_frame(px, d, {ok, TrackHistory::kStepBroken});  // track 1: a stereo mismatch
  EXPECT_EQ(h.consistent_steps(0), 3);
  EXPECT_EQ(h.consistent_steps_strict(0), 1);
  EXPECT_EQ(h.consistent_steps(1), 0);
  EXPECT_EQ(h.consistent_steps_strict(1), 0);
  h.retain({0, 1});
  EXPECT_EQ(h.consistent_steps(0), 0);
  EXPECT_EQ(h.consistent_steps_strict(0), 0);
}

TEST(MultiFrameTest, TracksChainedOnStereoAloneAreTestedAgainstAHigherThreshold) {
  // The box's tracks were flagged by the per-frame test in one step since the reference (kStepStereoOnly: only
  // their stereo agreed). By default such tracks are not tested at all; with chain_stereo_only they are, and they are
  // dynamic only when off by chain_stereo_factor times the thresholds. The box keeps its distance: its disparity
  // residual (~2 px) is above the threshold (~1.9 px) but not 3 times above it; its points away from the focus of
  // expansion are off in position by more.
  struct Outcome {
    int tested = 0, dynamic = 0, static_dynamic = 0, box = 0;
  };
  auto run_with = [](const MultiFrameTestConfig& c) {
    WalkerRun run(c, TrackHistory::kStepStereoOnly);
    MultiFrameResult r;
    const double bf = run.scene.camera.fx * run.scene.baseline_m;
    run.test.run(run.scene.camera, bf, run.history, std::vector<uint8_t>(run.history.size(), 1), run.cur_pyramid,
                 LkTrackerConfig{}, r);
    EXPECT_TRUE(r.valid);
    Outcome o;
    for (std::size_t i = 0; i < run.points_w.size(); ++i) {
      if (!run.on_box[i]) {
        o.static_dynamic += r.test.dynamic[i];
        continue;
      }
      ++o.box;
      o.tested += r.test.reprojection_px[i] >= 0 ? 1 : 0;
      o.dynamic += r.test.dynamic[i];
      if (r.test.dynamic[i] && c.chain_stereo_factor > 1) {
        // Flagged by its position alone: the disparity residual is under 3x its threshold.
        cv::Point2f p;
        float d = 0;
        run.history.observation(i, 0, p, d);
        EXPECT_GT(r.test.reprojection_px[i], c.chain_stereo_factor * (r.test.a_reproj_used_px + c.b_reproj * d));
      }
    }
    return o;
  };
  MultiFrameTestConfig c;
  c.chain_stereo_only = false;
  const Outcome unchained = run_with(c);
  EXPECT_EQ(unchained.tested, 0);
  EXPECT_EQ(unchained.dynamic, 0);
  c.chain_stereo_only = true;
  c.chain_stereo_factor = 1.0;
  const Outcome plain = run_with(c);
  EXPECT_EQ(plain.tested, plain.box);
  EXPECT_GE(plain.dynamic, plain.box * 9 / 10);
  c.chain_stereo_factor = 3.0;
  const Outcome strict = run_with(c);
  EXPECT_EQ(strict.tested, strict.box);
  EXPECT_LT(strict.dynamic, plain.dynamic * 3 / 4);
  EXPECT_GT(strict.dynamic, 0);
  EXPECT_EQ(unchained.static_dynamic + plain.static_dynamic + strict.static_dynamic, 0);
  std::printf("box tracks %d: dynamic %d with factor 1, %d with factor 3\n", plain.box, plain.dynamic, strict.dynamic);
}

TEST(MultiFrameTest, NeedsAChainAndEnoughSharedTracks) {
  MultiFrameTestConfig c;
  c.min_points = 1000;  // more than the run has
  WalkerRun run(c);
  MultiFrameResult r;
  const double bf = run.scene.camera.fx * run.scene.baseline_m;
  run.test.run(run.scene.camera, bf, run.history, std::vector<uint8_t>(run.history.size(), 1), run.cur_pyramid,
               LkTrackerConfig{}, r);
  EXPECT_FALSE(r.valid);
  for (uint8_t v : r.test.dynamic) EXPECT_EQ(v, 0);
  // A broken chain (invalid motion this frame) leaves nothing to compare with.
  WalkerRun broken;
  broken.test.add_frame(SE3d::Identity(), false, cv::Mat(480, 752, CV_8UC1, cv::Scalar(0)));
  broken.test.run(broken.scene.camera, bf, broken.history, std::vector<uint8_t>(broken.history.size(), 1),
                  broken.cur_pyramid, LkTrackerConfig{}, r);
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(broken.test.chain_length(), 1);
}

TEST(MultiFrameTest, StandingStillUsesTheOldestFrame) {
  MultiFrameTest test;
  TrackHistory history(13);
  const CorridorScene scene;
  const StereoFrame f = scene.render_frame(SE3d::Identity(), Eigen::Vector3d::Zero(), false, 0);
  std::vector<cv::Point2f> px;
  std::vector<float> d;
  for (int y = 40; y < 440; y += 40) {
    for (int x = 40; x < 720; x += 40) {
      px.emplace_back(static_cast<float>(x), static_cast<float>(y));
      d.push_back(8.0f);
    }
  }
  for (std::size_t i = 0; i < px.size(); ++i) history.add(px[i], d[i]);
  test.add_frame(SE3d::Identity(), false, f.left);
  for (int k = 1; k <= 20; ++k) {
    history.next_frame(px, d, std::vector<uint8_t>(px.size(), 1));
    test.add_frame(SE3d::Identity(), true, f.left);
  }
  std::vector<cv::Mat> pyramid;
  LkTracker().build_pyramid(f.left, pyramid);
  MultiFrameResult r;
  test.run(scene.camera, scene.camera.fx * scene.baseline_m, history, std::vector<uint8_t>(px.size(), 1), pyramid,
           LkTrackerConfig{}, r);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.frames_back, 12);
  EXPECT_EQ(test.chain_length(), 13);
  for (uint8_t v : r.test.dynamic) EXPECT_EQ(v, 0);
}

// Aperture check on built patches: on a horizontal step edge only the vertical part of the offset counts; a
// textured patch is well conditioned (-1: the whole offset counts).
TEST(MultiFrameTest, ApertureCheckKeepsOnlyTheOffsetAcrossAnEdge) {
  cv::Mat image(120, 160, CV_8UC1, cv::Scalar(60));
  image.rowRange(60, 120).setTo(180);  // horizontal edge at y = 60 for x < 80
  cv::Mat textured = image.colRange(80, 160);
  cv::randu(textured, cv::Scalar(0), cv::Scalar(255));     // x >= 80: random texture
  const PinholeCamera camera{400, 400, 80, 60, 160, 120};  // fx, fy, cx, cy, width, height
  const double bf = 40;
  const SE3d still = SE3d::Identity();
  const cv::Point2f on_edge(40, 60);
  // Slid 4 px along the edge: nothing across it.
  EXPECT_NEAR(offset_across_edge(image, on_edge, 5, camera, bf, still, on_edge + cv::Point2f(4, 0), 8.0f, 0.15), 0.0,
              1e-6);
  // 3 px across and 4 px along: the 3 px count.
  EXPECT_NEAR(offset_across_edge(image, on_edge, 5, camera, bf, still, on_edge + cv::Point2f(4, 3), 8.0f, 0.15), 3.0,
              1e-6);
  // A textured patch and a flat one: not edge-like, the whole offset counts.
  EXPECT_EQ(offset_across_edge(image, cv::Point2f(120, 60), 5, camera, bf, still, cv::Point2f(124, 60), 8.0f, 0.15),
            -1);
  EXPECT_EQ(offset_across_edge(image, cv::Point2f(40, 20), 5, camera, bf, still, cv::Point2f(44, 20), 8.0f, 0.15), -1);
  // The prediction moves with the camera: 0.1 m to the right makes a point at 5 m (d = 8 px) appear 8 px left.
  SE3d right = SE3d::Identity();
  right.translation() = Eigen::Vector3d(-0.1, 0, 0);
  EXPECT_NEAR(offset_across_edge(image, on_edge, 5, camera, bf, right, on_edge + cv::Point2f(8, 2), 8.0f, 0.15), 2.0,
              1e-6);
  // Too close to the border to sample the patch.
  EXPECT_EQ(offset_across_edge(image, cv::Point2f(3, 60), 5, camera, bf, still, cv::Point2f(7, 60), 8.0f, 0.15), -1);
}

TEST(MultiFrameTest, InvalidConfigurationNamesTheField) {
  MultiFrameTestConfig c;
  c.min_frames = 20;  // > max_frames
  try {
    MultiFrameTest t(c);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "multiframe.min_frames");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
