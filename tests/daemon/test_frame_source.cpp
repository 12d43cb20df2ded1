// Frame sources: a dataset played like a camera (order, range, loop, pacing on an absolute schedule, lossless at
// rate 0, capture stamps on CLOCK_REALTIME; agvslam-run's laps, black frames and ground-truth masks), what
// prepare_source() checks, and a camera that is not there.
#include "agvslam/daemon/frame_source.h"

#include <gtest/gtest.h>
#include <time.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "agvslam/core/error.h"
#include "agvslam/drivers/v4l2/device.h"
#include "daemon_test_util.h"

namespace agvslam::daemon {
namespace {

namespace fs = std::filesystem;

int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

using test::tiny_dataset;

DaemonConfig dataset_config(const std::string& dir, double rate, bool loop = false, const std::string& frames = "") {
  DaemonConfig c;
  c.path = "test.yaml";
  c.source.type = SourceType::kDataset;
  c.source.dataset = dir;
  c.source.rate = rate;
  c.source.loop = loop;
  c.source.frames = frames;
  return c;
}

TEST(DatasetSource, PlaysEveryFrameInOrderThenEnds) {
  const std::string dir = tiny_dataset(5);
  const DaemonConfig c = dataset_config(dir, 0);
  const SourceSetup setup = prepare_source(c);
  EXPECT_DOUBLE_EQ(setup.rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(setup.slam_rate_hz, 20.0);
  EXPECT_EQ(setup.calibration.left.width, 64);
  DatasetSource source(setup, c.source);
  EXPECT_TRUE(source.lossless());
  CapturedFrame f;
  for (int i = 0; i < 5; ++i) {
    const int64_t before = realtime_ns();
    ASSERT_EQ(source.grab(f, 100), FrameSource::Grab::kFrame);
    EXPECT_EQ(f.source_index, i);
    EXPECT_EQ(f.frame.index, static_cast<std::size_t>(i));
    EXPECT_EQ(f.source_t_ns, 50000000LL * i);
    EXPECT_EQ(f.frame.left.at<uint8_t>(10, 10), 10 * i);
    EXPECT_EQ(f.frame.right.at<uint8_t>(10, 10), 10 * i + 1);
    EXPECT_GE(f.capture_t_ns, before);  // stamped when delivered, on CLOCK_REALTIME
    EXPECT_LE(f.capture_t_ns, realtime_ns());
  }
  EXPECT_EQ(source.grab(f, 100), FrameSource::Grab::kEnd);
  EXPECT_EQ(source.stats().frames, 5U);
  fs::remove_all(dir);
}

TEST(DatasetSource, LoopsOverTheRangeAndCountsDeliveredFrames) {
  const std::string dir = tiny_dataset(6);
  const DaemonConfig c = dataset_config(dir, 0, /*loop=*/true, "2:4");
  const SourceSetup setup = prepare_source(c);
  DatasetSource source(setup, c.source);
  CapturedFrame f;
  std::vector<int64_t> seen;
  for (int i = 0; i < 7; ++i) {
    ASSERT_EQ(source.grab(f, 100), FrameSource::Grab::kFrame);
    seen.push_back(f.source_index);
    EXPECT_EQ(f.frame.index, static_cast<std::size_t>(i));
  }
  EXPECT_EQ(seen, (std::vector<int64_t>{2, 3, 4, 2, 3, 4, 2}));
  fs::remove_all(dir);
}

// Unreadable images (empty, truncated, not an image, another size) are skipped and counted, in a loop too; a range
// with nothing readable is an error that names a file.
TEST(DatasetSource, SkipsAndCountsUnreadableFramesButNotAWholeUnreadableRange) {
  const std::string dir = tiny_dataset(8);
  test::write_text(dir + "/image_0/000001.png", "");
  const std::string png = test::read_text(dir + "/image_1/000003.png");
  test::write_text(dir + "/image_1/000003.png", png.substr(0, png.size() / 2));
  test::write_text(dir + "/image_0/000004.png", "not a PNG at all");
  cv::imwrite(dir + "/image_1/000006.png", cv::Mat(24, 32, CV_8UC1, cv::Scalar(61)));
  {
    const DaemonConfig c = dataset_config(dir, 0, /*loop=*/true);
    DatasetSource source(prepare_source(c), c.source);
    CapturedFrame f;
    std::vector<int64_t> seen;
    for (int i = 0; i < 6; ++i) {
      ASSERT_EQ(source.grab(f, 100), FrameSource::Grab::kFrame);
      seen.push_back(f.source_index);
      EXPECT_EQ(f.frame.left.at<uint8_t>(10, 10), 10 * f.source_index);
    }
    EXPECT_EQ(seen, (std::vector<int64_t>{0, 2, 5, 7, 0, 2}));
    EXPECT_EQ(source.stats().dropped, 5U);  // 1, 3, 4, 6 and, in the second lap, 1 again
    EXPECT_NE(source.stats().line.find("5 unreadable skipped"), std::string::npos) << source.stats().line;
  }
  {
    const DaemonConfig c = dataset_config(dir, 0, /*loop=*/false, "3:4");
    DatasetSource source(prepare_source(c), c.source);
    CapturedFrame f;
    try {
      source.grab(f, 100);
      ADD_FAILURE() << "a range of unreadable frames played";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("000004.png"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

TEST(DatasetSource, ReleasesFramesOnAnAbsoluteScheduleAndReturnsWithinTheTimeout) {
  const std::string dir = tiny_dataset(4);
  DaemonConfig c = dataset_config(dir, 1.0);
  c.source.rate_hz = 25;  // 40 ms apart
  const SourceSetup setup = prepare_source(c);
  DatasetSource source(setup, c.source);
  EXPECT_FALSE(source.lossless());
  std::vector<int64_t> stamps;
  CapturedFrame f;
  int no_frame = 0;
  while (stamps.size() < 4) {
    const FrameSource::Grab g = source.grab(f, 5);  // shorter than the period: kNoFrame in between
    if (g == FrameSource::Grab::kFrame) stamps.push_back(f.capture_t_ns);
    if (g == FrameSource::Grab::kNoFrame) ++no_frame;
    ASSERT_NE(g, FrameSource::Grab::kEnd);
  }
  EXPECT_GT(no_frame, 0);
  // Frame k is released no earlier than k periods after the first (a loaded machine only delays it).
  for (std::size_t k = 1; k < stamps.size(); ++k)
    EXPECT_GE(stamps[k] - stamps[0], static_cast<int64_t>(k) * 40000000LL - 1000000);
  fs::remove_all(dir);
}

TEST(DatasetSource, PlaysLapsWithContinuingStampsBlackFramesAndGroundTruthMasks) {
  const std::string dir = tiny_dataset(5, /*with_masks=*/true);
  const DaemonConfig c = dataset_config(dir, 0, false, "1:3");
  const SourceSetup setup = prepare_source(c);
  DatasetPlayback playback;
  playback.laps = 2;
  playback.blank = std::make_pair(std::size_t(2), std::size_t(2));
  playback.ground_truth_masks = true;
  // One lap: frames 1..3 at 20 Hz, 0.1 s from the first stamp to the last, plus one period.
  EXPECT_EQ(lap_duration_ns(*setup.dataset, 1, 3), 150000000LL);
  DatasetSource source(setup, c.source, playback);
  CapturedFrame f;
  std::vector<int64_t> index, t_ns;
  for (int k = 0; k < 6; ++k) {
    ASSERT_EQ(source.grab(f, 100), FrameSource::Grab::kFrame) << k;
    index.push_back(f.source_index);
    t_ns.push_back(f.frame.t_ns);
    EXPECT_EQ(f.lap, k / 3);
    EXPECT_EQ(f.source_t_ns, 50000000LL * f.source_index);  // the dataset's own stamp, whatever the lap
    EXPECT_EQ(f.blank, f.source_index == 2);
    EXPECT_EQ(f.frame.left.at<uint8_t>(10, 10), f.blank ? 0 : 10 * f.source_index);
    EXPECT_EQ(f.frame.right.at<uint8_t>(10, 10), f.blank ? 0 : 10 * f.source_index + 1);
    ASSERT_FALSE(f.ground_truth_mask.empty());
    EXPECT_EQ(cv::countNonZero(f.ground_truth_mask.col(static_cast<int>(f.source_index))), 48);
    EXPECT_EQ(cv::countNonZero(f.ground_truth_mask), 48);
  }
  EXPECT_EQ(source.grab(f, 100), FrameSource::Grab::kEnd);
  EXPECT_EQ(index, (std::vector<int64_t>{1, 2, 3, 1, 2, 3}));
  EXPECT_EQ(t_ns, (std::vector<int64_t>{50000000, 100000000, 150000000, 200000000, 250000000, 300000000}));
  fs::remove_all(dir);
}

TEST(DatasetSource, PacedPlayIsLosslessWhenAskedAndMasksOnlyWhenAsked) {
  const std::string dir = tiny_dataset(2);
  const DaemonConfig c = dataset_config(dir, 1.0);
  const SourceSetup setup = prepare_source(c);
  EXPECT_FALSE(DatasetSource(setup, c.source).lossless());
  DatasetPlayback playback;
  playback.lossless = true;
  DatasetSource source(setup, c.source, playback);
  EXPECT_TRUE(source.lossless());
  CapturedFrame f;
  ASSERT_EQ(source.grab(f, 100), FrameSource::Grab::kFrame);
  EXPECT_TRUE(f.ground_truth_mask.empty());
  EXPECT_FALSE(f.blank);
  EXPECT_EQ(f.lap, 0);
  fs::remove_all(dir);
}

TEST(PrepareSource, NamesTheSettingThatLedToAnUnreadableFileOrAMismatch) {
  const std::string dir = tiny_dataset(3);
  auto expect_field = [](const DaemonConfig& c, const std::string& field) {
    try {
      prepare_source(c);
      ADD_FAILURE() << "no error, expected one naming " << field;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("test.yaml: " + field), std::string::npos) << e.what();
    }
  };
  expect_field(dataset_config(dir + "/missing", 1), "source.dataset");
  expect_field(dataset_config(dir, 1, false, "5:9"), "source.frames");
  // The camera: the calibration must be for its image size, and the SLAM must know the rate.
  DaemonConfig cam;
  cam.path = "test.yaml";
  cam.source.type = SourceType::kV4l2;
  cam.calibration_file = dir + "/calib.txt";  // 64x48 is taken from the camera size for KITTI files ...
  cam.camera.width = 64;
  cam.camera.height = 48;
  EXPECT_NO_THROW(prepare_source(cam));
  cam.calibration_file = std::string(AGVSLAM_SOURCE_DIR) + "/params/agvslamd_calibration_example.yaml";  // 752x480
  expect_field(cam, "calibration.file");
  cam.calibration_file = dir + "/nothing.yaml";
  expect_field(cam, "calibration.file");
  cam.calibration_file = dir + "/calib.txt";
  cam.camera.fps = 0;
  expect_field(cam, "pipeline.frame_rate_hz");
  cam.pipeline.frame_rate_hz = 15;
  EXPECT_DOUBLE_EQ(prepare_source(cam).slam_rate_hz, 15.0);
  fs::remove_all(dir);
}

TEST(V4l2Source, AnAbsentCameraIsRetriedOrReportedByName) {
  const std::string dir = tiny_dataset(1);
  DaemonConfig c;
  c.path = "test.yaml";
  c.source.type = SourceType::kV4l2;
  c.calibration_file = dir + "/calib.txt";
  c.camera.width = 64;
  c.camera.height = 48;
  c.camera.left_device = dir + "/no-video-left";
  c.camera.right_device = dir + "/no-video-right";
  c.camera.reopen_backoff_initial_ms = 20;
  const SourceSetup setup = prepare_source(c);
  // Without waiting: the device's error, naming it.
  try {
    V4l2Source source(setup, c.camera, /*wait_for_camera=*/false);
    ADD_FAILURE() << "opened a device that does not exist";
  } catch (const drivers::v4l2::V4l2Error& e) {
    EXPECT_NE(std::string(e.what()).find("no-video-left"), std::string::npos) << e.what();
  }
  // Waiting: grab() keeps returning within its time-out while it retries, and says the camera is not there.
  V4l2Source source(setup, c.camera, /*wait_for_camera=*/true);
  CapturedFrame f;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(source.grab(f, 30), FrameSource::Grab::kNoFrame);
  const SourceStats st = source.stats();
  EXPECT_FALSE(st.connected);
  EXPECT_EQ(st.frames, 0U);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace agvslam::daemon
