// The System facade on real data (KITTI 06 and EuRoC V1_01 excerpts in ../shared/data): trajectory accuracy against
// ground truth, a still camera staying still, loss on blank frames without garbage, reset, and the dynamic mask.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "agvslam/eval/association.h"
#include "agvslam/eval/metrics.h"
#include "agvslam/features/features_config.h"
#include "agvslam/io/dataset.h"
#include "agvslam/slam/system.h"
#include "common/test_data.h"

namespace agvslam::slam {
namespace {

SystemConfig inline_config(const io::StereoDataset& d) {
  SystemConfig c;
  c.frame_rate_hz = d.rate_hz();
  c.threaded_mapping = false;  // deterministic
  return c;
}

double ate_rmse(const io::StereoDataset& d, const Trajectory& est) {
  const auto gt = d.ground_truth();
  if (!gt) return -1;
  const auto pairs = eval::associate_by_timestamp(*gt, est, 5'000'000);
  if (pairs.size() < 3) return -1;
  return eval::compute_ate(pairs, eval::AlignMode::kSE3).translation_m.rmse;
}

TEST(System, KittiExcerptTracksEveryFrameAccurately) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto d = io::open_dataset(root);
  SystemConfig c = inline_config(*d);
  // ORB-SLAM2's KITTI settings (2000 features, descriptor stereo matching).
  const features::FeaturesConfig fc = features::load_features_config(AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml");
  c.orb = fc.orb;
  c.stereo = fc.stereo_matching;
  System slam(d->calibration(), c);
  int ok = 0;
  for (std::size_t i = 0; i < d->size(); ++i) {
    const StereoFrame f = d->frame(i);
    const TrackResult r = slam.track_stereo(f.t_ns, f.left, f.right, {});
    if (r.state == TrackingState::kOk) {
      ++ok;
      EXPECT_TRUE(r.pose_valid);
      EXPECT_TRUE(is_valid_pose(r.T_w_c));
    }
  }
  EXPECT_EQ(ok, static_cast<int>(d->size()));
  const Trajectory traj = slam.trajectory();
  EXPECT_EQ(traj.size(), d->size());
  const double ate = ate_rmse(*d, traj);
  // ORB-SLAM2 stereo on the same frames on this machine: 0.054 m (0.050-0.057).
  EXPECT_GE(ate, 0);
  EXPECT_LT(ate, 0.054);
  EXPECT_GE(slam.map().keyframe_count(), 3u);
}

TEST(System, KittiExcerptWithTheMappingThread) {
  // The same with local mapping in its own thread (as on the vehicle; the order of events varies from run to run).
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto d = io::open_dataset(root);
  SystemConfig c = inline_config(*d);
  c.threaded_mapping = true;
  const features::FeaturesConfig f = features::load_features_config(AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml");
  c.orb = f.orb;
  c.stereo = f.stereo_matching;
  System slam(d->calibration(), c);
  std::size_t max_queue = 0;
  // Frames arrive at the camera's 10 Hz, as on the vehicle.
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < d->size(); ++i) {
    const StereoFrame fr = d->frame(i);
    std::this_thread::sleep_until(
        t0 + std::chrono::milliseconds(static_cast<int64_t>(1000.0 * static_cast<double>(i) / d->rate_hz())));
    const TrackResult r = slam.track_stereo(fr.t_ns, fr.left, fr.right, {});
    EXPECT_EQ(r.state, TrackingState::kOk) << "frame " << i;
    max_queue = std::max(max_queue, r.mapping_queue);
  }
  slam.wait_for_mapping();
  EXPECT_LE(max_queue, static_cast<std::size_t>(c.slam.mapping.queue_capacity));
  const double ate = ate_rmse(*d, slam.trajectory());
  const LocalMappingStats ms = slam.mapping_stats();
  std::printf(
      "KITTI 06 excerpt, mapping thread: ATE %.4f m, max queue %zu, keyframes %llu (%llu skipped), BA %llu (%llu "
      "aborted)\n",
      ate, max_queue, static_cast<unsigned long long>(ms.keyframes_processed),
      static_cast<unsigned long long>(ms.keyframes_skipped), static_cast<unsigned long long>(ms.ba_runs),
      static_cast<unsigned long long>(ms.ba_aborted));
  // The order of tracking and mapping events varies from run to run, and so does the result: 13 runs on this
  // machine gave 0.036-0.071 m, median 0.052 m (ORB-SLAM2: 0.050-0.057 m over three runs). The deterministic
  // inline test above holds the 0.054 m bound; this one catches breakage of the threaded path.
  EXPECT_GE(ate, 0);
  EXPECT_LT(ate, 0.085);
  EXPECT_GT(ms.keyframes_processed, 3u);
  slam.shutdown();
}

TEST(System, EurocStillCameraDoesNotDrift) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto d = io::open_dataset(root);
  System slam(d->calibration(), inline_config(*d));
  std::vector<Eigen::Vector3d> positions;
  for (std::size_t i = 0; i < d->size(); ++i) {
    const StereoFrame f = d->frame(i);
    const TrackResult r = slam.track_stereo(f.t_ns, f.left, f.right, {});
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << i;
    positions.push_back(r.T_w_c.translation());
  }
  double drift = 0;
  for (const auto& p : positions) drift = std::max(drift, (p - positions.front()).norm());
  EXPECT_LT(drift, 0.01);
}

TEST(System, BlankFramesGiveLostWithoutAPoseThenTrackingResumes) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto d = io::open_dataset(root);
  SystemConfig c = inline_config(*d);
  c.slam.tracking.reset_max_keyframes = 0;  // a still camera has a single keyframe: keep the map, do not reset
  System slam(d->calibration(), c);
  const cv::Mat black = cv::Mat::zeros(d->calibration().left.size(), CV_8UC1);
  int lost = 0, ok_after = 0;
  for (std::size_t i = 0; i < 60; ++i) {
    const StereoFrame f = d->frame(i);
    const bool blank = i >= 30 && i < 40;
    const TrackResult r =
        blank ? slam.track_stereo(f.t_ns, black, black, {}) : slam.track_stereo(f.t_ns, f.left, f.right, {});
    if (blank) {
      EXPECT_NE(r.state, TrackingState::kOk) << "frame " << i;
      EXPECT_FALSE(r.pose_valid);
      EXPECT_TRUE(r.T_w_c.isApprox(SE3d::Identity()));
      lost += r.state == TrackingState::kLost ? 1 : 0;
    } else if (i >= 40) {
      ok_after += r.state == TrackingState::kOk ? 1 : 0;
    }
  }
  EXPECT_EQ(lost, 10);
  // The view is the same as before the blank frames: recovered against the last reference keyframe.
  EXPECT_GE(ok_after, 18);
  const Trajectory traj = slam.trajectory();
  EXPECT_EQ(traj.size(), 50u);
}

TEST(System, RequestResetStartsAgain) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto d = io::open_dataset(root);
  SystemConfig c = inline_config(*d);
  c.threaded_mapping = true;
  System slam(d->calibration(), c);
  for (std::size_t i = 0; i < 10; ++i) {
    const StereoFrame f = d->frame(i);
    EXPECT_EQ(slam.track_stereo(f.t_ns, f.left, f.right, {}).state, TrackingState::kOk);
  }
  slam.request_reset();
  const StereoFrame f = d->frame(10);
  const TrackResult r = slam.track_stereo(f.t_ns, f.left, f.right, {});
  EXPECT_TRUE(r.counts.reset);
  EXPECT_EQ(r.state, TrackingState::kOk);  // initialised again on this frame
  EXPECT_EQ(r.keyframes, 1u);
  slam.shutdown();
}

TEST(System, NoFeaturesInsideTheDynamicMask) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto d = io::open_dataset(root);
  System slam(d->calibration(), inline_config(*d));
  const StereoFrame f = d->frame(0);
  cv::Mat mask = cv::Mat::zeros(f.left.size(), CV_8UC1);
  const cv::Rect moving(f.left.cols / 4, 0, f.left.cols / 2, f.left.rows);
  mask(moving).setTo(255);
  const TrackResult r = slam.track_stereo(f.t_ns, f.left, f.right, mask);
  ASSERT_EQ(r.state, TrackingState::kOk);
  std::lock_guard<std::mutex> lock(slam.map().mutex());
  const auto kfs = slam.map().keyframes();
  ASSERT_EQ(kfs.size(), 1u);
  ASSERT_GT(kfs[0]->size(), 100u);
  for (const cv::KeyPoint& kp : kfs[0]->keypoints) EXPECT_FALSE(moving.contains(cv::Point(kp.pt))) << kp.pt;
}

SystemConfig kitti_config(const io::StereoDataset& d) {
  SystemConfig c = inline_config(d);
  const features::FeaturesConfig f = features::load_features_config(AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml");
  c.orb = f.orb;
  c.stereo = f.stereo_matching;
  return c;
}

TEST(System, LongLossStartsANewMapAfterTheConfiguredTimeAndTrackingResumes) {
  // KITTI 06 with frames 10..25 blacked out: the car drives ~17 m meanwhile, out of reach of relocalisation. The
  // covered camera is waited out; then relocalisation gets new_map_after_lost_s of real views before a new map
  // starts from the current frame. With new_map_after_lost_s = 0 the same run stays lost to the end.
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto d = io::open_dataset(root);
  const std::string folder = test::make_temp_dir("agvslam-earlier-maps");
  for (const double after_s : {1.0, 0.0}) {
    SystemConfig c = kitti_config(*d);
    c.slam.tracking.new_map_after_lost_s = after_s;
    c.earlier_maps_folder = folder;
    System slam(d->calibration(), c);
    const cv::Mat black = cv::Mat::zeros(d->calibration().left.size(), CV_8UC1);
    long new_map_frame = -1;
    int ok_in_new_map = 0;
    for (std::size_t i = 0; i < d->size(); ++i) {
      const StereoFrame f = d->frame(i);
      const bool blank = i >= 10 && i <= 25;
      const TrackResult r =
          blank ? slam.track_stereo(f.t_ns, black, black, {}) : slam.track_stereo(f.t_ns, f.left, f.right, {});
      if (i < 10) {
        EXPECT_EQ(r.state, TrackingState::kOk) << "frame " << i;
      }
      if (blank) {
        EXPECT_FALSE(r.pose_valid) << "frame " << i;
      }
      if (r.counts.new_map) {
        EXPECT_EQ(new_map_frame, -1) << "a second new map at frame " << i;
        new_map_frame = static_cast<long>(i);
        // The new map's world frame is the camera of the frame that starts it.
        EXPECT_EQ(r.state, TrackingState::kOk);
        EXPECT_TRUE(r.T_w_c.isApprox(SE3d::Identity()));
        // Lost time counts from the first frame with a view again (the last blank frame's stamp).
        const double waited_s = 1e-9 * static_cast<double>(f.t_ns - d->frame(25).t_ns);
        EXPECT_GE(waited_s, after_s);
        EXPECT_LT(waited_s, after_s + 1.5 / d->rate_hz());
      }
      EXPECT_EQ(r.map_id, new_map_frame >= 0 && static_cast<long>(i) >= new_map_frame ? 1u : 0u) << "frame " << i;
      if (new_map_frame >= 0) {
        EXPECT_EQ(r.state, TrackingState::kOk) << "frame " << i << " after the new map";
        ok_in_new_map += r.state == TrackingState::kOk ? 1 : 0;
      }
    }
    if (after_s > 0) {
      ASSERT_GE(new_map_frame, 26);
      std::printf("new map at frame %ld, %d frames tracked in it\n", new_map_frame, ok_in_new_map);
      // Both maps' frames are in the trajectory, each pose with its map.
      std::vector<uint32_t> map_ids;
      const Trajectory traj = slam.trajectory(&map_ids);
      ASSERT_EQ(map_ids.size(), traj.size());
      EXPECT_EQ(std::count(map_ids.begin(), map_ids.end(), 0u), 10);
      EXPECT_EQ(std::count(map_ids.begin(), map_ids.end(), 1u), ok_in_new_map);
      // The map left behind was saved and loads again.
      EXPECT_TRUE(slam.earlier_map_errors().empty());
      ASSERT_EQ(slam.earlier_map_files(), std::vector<std::string>{folder + "/map_0.agvmap"});
      System reloaded(d->calibration(), kitti_config(*d));
      EXPECT_GE(reloaded.load_map(folder + "/map_0.agvmap", MapMode::kLocalisation).keyframes, 2u);
    } else {
      EXPECT_EQ(new_map_frame, -1);
      EXPECT_EQ(slam.map_id(), 0u);
      EXPECT_TRUE(slam.earlier_map_files().empty());
    }
  }
  std::filesystem::remove_all(folder);
}

TEST(System, ResetWithKeyframesStillQueuedForMapping) {
  // Local mapping far slower than the frame rate leaves keyframes queued; their points are in the map already and
  // point back at them. A reset drops the queue and clears the map: the keyframes must outlive that.
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto d = io::open_dataset(root);
  SystemConfig c = kitti_config(*d);
  c.threaded_mapping = true;
  c.test_mapping_step_delay_ms = 300;
  c.slam.tracking.keyframe_queue_wait_ms = 0;  // queue up keyframes without waiting for room
  c.slam.tracking.keyframe_queue_wait_weak_ms = 0;
  System slam(d->calibration(), c);
  std::size_t queued = 0;
  for (std::size_t i = 0; i < 8; ++i) {
    const StereoFrame f = d->frame(i);
    queued = std::max(queued, slam.track_stereo(f.t_ns, f.left, f.right, {}).mapping_queue);
  }
  EXPECT_GE(queued, 1u);
  slam.request_reset();
  const StereoFrame f = d->frame(8);
  const TrackResult r = slam.track_stereo(f.t_ns, f.left, f.right, {});
  EXPECT_TRUE(r.counts.reset);
  EXPECT_EQ(r.state, TrackingState::kOk);
  slam.wait_for_mapping();
  EXPECT_EQ(slam.map().keyframe_count(), 1u);
}

}  // namespace
}  // namespace agvslam::slam
