#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <random>

#include "agvslam/io/calibration_io.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "io_test_util.h"

namespace agvslam::io {
namespace {
namespace fs = std::filesystem;
using testing::expect_input_error;
using testing::TempDir;

// ---------------------------------------------------------------------------------------------------------------
// Real data

TEST(Dataset, Kitti06OpensWithUnlabelledCalibAndGroundTruth) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const auto dataset = open_dataset(root);
  ASSERT_EQ(dataset->kind(), "kitti");
  EXPECT_EQ(dataset->root(), root);
  ASSERT_EQ(dataset->size(), 51u);
  const StereoCalibration& calib = dataset->calibration();
  EXPECT_DOUBLE_EQ(calib.left.fx, 707.0912);
  EXPECT_DOUBLE_EQ(calib.left.cx, 601.8873);
  EXPECT_DOUBLE_EQ(calib.left.cy, 183.1104);
  EXPECT_NEAR(calib.baseline_m, 0.53716, 1e-4);
  EXPECT_EQ(calib.left.size(), cv::Size(1226, 370));
  EXPECT_FALSE(calib.needs_rectification);
  EXPECT_EQ(dataset->timestamp_ns(0), 0);
  EXPECT_EQ(dataset->timestamp_ns(1), 104'498'900);
  EXPECT_NEAR(dataset->rate_hz(), 9.65, 0.2);

  const StereoFrame frame = dataset->frame(50);
  EXPECT_EQ(frame.index, 50u);
  EXPECT_EQ(frame.t_ns, dataset->timestamp_ns(50));
  EXPECT_EQ(frame.left.type(), CV_8UC1);
  EXPECT_EQ(frame.left.size(), cv::Size(1226, 370));
  EXPECT_EQ(frame.right.size(), cv::Size(1226, 370));
  EXPECT_GT(cv::norm(frame.left, frame.right, cv::NORM_L1), 0.0);  // two different images

  const auto gt = dataset->ground_truth();
  ASSERT_TRUE(gt.has_value());
  ASSERT_EQ(gt->size(), 51u);
  EXPECT_EQ((*gt)[10].t_ns, dataset->timestamp_ns(10));
  EXPECT_NEAR((*gt)[1].T_w_c.translation().z(), 1.198998, 1e-9);
  EXPECT_TRUE(dataset->ground_truth_mask(0).empty());
  EXPECT_TRUE(dataset->ground_truth_disparity_px(0).empty());
  EXPECT_THROW(dataset->frame(51), std::out_of_range);
}

TEST(Dataset, EurocPairsByTimestampAndSkipsMissingImages) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const auto opened = open_dataset(root);
  ASSERT_EQ(opened->kind(), "euroc");
  const auto* dataset = dynamic_cast<const EurocDataset*>(opened.get());
  ASSERT_NE(dataset, nullptr);
  ASSERT_EQ(dataset->size(), 95u);
  EXPECT_EQ(dataset->skipped_frames(), 4u);  // cam1/data.csv lists 4 frames whose images are absent
  EXPECT_EQ(dataset->timestamp_ns(0), 1403715273262142976);
  EXPECT_EQ(dataset->timestamp_ns(94), 1403715277962142976);
  EXPECT_NEAR(dataset->rate_hz(), 20.0, 0.01);
  const StereoCalibration& calib = dataset->calibration();
  EXPECT_TRUE(calib.needs_rectification);
  EXPECT_EQ(calib.left.size(), cv::Size(752, 480));
  EXPECT_NEAR(calib.baseline_m, 0.1101, 5e-4);
  EXPECT_NEAR(dataset->T_B_cam0().translation().y(), -0.064676986768, 1e-12);
  for (std::size_t i = 0; i < dataset->size(); ++i) {
    EXPECT_EQ(fs::path(dataset->left_path(i)).filename(), fs::path(dataset->right_path(i)).filename());
  }
  const StereoFrame frame = dataset->frame(3);
  EXPECT_EQ(frame.left.type(), CV_8UC1);
  EXPECT_EQ(frame.left.size(), cv::Size(752, 480));
  const cv::Mat raw_left = cv::imread(dataset->left_path(3), cv::IMREAD_GRAYSCALE);
  EXPECT_GT(cv::norm(frame.left, raw_left, cv::NORM_L1), 0.0);  // rectified, not a copy
  // The excerpt has no mav0/state_groundtruth_estimate0/data.csv.
  EXPECT_FALSE(dataset->ground_truth().has_value());
  // The mav0 folder itself also opens.
  EXPECT_EQ(open_dataset(root + "/mav0/")->size(), 95u);
}

struct RowAgreement {
  std::size_t matches = 0;
  double median_px = 0, p90_px = 0;
};

// Corners of the left image tracked into the right one with pyramidal Lucas-Kanade (sub-pixel), kept when the
// track is good both ways (right -> left lands within 0.3 px of the start) and the disparity is positive.
void collect_row_differences(const cv::Mat& left, const cv::Mat& right, std::vector<double>& dy_px) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(left, corners, 600, 0.01, 8);
  ASSERT_GT(corners.size(), 100u);
  std::vector<cv::Point2f> in_right, back_in_left;
  std::vector<uint8_t> status, back_status;
  std::vector<float> error, back_error;
  const cv::Size window(21, 21);
  cv::calcOpticalFlowPyrLK(left, right, corners, in_right, status, error, window, 3);
  cv::calcOpticalFlowPyrLK(right, left, in_right, back_in_left, back_status, back_error, window, 3);
  for (std::size_t k = 0; k < corners.size(); ++k) {
    if (!status[k] || !back_status[k]) continue;
    if (cv::norm(back_in_left[k] - corners[k]) > 0.3) continue;
    const double disparity = corners[k].x - in_right[k].x;
    const double dy = std::abs(corners[k].y - in_right[k].y);
    // The same gates for raw and rectified pairs: a plausible disparity, not a gross mismatch.
    if (disparity > 0 && disparity < 150 && dy < 40) dy_px.push_back(dy);
  }
}

RowAgreement summarize(std::vector<double> dy_px) {
  RowAgreement out;
  out.matches = dy_px.size();
  if (dy_px.empty()) return out;
  std::sort(dy_px.begin(), dy_px.end());
  out.median_px = dy_px[dy_px.size() / 2];
  out.p90_px = dy_px[std::min(dy_px.size() - 1, dy_px.size() * 9 / 10)];
  return out;
}

TEST(Dataset, EurocRectificationAlignsMatchedFeatureRows) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  const EurocDataset dataset(root);
  std::vector<double> dy_rect, dy_raw;
  for (const std::size_t i : {std::size_t{0}, std::size_t{47}, std::size_t{94}}) {
    const StereoFrame frame = dataset.frame(i);
    collect_row_differences(frame.left, frame.right, dy_rect);
    const cv::Mat raw_l = cv::imread(dataset.left_path(i), cv::IMREAD_GRAYSCALE);
    const cv::Mat raw_r = cv::imread(dataset.right_path(i), cv::IMREAD_GRAYSCALE);
    collect_row_differences(raw_l, raw_r, dy_raw);
  }
  const RowAgreement rect = summarize(dy_rect), raw = summarize(dy_raw);
  std::printf("rectified: %zu matches, median |dy| %.3f px, p90 %.3f px; raw: %zu matches, median %.3f, p90 %.3f\n",
              rect.matches, rect.median_px, rect.p90_px, raw.matches, raw.median_px, raw.p90_px);
  ASSERT_GT(rect.matches, 150u);
  EXPECT_LT(rect.median_px, 1.0);
  EXPECT_LT(rect.p90_px, 1.5);
  // Without rectification the rows disagree by several pixels (different cy, distortion, small rotation).
  EXPECT_GT(raw.median_px, 2.0 * rect.median_px + 1.0);
}

// Converts the ORB-SLAM3 cam0 ground truth (quaternion = R_cam_world, see shared/data README) to EuRoC body
// poses, writes them as state_groundtruth_estimate0/data.csv beside links to the real images, and checks that
// ground_truth() gives back the camera: T_w_rect = T_w_B * T_B_cam0 * T_cam0_rect.
TEST(Dataset, EurocGroundTruthIsTheRectifiedLeftCamera) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  TempDir dir;
  fs::create_directories(dir.file("mav0/state_groundtruth_estimate0"));
  fs::create_directory_symlink(root + "/mav0/cam0", dir.file("mav0/cam0"));
  fs::create_directory_symlink(root + "/mav0/cam1", dir.file("mav0/cam1"));
  const SE3d T_B_cam0 = load_euroc_sensor(root + "/mav0/cam0/sensor.yaml").T_B_S;

  const Trajectory orbslam_gt = read_euroc_csv(root + "/gt_orbslam3_left_cam/V101_GT.txt");
  Trajectory body;
  std::vector<SE3d> T_w_cam0_by_row;
  for (const StampedPose& row : orbslam_gt) {
    SE3d T_w_cam0 = row.T_w_c;
    T_w_cam0.linear() = Eigen::Matrix3d(row.T_w_c.linear().transpose());  // stored quaternion is R_cam_world
    body.push_back({row.t_ns, T_w_cam0 * T_B_cam0.inverse()});
  }
  write_trajectory(dir.file("mav0/state_groundtruth_estimate0/data.csv"), body, TrajectoryFormat::kEuroc);

  const EurocDataset dataset(dir.path());
  ASSERT_EQ(dataset.size(), 95u);
  const auto gt = dataset.ground_truth();
  ASSERT_TRUE(gt.has_value());
  ASSERT_EQ(gt->size(), 74u);  // ground truth starts at frame 21
  EXPECT_EQ(gt->front().t_ns, dataset.timestamp_ns(21));
  EXPECT_EQ(gt->front().t_ns, orbslam_gt.front().t_ns);
  const SE3d T_cam0_rect = dataset.calibration().T_cam0_rect;
  for (std::size_t k = 0; k < gt->size(); ++k) {
    const StampedPose& row = orbslam_gt[k];
    SE3d T_w_cam0 = row.T_w_c;
    T_w_cam0.linear() = Eigen::Matrix3d(row.T_w_c.linear().transpose());
    ASSERT_EQ((*gt)[k].t_ns, row.t_ns);
    EXPECT_LT(((*gt)[k].T_w_c.matrix() - (T_w_cam0 * T_cam0_rect).matrix()).cwiseAbs().maxCoeff(), 1e-9);
  }
  // The rectified camera's optical axis stays close to the raw one (EuRoC rectification rotates ~0.5 deg).
  EXPECT_LT(rotation_angle_rad(T_cam0_rect), 0.02);
}

// Body ground truth at 200 Hz, offset from the image times, with the 17-column layout of real EuRoC files:
// ground_truth() interpolates to the image times and leaves out frames without ground truth within 5 ms.
TEST(Dataset, EurocGroundTruthInterpolatesToImageTimes) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  TempDir dir;
  fs::create_directories(dir.file("mav0/state_groundtruth_estimate0"));
  fs::create_directory_symlink(root + "/mav0/cam0", dir.file("mav0/cam0"));
  fs::create_directory_symlink(root + "/mav0/cam1", dir.file("mav0/cam1"));

  const int64_t t0 = 1403715273262142976;
  auto T_w_B_at = [t0](int64_t t_ns) {
    const double s = ns_to_s(t_ns - t0);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3 * s, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 0.3, 0).normalized()))
                                  .toRotationMatrix();
    return make_se3(R, Eigen::Vector3d(1.0 + 0.4 * s, 2.0 - 0.1 * s, 0.9 + 0.05 * s));
  };
  const int64_t gt_first = t0 + 1'000'000'000 + 1'300'000, gt_last = t0 + 4'000'000'000;
  std::string csv =
      "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],"
      "v_RS_R_x [m s^-1],v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],b_w_RS_S_x,b_w_RS_S_y,b_w_RS_S_z,"
      "b_a_RS_S_x,b_a_RS_S_y,b_a_RS_S_z\n";
  char buf[400];
  int64_t gt_last_sample = gt_first;
  for (int64_t t = gt_first; t <= gt_last; t += 5'000'000) {
    gt_last_sample = t;
    const SE3d T = T_w_B_at(t);
    const Eigen::Quaterniond q(T.linear());
    std::snprintf(buf, sizeof(buf), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,0.4,-0.1,0.05,0,0,0,0,0,0\n",
                  static_cast<long long>(t), T.translation().x(), T.translation().y(), T.translation().z(), q.w(),
                  q.x(), q.y(), q.z());
    csv += buf;
  }
  dir.write("mav0/state_groundtruth_estimate0/data.csv", csv);

  const EurocDataset dataset(dir.path());
  const auto gt = dataset.ground_truth();
  ASSERT_TRUE(gt.has_value());
  std::vector<int64_t> expected_times;
  for (std::size_t i = 0; i < dataset.size(); ++i) {
    const int64_t t = dataset.timestamp_ns(i);
    if (t >= gt_first - 5'000'000 && t <= gt_last_sample + 5'000'000) expected_times.push_back(t);
  }
  ASSERT_EQ(gt->size(), expected_times.size());
  ASSERT_GT(gt->size(), 50u);
  const SE3d T_B_rect = dataset.T_B_cam0() * dataset.calibration().T_cam0_rect;
  std::size_t interpolated = 0;
  for (std::size_t k = 0; k < gt->size(); ++k) {
    const int64_t t = expected_times[k];
    EXPECT_EQ((*gt)[k].t_ns, t);
    // Inside the ground truth's span the pose is interpolated (exact for this constant-rate motion); just
    // outside it, the nearest sample (within 5 ms) is used.
    int64_t t_pose = t;
    if (t < gt_first) t_pose = gt_first;
    if (t > gt_last_sample) t_pose = gt_last_sample;
    interpolated += t_pose == t ? 1 : 0;
    const SE3d expected = T_w_B_at(t_pose) * T_B_rect;
    EXPECT_LT(((*gt)[k].T_w_c.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-9) << "frame " << k;
  }
  EXPECT_GT(interpolated, 50u);
}

// ---------------------------------------------------------------------------------------------------------------
// Synthetic sequences

cv::Mat noise_image(cv::Size size, unsigned seed) {
  cv::Mat image(size, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

StereoCalibration small_calibration() {
  StereoCalibration calib;
  calib.left = {50, 50, 32, 24, 64, 48};
  calib.baseline_m = 0.2;
  return calib;
}

// A KITTI-layout sequence the way agvslam-sim writes it: image_0/1, calib.txt, times.txt, poses.txt,
// disp_0 (16-bit disparity * 256), mask_0, instance_0.
void write_sim_sequence(const TempDir& dir, std::size_t frames) {
  const cv::Size size(64, 48);
  fs::create_directories(dir.file("image_0"));
  fs::create_directories(dir.file("image_1"));
  fs::create_directories(dir.file("disp_0"));
  fs::create_directories(dir.file("mask_0"));
  fs::create_directories(dir.file("instance_0"));
  std::vector<int64_t> times_ns;
  Trajectory poses;
  for (std::size_t i = 0; i < frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu.png", i);
    cv::imwrite(dir.file(std::string("image_0/") + name), noise_image(size, static_cast<unsigned>(2 * i)));
    cv::imwrite(dir.file(std::string("image_1/") + name), noise_image(size, static_cast<unsigned>(2 * i + 1)));
    cv::Mat disparity(size, CV_16UC1, cv::Scalar(0));
    disparity(cv::Rect(10, 10, 20, 10)).setTo(3200 + static_cast<int>(i));  // 12.5 px (+ i/256)
    cv::imwrite(dir.file(std::string("disp_0/") + name), disparity);
    cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
    mask(cv::Rect(40, 5, 10, 30)).setTo(255);
    cv::imwrite(dir.file(std::string("mask_0/") + name), mask);
    cv::Mat instances(size, CV_8UC1, cv::Scalar(0));
    instances.setTo(3, mask);
    instances(cv::Rect(2, 30, 8, 8)).setTo(7);  // a parked object
    cv::imwrite(dir.file(std::string("instance_0/") + name), instances);
    times_ns.push_back(1'000'000'000 + static_cast<int64_t>(i) * 33'333'333);
    poses.push_back(
        {times_ns.back(), make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.1 * static_cast<double>(i)))});
  }
  write_kitti_calib(dir.file("calib.txt"), small_calibration());
  write_kitti_times(dir.file("times.txt"), times_ns);
  write_kitti_poses(dir.file("poses.txt"), poses);
}

TEST(Dataset, SimulatorSequenceWithDisparityAndMask) {
  TempDir dir;
  write_sim_sequence(dir, 4);
  const KittiDataset dataset(dir.path());
  ASSERT_EQ(dataset.size(), 4u);
  EXPECT_EQ(dataset.timestamp_ns(3), 1'000'000'000 + 3 * 33'333'333);
  EXPECT_NEAR(dataset.rate_hz(), 30.0, 1e-3);
  EXPECT_NEAR(dataset.calibration().baseline_m, 0.2, 1e-12);
  EXPECT_EQ(fs::path(dataset.left_dir()).filename(), "image_0");

  const StereoFrame frame = dataset.frame(2);
  EXPECT_EQ(cv::norm(frame.left, noise_image({64, 48}, 4), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(frame.right, noise_image({64, 48}, 5), cv::NORM_INF), 0.0);

  const cv::Mat disparity = dataset.ground_truth_disparity_px(2);
  ASSERT_EQ(disparity.type(), CV_32FC1);
  ASSERT_EQ(disparity.size(), cv::Size(64, 48));
  EXPECT_FLOAT_EQ(disparity.at<float>(15, 15), 12.5f + 2.0f / 256.0f);
  EXPECT_FLOAT_EQ(disparity.at<float>(0, 0), 0.0f);
  EXPECT_EQ(cv::countNonZero(disparity), 200);

  const cv::Mat mask = dataset.ground_truth_mask(1);
  ASSERT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(mask.at<uint8_t>(10, 45), 255);
  EXPECT_EQ(cv::countNonZero(mask), 300);

  const cv::Mat instances = dataset.ground_truth_instances(1);
  ASSERT_EQ(instances.type(), CV_8UC1);
  EXPECT_EQ(instances.at<uint8_t>(10, 45), 3);
  EXPECT_EQ(instances.at<uint8_t>(33, 5), 7);
  EXPECT_EQ(cv::countNonZero(instances), 364);
  // A wrong instance image names its file and what was expected; a missing one is simply absent.
  cv::imwrite(dir.file("instance_0/000002.png"), cv::Mat(24, 32, CV_8UC1, cv::Scalar(1)));
  try {
    (void)dataset.ground_truth_instances(2);
    FAIL() << "an instance image of another size must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(e.source().find("instance_0/000002.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("64x48"), std::string::npos) << e.what();
  }
  fs::remove(dir.file("instance_0/000003.png"));
  EXPECT_TRUE(dataset.ground_truth_instances(3).empty());

  const auto gt = dataset.ground_truth();
  ASSERT_TRUE(gt.has_value());
  ASSERT_EQ(gt->size(), 4u);
  EXPECT_EQ((*gt)[3].t_ns, dataset.timestamp_ns(3));
  EXPECT_NEAR((*gt)[3].T_w_c.translation().z(), 0.3, 1e-12);

  // Without times.txt: 10 Hz from zero.
  fs::remove(dir.file("times.txt"));
  const auto untimed = open_dataset(dir.path());
  EXPECT_EQ(untimed->timestamp_ns(3), 300'000'000);
  EXPECT_DOUBLE_EQ(untimed->rate_hz(), 10.0);
}

TEST(Dataset, KittiSortsNumericFileNamesAndAcceptsCalibOverride) {
  TempDir dir;
  fs::create_directories(dir.file("image_l"));
  fs::create_directories(dir.file("image_r"));
  for (int n : {10, 2, 1}) {
    const cv::Mat image(48, 64, CV_8UC1, cv::Scalar(n));
    cv::imwrite(dir.file("image_l/" + std::to_string(n) + ".png"), image);
    cv::imwrite(dir.file("image_r/" + std::to_string(n) + ".png"), image);
  }
  dir.write("image_l/notes.txt", "not an image\n");
  write_kitti_calib(dir.file("other_calib.txt"), small_calibration());
  // No calib.txt in the folder: the override is used.
  const auto dataset = open_dataset(dir.path(), dir.file("other_calib.txt"));
  ASSERT_EQ(dataset->size(), 3u);
  EXPECT_EQ(dataset->frame(0).left.at<uint8_t>(0, 0), 1);
  EXPECT_EQ(dataset->frame(1).left.at<uint8_t>(0, 0), 2);
  EXPECT_EQ(dataset->frame(2).left.at<uint8_t>(0, 0), 10);
  EXPECT_FALSE(dataset->ground_truth().has_value());
  expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("calib.txt"), "file not found"});
}

TEST(Dataset, BadKittiSequencesNameFileAndProblem) {
  {
    TempDir dir;
    write_sim_sequence(dir, 3);
    fs::remove(dir.file("image_1/000002.png"));
    expect_input_error([&] { open_dataset(dir.path()); },
                       {dir.file("image_1"), "image count", "expected 3 .png images like image_0/", "found 2"});
  }
  {
    TempDir dir;
    write_sim_sequence(dir, 3);
    write_kitti_times(dir.file("times.txt"), {0, 100'000'000});
    expect_input_error([&] { open_dataset(dir.path()); },
                       {dir.file("times.txt"), "line count", "expected 3 time stamps", "found 2"});
  }
  {
    TempDir dir;
    write_sim_sequence(dir, 3);
    dir.write("times.txt", "0.0\n0.2\n0.1\n");
    expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("times.txt"), "line 3", "increasing"});
  }
  {
    TempDir dir;
    write_sim_sequence(dir, 3);
    dir.write("image_1/000001.png", "this is not a PNG");
    const auto dataset = open_dataset(dir.path());
    expect_input_error([&] { dataset->frame(1); }, {dir.file("image_1/000001.png"), "readable image"});
    cv::imwrite(dir.file("image_0/000002.png"), cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
    expect_input_error([&] { dataset->frame(2); }, {dir.file("image_0/000002.png"), "expected 64x48", "found 10x10"});
    cv::imwrite(dir.file("disp_0/000000.png"), cv::Mat(48, 64, CV_8UC1, cv::Scalar(0)));
    expect_input_error([&] { dataset->ground_truth_disparity_px(0); }, {dir.file("disp_0/000000.png"), "16-bit"});
    dir.write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 nan 0 0 1 0\n");
    expect_input_error([&] { dataset->ground_truth(); }, {dir.file("poses.txt") + ": line 2: NaN in pose"});
  }
  {
    TempDir dir;
    write_sim_sequence(dir, 2);
    dir.write("calib.txt", "P0: 50 0 32 0 0 50 24 0 0 0 1 0\nP1: 50 0 32 -10 0 50 24 0 0 0 1\n");
    expect_input_error([&] { open_dataset(dir.path()); },
                       {dir.file("calib.txt") + ": line 2: expected 12 numbers after 'P1:', found 11"});
  }
  {
    TempDir dir;
    fs::create_directories(dir.file("image_0"));
    fs::create_directories(dir.file("image_1"));
    expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("image_0"), "expected .png images, found none"});
  }
}

TEST(Dataset, FolderThatIsNeitherLayout) {
  TempDir dir;
  fs::create_directories(dir.file("images"));
  expect_input_error([&] { open_dataset(dir.path()); },
                     {dir.path(), "layout", "expected a KITTI odometry folder", "EuRoC ASL folder"});
  expect_input_error([&] { open_dataset(dir.file("missing")); }, {dir.file("missing"), "folder not found"});
  expect_input_error([&] { KittiDataset kitti(dir.path()); }, {dir.path(), "layout", "image_0/"});
  expect_input_error([&] { EurocDataset euroc(dir.path()); }, {dir.path(), "layout", "mav0/"});
}

TEST(Dataset, BadEurocSequencesNameFileAndLine) {
  TempDir dir;
  fs::create_directories(dir.file("mav0/cam0/data"));
  fs::create_directories(dir.file("mav0/cam1/data"));
  for (const char* cam : {"cam0", "cam1"}) {
    for (const char* stamp : {"1000000000", "1050000000"}) {
      cv::imwrite(dir.file(std::string("mav0/") + cam + "/data/" + stamp + ".png"), noise_image({64, 48}, 1));
    }
  }
  dir.write("mav0/cam0/data.csv", "#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000\n");
  dir.write("mav0/cam1/data.csv", "#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000,1050000000.png\n");
  expect_input_error([&] { open_dataset(dir.path()); },
                     {dir.file("mav0/cam0/data.csv"), "line 3", "expected 2 comma-separated fields"});

  dir.write("mav0/cam0/data.csv", "#timestamp [ns],filename\n1000000000,1000000000.png\nabc,1050000000.png\n");
  expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("mav0/cam0/data.csv"), "line 3", "found 'abc'"});

  // Right stamps 3 ms off: no pairs at all.
  dir.write("mav0/cam0/data.csv", "#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000,1050000000.png\n");
  dir.write("mav0/cam1/data.csv", "#timestamp [ns],filename\n1003000000,1000000000.png\n1053000000,1050000000.png\n");
  expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("mav0/cam0/data.csv"), "found none"});

  // Within 1 ms they pair; then sensor.yaml is needed.
  dir.write("mav0/cam1/data.csv", "#timestamp [ns],filename\n1000400000,1000000000.png\n1050000000,1050000000.png\n");
  expect_input_error([&] { open_dataset(dir.path()); }, {dir.file("mav0/cam0/sensor.yaml"), "file not found"});
}

}  // namespace
}  // namespace agvslam::io
