// rosbag2 recordings as datasets: a bag written here (rosbag_test_writer.h: the layout of ros2 bag record) read
// back through io::open_dataset, pixel for pixel; topic choice, pairing by header stamp, encodings, bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "../src/io/ros_message_decode.h"
#include "agvslam/io/calibration_io.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/rosbag_dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "io/rosbag_test_writer.h"
#include "io_test_util.h"

namespace agvslam::io {
namespace {
namespace fs = std::filesystem;
using test::BagWriter;
using testing::expect_input_error;
using testing::TempDir;

constexpr double kFx = 400.0, kFy = 401.0, kCx = 31.5, kCy = 23.5, kBaseline = 0.12;
constexpr int64_t kPeriodNs = 50'000'000;  // 20 Hz
constexpr int64_t kT0Ns = 1'700'000'000'123'456'789;

cv::Mat noise_image(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 65536 : 256);
  return image;
}

struct SyntheticBag {
  std::string left_topic = "/stereo/left/image_raw", right_topic = "/stereo/right/image_raw/compressed";
  std::string left_encoding = "mono8";
  int frames = 5;
  bool camera_info = true;
  bool big_endian_right = false;
  int64_t right_offset_ns = 0;
  std::vector<cv::Mat> left, right;  // filled by write(): the grey images written
};

// Left: Image, right: CompressedImage png (or Image when the topic does not end in /compressed), camera_info.
void write_synthetic(const std::string& dir, SyntheticBag& spec) {
  BagWriter bag(dir);
  const int left_id = bag.topic(spec.left_topic, "sensor_msgs/msg/Image");
  const bool right_png =
      spec.right_topic.size() > 11 && spec.right_topic.substr(spec.right_topic.size() - 11) == "/compressed";
  const int right_id =
      bag.topic(spec.right_topic, right_png ? "sensor_msgs/msg/CompressedImage" : "sensor_msgs/msg/Image");
  int left_info = 0, right_info = 0;
  if (spec.camera_info) {
    left_info = bag.topic("/stereo/left/camera_info", "sensor_msgs/msg/CameraInfo");
    right_info = bag.topic("/stereo/right/camera_info", "sensor_msgs/msg/CameraInfo");
  }
  const std::vector<double> K = {kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1}, R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int i = 0; i < spec.frames; ++i) {
    const int64_t t = kT0Ns + i * kPeriodNs;
    const cv::Mat left = noise_image(48, 64, CV_8UC1, 2 * i + 1), right = noise_image(48, 64, CV_8UC1, 2 * i + 2);
    spec.left.push_back(left);
    spec.right.push_back(right);
    // Recorded (messages.timestamp) in reverse order: the reader must order by header stamp.
    const int64_t recorded = kT0Ns + (spec.frames - i) * kPeriodNs;
    bag.write(left_id, recorded, test::encode_image(t, left, spec.left_encoding));
    bag.write(right_id, recorded + 1,
              right_png ? test::encode_png_image(t + spec.right_offset_ns, right, spec.big_endian_right)
                        : test::encode_image(t + spec.right_offset_ns, right, "mono8", spec.big_endian_right));
    if (spec.camera_info) {
      bag.write(left_info, recorded,
                test::encode_camera_info(t, 64, 48, {0, 0, 0, 0, 0}, K, R, test::rectified_p(kFx, kFy, kCx, kCy, 0)));
      bag.write(
          right_info, recorded,
          test::encode_camera_info(t, 64, 48, {}, K, R, test::rectified_p(kFx, kFy, kCx, kCy, -kFx * kBaseline), true));
    }
  }
}

// A KITTI calib.txt of the synthetic camera (for bags without camera_info).
std::string write_calib(const TempDir& dir) {
  const std::string p = std::to_string(kFx) + " 0 " + std::to_string(kCx) + " ";
  const std::string rest = " 0 " + std::to_string(kFy) + " " + std::to_string(kCy) + " 0 0 0 1 0\n";
  return dir.write("calib.txt", "P0: " + p + "0" + rest + "P1: " + p + std::to_string(-kFx * kBaseline) + rest);
}

void expect_same_image(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.type(), b.type()) << what;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << what;
}

// ---------------------------------------------------------------------------------------------------------------
// Real data: the KITTI 06 excerpt through a bag

TEST(RosbagDataset, Kitti06RoundTripPixelsStampsCalibrationOdometry) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto kitti = open_dataset(root);
  const auto* kitti_ds = dynamic_cast<const KittiDataset*>(kitti.get());
  ASSERT_NE(kitti_ds, nullptr);
  constexpr std::size_t kFrames = 6;

  TempDir dir("agvslam-rosbag");
  const std::string bag_dir = dir.file("kitti06_bag");
  std::vector<test::OdometryValues> odometry;
  for (std::size_t i = 0; i < kFrames; ++i) {
    for (int k = 0; k < 2; ++k) {  // wheel odometry at twice the camera rate
      test::OdometryValues o;
      o.t_ns = kitti->timestamp_ns(i) + k * 40'000'000;
      o.position[0] = 0.5 * static_cast<double>(2 * i + k);
      o.position[1] = -0.25 * static_cast<double>(i);
      o.orientation_xyzw[2] = std::sin(0.05 * static_cast<double>(i));
      o.orientation_xyzw[3] = std::cos(0.05 * static_cast<double>(i));
      o.linear[0] = 1.25 + 0.01 * static_cast<double>(i);
      o.angular[2] = -0.125 * static_cast<double>(k);
      odometry.push_back(o);
    }
  }
  test::write_kitti_bag(*kitti_ds, kFrames, bag_dir, odometry);

  const auto bag = open_dataset(bag_dir);
  ASSERT_EQ(bag->kind(), "rosbag2");
  const auto* rosbag = dynamic_cast<const RosbagDataset*>(bag.get());
  ASSERT_NE(rosbag, nullptr);
  EXPECT_EQ(rosbag->left_topic(), "/kitti/camera_gray_left/image_raw");
  EXPECT_EQ(rosbag->right_topic(), "/kitti/camera_gray_right/image_raw/compressed");
  EXPECT_EQ(rosbag->odometry_topic(), "/odom");
  EXPECT_TRUE(rosbag->calibration_from_camera_info());
  EXPECT_EQ(rosbag->skipped_images(), 0u);
  ASSERT_EQ(bag->size(), kFrames);

  // Calibration from camera_info equals calib.txt's.
  const StereoCalibration kitti_calib = load_kitti_calib(root + "/calib.txt", kitti->calibration().left.size());
  const StereoCalibration& bag_calib = bag->calibration();
  EXPECT_NEAR(bag_calib.left.fx, kitti_calib.left.fx, 1e-9);
  EXPECT_NEAR(bag_calib.left.fy, kitti_calib.left.fy, 1e-9);
  EXPECT_NEAR(bag_calib.left.cx, kitti_calib.left.cx, 1e-9);
  EXPECT_NEAR(bag_calib.left.cy, kitti_calib.left.cy, 1e-9);
  EXPECT_NEAR(bag_calib.baseline_m, kitti_calib.baseline_m, 1e-9);
  EXPECT_EQ(bag_calib.left.size(), kitti_calib.left.size());
  EXPECT_FALSE(bag_calib.needs_rectification);

  // Frames: the source images, pixel for pixel, with the source time stamps.
  for (std::size_t i = 0; i < kFrames; ++i) {
    EXPECT_EQ(bag->timestamp_ns(i), kitti->timestamp_ns(i));
    const StereoFrame from_bag = bag->frame(i), from_kitti = kitti->frame(i);
    EXPECT_EQ(from_bag.t_ns, from_kitti.t_ns);
    expect_same_image(from_bag.left, from_kitti.left, "left " + std::to_string(i));
    expect_same_image(from_bag.right, from_kitti.right, "right " + std::to_string(i));
  }
  EXPECT_NEAR(bag->rate_hz(),
              static_cast<double>(kFrames - 1) / ns_to_s(kitti->timestamp_ns(kFrames - 1) - kitti->timestamp_ns(0)),
              1e-9);

  // Odometry: every sample, exactly.
  const std::vector<BagOdometrySample>& samples = rosbag->odometry();
  ASSERT_EQ(samples.size(), odometry.size());
  const std::vector<OdometryRate> rates = bag->wheel_odometry();
  ASSERT_EQ(rates.size(), odometry.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const test::OdometryValues& o = odometry[i];
    EXPECT_EQ(samples[i].t_ns, o.t_ns);
    EXPECT_EQ(samples[i].frame_id, "odom");
    EXPECT_EQ(samples[i].child_frame_id, "base_link");
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(samples[i].T_frame_child.translation()[k], o.position[k]);
      EXPECT_EQ(samples[i].linear_mps[k], o.linear[k]);
      EXPECT_EQ(samples[i].angular_radps[k], o.angular[k]);
    }
    const Eigen::Quaterniond q(samples[i].T_frame_child.linear());
    EXPECT_NEAR(std::abs(q.z()), std::abs(o.orientation_xyzw[2]), 1e-12);
    EXPECT_NEAR(std::abs(q.w()), std::abs(o.orientation_xyzw[3]), 1e-12);
    EXPECT_EQ(rates[i].t_ns, o.t_ns);
    EXPECT_EQ(rates[i].speed_mps, o.linear[0]);
    EXPECT_EQ(rates[i].yaw_rate_radps, o.angular[2]);
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Synthetic bags

TEST(RosbagDataset, SyntheticBagFramesInStampOrderBothByteOrders) {
  TempDir dir("agvslam-rosbag");
  SyntheticBag spec;
  spec.big_endian_right = true;
  write_synthetic(dir.file("bag"), spec);
  const auto bag = open_dataset(dir.file("bag"));
  ASSERT_EQ(bag->size(), 5u);
  EXPECT_NEAR(bag->rate_hz(), 20.0, 1e-9);
  EXPECT_NEAR(bag->calibration().baseline_m, kBaseline, 1e-12);
  EXPECT_EQ(bag->calibration().left.fy, kFy);
  EXPECT_TRUE(bag->wheel_odometry().empty());
  for (std::size_t i = 0; i < bag->size(); ++i) {
    EXPECT_EQ(bag->timestamp_ns(i), kT0Ns + static_cast<int64_t>(i) * kPeriodNs);
    const StereoFrame frame = bag->frame(i);
    expect_same_image(frame.left, spec.left[i], "left");
    expect_same_image(frame.right, spec.right[i], "right");
  }
}

TEST(RosbagDataset, PairsWithinHalfAPeriodAndSkipsUnpaired) {
  TempDir dir("agvslam-rosbag");
  SyntheticBag spec;
  spec.right_offset_ns = 7'000'000;  // right camera 7 ms late, under half the 50 ms period
  write_synthetic(dir.file("bag"), spec);
  {
    // One more left image without a right partner.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(dir.file("bag/recording_0.db3").c_str(), &db), SQLITE_OK);
    const std::vector<uint8_t> lone = test::encode_image(kT0Ns + 10 * kPeriodNs, spec.left[0], "mono8");
    sqlite3_stmt* stmt = nullptr;
    sqlite3_prepare_v2(db, "INSERT INTO messages (topic_id, timestamp, data) VALUES (1, 0, ?1)", -1, &stmt, nullptr);
    sqlite3_bind_blob(stmt, 1, lone.data(), static_cast<int>(lone.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(stmt), SQLITE_DONE);
    sqlite3_finalize(stmt);
    sqlite3_close(db);
  }
  const auto bag = open_dataset(dir.file("bag"));
  const auto& rosbag = dynamic_cast<const RosbagDataset&>(*bag);
  ASSERT_EQ(bag->size(), 5u);
  EXPECT_EQ(rosbag.skipped_images(), 1u);
  EXPECT_EQ(bag->timestamp_ns(2), kT0Ns + 2 * kPeriodNs);  // the left stamp
  expect_same_image(bag->frame(2).right, spec.right[2], "right");

  // 25 ms late: half a period from both neighbouring left images, a partner of neither; nothing pairs.
  TempDir far("agvslam-rosbag");
  SyntheticBag late;
  late.right_offset_ns = kPeriodNs / 2;
  write_synthetic(far.file("bag"), late);
  expect_input_error([&] { open_dataset(far.file("bag")); }, {"expected at least one left/right pair"});
}

TEST(RosbagDataset, ImageEncodingsBecomeGrey) {
  const cv::Mat bgr = noise_image(48, 64, CV_8UC3, 7), wide = noise_image(48, 64, CV_16UC1, 8);
  cv::Mat grey_bgr, grey_rgb, grey_wide;
  cv::cvtColor(bgr, grey_bgr, cv::COLOR_BGR2GRAY);
  cv::cvtColor(bgr, grey_rgb, cv::COLOR_RGB2GRAY);
  wide.convertTo(grey_wide, CV_8UC1, 1.0 / 256.0);
  struct Case {
    const char* encoding;
    cv::Mat image, grey;
    bool big_endian;
  };
  for (const Case& c : {Case{"bgr8", bgr, grey_bgr, false}, Case{"rgb8", bgr, grey_rgb, false},
                        Case{"mono16", wide, grey_wide, false}, Case{"mono16", wide, grey_wide, true}}) {
    TempDir dir("agvslam-rosbag");
    BagWriter writer(dir.file("bag"));
    const int left = writer.topic("/left/image", "sensor_msgs/msg/Image");
    const int right = writer.topic("/right/image", "sensor_msgs/msg/Image");
    writer.write(left, 1, test::encode_image(1000, c.image, c.encoding, c.big_endian));
    writer.write(right, 1, test::encode_image(1000, c.image, c.encoding, c.big_endian));
    writer.finish();
    const auto bag = open_dataset(dir.file("bag"), write_calib(dir));
    expect_same_image(bag->frame(0).left, c.grey, std::string(c.encoding) + (c.big_endian ? " big-endian" : ""));
  }
}

TEST(RosbagDataset, TopicChoiceAutomaticOrByQuery) {
  TempDir dir("agvslam-rosbag");
  // Two image topics that name no side: cam0 is the left one.
  SyntheticBag numbered;
  numbered.left_topic = "/cam0/image_raw";
  numbered.right_topic = "/cam1/image_raw";
  write_synthetic(dir.file("numbered"), numbered);
  const std::string calib = write_calib(dir);
  const auto bag = open_dataset(dir.file("numbered"), calib);
  EXPECT_EQ(dynamic_cast<const RosbagDataset&>(*bag).left_topic(), "/cam0/image_raw");
  EXPECT_FALSE(dynamic_cast<const RosbagDataset&>(*bag).calibration_from_camera_info());
  expect_same_image(bag->frame(0).left, numbered.left[0], "cam0");

  // Swapped by the query.
  const auto swapped = open_dataset(dir.file("numbered") + "?left=/cam1/image_raw&right=/cam0/image_raw", calib);
  expect_same_image(swapped->frame(0).left, numbered.right[0], "cam1 as left");

  // Raw and compressed twins (image_transport): the raw topics are taken.
  {
    BagWriter writer(dir.file("twins"));
    const cv::Mat image = noise_image(48, 64, CV_8UC1, 5);
    for (const char* side : {"/left", "/right"}) {
      const int raw = writer.topic(std::string(side) + "/image_raw", "sensor_msgs/msg/Image");
      const int png = writer.topic(std::string(side) + "/image_raw/compressed", "sensor_msgs/msg/CompressedImage");
      writer.write(raw, 1, test::encode_image(1000, image, "mono8"));
      writer.write(png, 1, test::encode_png_image(1000, image));
    }
  }
  const auto twins = open_dataset(dir.file("twins"), calib);
  EXPECT_EQ(dynamic_cast<const RosbagDataset&>(*twins).left_topic(), "/left/image_raw");
  EXPECT_EQ(dynamic_cast<const RosbagDataset&>(*twins).right_topic(), "/right/image_raw");
  // One side chosen: the other is the remaining image topic.
  const auto half = open_dataset(dir.file("numbered") + "?right=/cam0/image_raw", calib);
  EXPECT_EQ(dynamic_cast<const RosbagDataset&>(*half).left_topic(), "/cam1/image_raw");

  // Three image topics, two on the left: ambiguous, the error lists the topics and the way out.
  {
    BagWriter writer(dir.file("three"));
    writer.topic("/left/image_raw", "sensor_msgs/msg/Image");
    writer.topic("/left/image_rect", "sensor_msgs/msg/Image");
    writer.topic("/right/image_rect", "sensor_msgs/msg/Image");
  }
  expect_input_error([&] { open_dataset(dir.file("three"), calib); },
                     {"image topics", "/left/image_raw (sensor_msgs/msg/Image)", "/left/image_rect", "?left=TOPIC"});
  expect_input_error([&] { open_dataset(dir.file("numbered") + "?left=/nope&right=/cam0/image_raw", calib); },
                     {"left=/nope", "expected an image topic", "/cam1/image_raw"});
  expect_input_error([&] { open_dataset(dir.file("numbered") + "?lft=/cam1/image_raw", calib); },
                     {"lft=/cam1/image_raw", "left, right, odom"});
  expect_input_error([&] { open_dataset(dir.path() + "?left=/a&right=/b"); }, {"no metadata.yaml"});
}

// A recording split into two .db3 files (ros2 bag record --max-bag-size): each file numbers its topics itself.
TEST(RosbagDataset, SplitRecordingReadsEveryFileWithItsOwnTopicIds) {
  TempDir dir("agvslam-rosbag");
  std::vector<cv::Mat> lefts, rights;
  for (int part = 0; part < 2; ++part) {
    BagWriter writer(dir.file("part" + std::to_string(part)), "recording_part" + std::to_string(part));
    // The second file registers the topics in the other order: other ids for the same names.
    const int first = writer.topic(part == 0 ? "/left/image" : "/right/image", "sensor_msgs/msg/Image");
    const int second = writer.topic(part == 0 ? "/right/image" : "/left/image", "sensor_msgs/msg/Image");
    const int left_id = part == 0 ? first : second, right_id = part == 0 ? second : first;
    for (int i = 0; i < 3; ++i) {
      const int64_t t = kT0Ns + (3 * part + i) * kPeriodNs;
      lefts.push_back(noise_image(48, 64, CV_8UC1, 100 + 2 * (3 * part + i)));
      rights.push_back(noise_image(48, 64, CV_8UC1, 101 + 2 * (3 * part + i)));
      writer.write(left_id, t, test::encode_image(t, lefts.back(), "mono8"));
      writer.write(right_id, t, test::encode_image(t, rights.back(), "mono8"));
    }
  }
  fs::rename(dir.file("part1/recording_part1_0.db3"), dir.file("part0/recording_part1_0.db3"));
  {
    std::ifstream in(dir.file("part0/metadata.yaml"));
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string files = "  relative_file_paths:\n    - recording_part0_0.db3\n";
    ASSERT_NE(text.find(files), std::string::npos);
    text.replace(text.find(files), files.size(), files + "    - recording_part1_0.db3\n");
    std::ofstream(dir.file("part0/metadata.yaml")) << text;
  }
  const auto bag = open_dataset(dir.file("part0"), write_calib(dir));
  ASSERT_EQ(bag->size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(bag->timestamp_ns(i), kT0Ns + static_cast<int64_t>(i) * kPeriodNs);
    const StereoFrame frame = bag->frame(i);
    expect_same_image(frame.left, lefts[i], "left " + std::to_string(i));
    expect_same_image(frame.right, rights[i], "right " + std::to_string(i));
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Bad input

TEST(RosbagDataset, BadBagsNameTheFileTopicAndField) {
  TempDir dir("agvslam-rosbag");
  SyntheticBag good;
  write_synthetic(dir.file("good"), good);
  auto copy_of = [&](const std::string& name) {
    fs::copy(dir.file("good"), dir.file(name), fs::copy_options::recursive);
    return dir.file(name);
  };
  auto replace_in_metadata = [](const std::string& bag, const std::string& from, const std::string& to) {
    std::ifstream in(bag + "/metadata.yaml");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    std::ofstream(bag + "/metadata.yaml") << text;
  };

  // No image topics.
  {
    BagWriter writer(dir.file("no_images"));
    writer.topic("/odom", "nav_msgs/msg/Odometry");
  }
  expect_input_error([&] { open_dataset(dir.file("no_images")); },
                     {"image topics", "found 0 image topics", "/odom (nav_msgs/msg/Odometry)"});

  // Unknown encoding.
  TempDir bayer_dir("agvslam-rosbag");
  SyntheticBag bayer;
  bayer.left_encoding = "bayer_rggb8";
  write_synthetic(bayer_dir.file("bag"), bayer);
  expect_input_error([&] { open_dataset(bayer_dir.file("bag")); },
                     {"recording_0.db3", "topic /stereo/left/image_raw", "'encoding'", "bayer_rggb8", "mono8"});

  // A truncated message: frame(i) throws (the daemon's source skips and counts it), other frames read.
  const std::string truncated = copy_of("truncated");
  // Frame 2's left image (recorded third from last) loses its pixel data.
  ASSERT_TRUE(test::truncate_message(truncated + "/recording_0.db3", 1, 2, true, 60));
  const auto damaged = open_dataset(truncated);
  ASSERT_EQ(damaged->size(), 5u);
  EXPECT_NO_THROW(damaged->frame(1));
  expect_input_error([&] { damaged->frame(2); },
                     {"recording_0.db3", "topic /stereo/left/image_raw", "field 'data'", "truncated CDR"});

  // A missing .db3.
  const std::string missing = copy_of("missing");
  fs::remove(missing + "/recording_0.db3");
  expect_input_error([&] { open_dataset(missing); },
                     {"metadata.yaml", "relative_file_paths[0]", "recording_0.db3, not found"});

  // A corrupt sqlite file.
  const std::string corrupt = copy_of("corrupt");
  std::ofstream(corrupt + "/recording_0.db3", std::ios::binary | std::ios::trunc) << std::string(4096, 'x');
  expect_input_error([&] { open_dataset(corrupt); }, {"recording_0.db3", "expected a rosbag2 sqlite3 database"});

  // metadata.yaml without a field, another storage, a compressed bag.
  const std::string no_storage = copy_of("no_storage");
  replace_in_metadata(no_storage, "storage_identifier: sqlite3", "storage: sqlite3");
  expect_input_error([&] { open_dataset(no_storage); },
                     {"metadata.yaml", "rosbag2_bagfile_information.storage_identifier", "missing"});
  const std::string no_type = copy_of("no_type");
  replace_in_metadata(no_type, "type: sensor_msgs/msg/Image", "kind: sensor_msgs/msg/Image");
  expect_input_error([&] { open_dataset(no_type); },
                     {"metadata.yaml", "topics_with_message_count[0].topic_metadata.type", "missing"});
  const std::string mcap = copy_of("mcap");
  replace_in_metadata(mcap, "storage_identifier: sqlite3", "storage_identifier: mcap");
  expect_input_error([&] { open_dataset(mcap); }, {"expected sqlite3, found mcap", "ros2 bag convert"});
  const std::string zstd = copy_of("zstd");
  replace_in_metadata(zstd, "compression_format: \"\"", "compression_format: zstd");
  expect_input_error([&] { open_dataset(zstd); }, {"compression_format", "zstd"});
  // Not a map where one is expected (found by fuzzing: yaml-cpp throws its own exception on a scalar's key).
  const std::string scalar = copy_of("scalar");
  std::ofstream(scalar + "/metadata.yaml", std::ios::trunc) << "just some text\n";
  expect_input_error([&] { open_dataset(scalar); }, {"metadata.yaml", "rosbag2_bagfile_information", "missing"});
  const std::string topic_scalar = copy_of("topic_scalar");
  replace_in_metadata(topic_scalar, "  topics_with_message_count:\n", "  topics_with_message_count:\n    - 7\n");
  expect_input_error([&] { open_dataset(topic_scalar); },
                     {"metadata.yaml", "topics_with_message_count[0].topic_metadata", "missing"});

  // No camera_info and no calibration file.
  TempDir bare_dir("agvslam-rosbag");
  SyntheticBag bare;
  bare.camera_info = false;
  write_synthetic(bare_dir.file("bag"), bare);
  expect_input_error([&] { open_dataset(bare_dir.file("bag")); },
                     {"calibration", "/stereo/left/camera_info", "/stereo/right/camera_info", "--calib"});
}

TEST(RosbagDataset, RawCameraInfoIsRectified) {
  TempDir dir("agvslam-rosbag");
  {
    BagWriter writer(dir.file("bag"));
    const int left = writer.topic("/left/image_raw", "sensor_msgs/msg/Image");
    const int right = writer.topic("/right/image_raw", "sensor_msgs/msg/Image");
    const int left_info = writer.topic("/left/camera_info", "sensor_msgs/msg/CameraInfo");
    const int right_info = writer.topic("/right/camera_info", "sensor_msgs/msg/CameraInfo");
    const std::vector<double> K = {kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1}, R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const cv::Mat image = noise_image(48, 64, CV_8UC1, 3);
    writer.write(left, 1, test::encode_image(1000, image, "mono8"));
    writer.write(right, 1, test::encode_image(1000, image, "mono8"));
    writer.write(
        left_info, 1,
        test::encode_camera_info(1000, 64, 48, {-0.2, 0.05, 0, 0, 0}, K, R, test::rectified_p(kFx, kFy, kCx, kCy, 0)));
    writer.write(right_info, 1,
                 test::encode_camera_info(1000, 64, 48, {-0.2, 0.05, 0, 0, 0}, K, R,
                                          test::rectified_p(kFx, kFy, kCx, kCy, -kFx * kBaseline)));
  }
  const auto bag = open_dataset(dir.file("bag"));
  EXPECT_TRUE(bag->calibration().needs_rectification);
  EXPECT_EQ(bag->calibration().map_left_x.size(), cv::Size(64, 48));
  EXPECT_EQ(bag->frame(0).left.size(), cv::Size(64, 48));
}

// Projection matrices that are not one rectified pair name the camera_info topic and what was expected.
TEST(RosbagDataset, CameraInfoOfNoRectifiedPairNamesTheTopic) {
  const std::vector<double> K = {kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1}, R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const cv::Mat image = noise_image(48, 64, CV_8UC1, 3);
  auto bag_with_right_p = [&](const std::string& path, const std::vector<double>& right_p) {
    BagWriter writer(path);
    const int left = writer.topic("/left/image_raw", "sensor_msgs/msg/Image");
    const int right = writer.topic("/right/image_raw", "sensor_msgs/msg/Image");
    const int left_info = writer.topic("/left/camera_info", "sensor_msgs/msg/CameraInfo");
    const int right_info = writer.topic("/right/camera_info", "sensor_msgs/msg/CameraInfo");
    writer.write(left, 1, test::encode_image(1000, image, "mono8"));
    writer.write(right, 1, test::encode_image(1000, image, "mono8"));
    writer.write(left_info, 1,
                 test::encode_camera_info(1000, 64, 48, {}, K, R, test::rectified_p(kFx, kFy, kCx, kCy, 0)));
    writer.write(right_info, 1, test::encode_camera_info(1000, 64, 48, {}, K, R, right_p));
  };
  TempDir dir("agvslam-rosbag");
  bag_with_right_p(dir.file("behind"), test::rectified_p(kFx, kFy, kCx, kCy, kFx * kBaseline));
  expect_input_error([&] { open_dataset(dir.file("behind")); },
                     {"/right/camera_info field 'p'", "expected a positive baseline"});
  bag_with_right_p(dir.file("other_cy"), test::rectified_p(kFx, kFy, kCx, kCy + 5, -kFx * kBaseline));
  expect_input_error([&] { open_dataset(dir.file("other_cy")); },
                     {"/right/camera_info field 'p'", "expected a rectified pair"});
}

}  // namespace
// Found by tests/fuzz (rosbag_cdr): a mono16 image whose step is not a whole number of pixels escaped from
// cv::Mat as a cv::Exception.
TEST(RosbagDataset, ImageStepOfHalfASampleNamesTheField) {
  test::CdrWriter w;
  w.header(1'000'000'000, "camera");
  w.u32(2);  // height
  w.u32(2);  // width
  w.string("mono16");
  w.u8(0);
  w.u32(5);  // step: 2 pixels of 2 bytes and one byte of padding, half a sample
  const std::vector<uint8_t> pixels(10, 0x80);
  w.bytes(pixels.data(), pixels.size());
  io::detail::CdrReader in(w.data().data(), w.data().size(), "bag.db3", "topic /left message 3");
  expect_input_error([&] { io::detail::decode_raw_image(in, "bag.db3", "topic /left message 3"); },
                     {"bag.db3", "topic /left message 3 field 'step'", "multiple of the 2-byte samples of mono16"});
}

}  // namespace agvslam::io
