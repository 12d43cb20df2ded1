#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>

#include "agvslam/io/calibration_io.h"
#include "io_test_util.h"

namespace agvslam::io {
namespace {
using testing::expect_input_error;
using testing::TempDir;

// EuRoC MAV VI-sensor calibration (the values of mav0/cam0|cam1/sensor.yaml in every EuRoC sequence).
constexpr double kCam0Intrinsics[4] = {458.654, 457.296, 367.215, 248.375};
constexpr double kCam0Distortion[4] = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
constexpr double kCam0T_BS[16] = {0.0148655429818,
                                  -0.999880929698,
                                  0.00414029679422,
                                  -0.0216401454975,
                                  0.999557249008,
                                  0.0149672133247,
                                  0.025715529948,
                                  -0.064676986768,
                                  -0.0257744366974,
                                  0.00375618835797,
                                  0.999660727178,
                                  0.00981073058949,
                                  0.0,
                                  0.0,
                                  0.0,
                                  1.0};
constexpr double kCam1Intrinsics[4] = {457.587, 456.134, 379.999, 255.238};
constexpr double kCam1Distortion[4] = {-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05};
constexpr double kCam1T_BS[16] = {0.0125552670891,
                                  -0.999755099723,
                                  0.0182237714554,
                                  -0.0198435579556,
                                  0.999598781151,
                                  0.0130119051815,
                                  0.0251588363115,
                                  0.0453689425024,
                                  -0.0253898008918,
                                  0.0179005838253,
                                  0.999517347078,
                                  0.00786212447038,
                                  0.0,
                                  0.0,
                                  0.0,
                                  1.0};

std::string list(const double* values, int n) {
  std::string out = "[";
  char buf[40];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buf, sizeof(buf), "%s%.17g", k ? ", " : "", values[k]);
    out += buf;
  }
  return out + "]";
}

std::string euroc_sensor_yaml(const double* intrinsics, const double* distortion, const double* T_BS) {
  return "%YAML:1.0\n"
         "# General sensor definitions.\n"
         "sensor_type: camera\n"
         "comment: VI-Sensor (MT9M034)\n"
         "T_BS:\n"
         "  cols: 4\n"
         "  rows: 4\n"
         "  data: " +
         list(T_BS, 16) +
         "\n"
         "rate_hz: 20\n"
         "resolution: [752, 480]\n"
         "camera_model: pinhole\n"
         "intrinsics: " +
         list(intrinsics, 4) +
         " #fu, fv, cu, cv\n"
         "distortion_model: radial-tangential\n"
         "distortion_coefficients: " +
         list(distortion, 4) + "\n";
}

struct EurocFiles {
  std::string cam0, cam1;
};

EurocFiles write_euroc_sensors(const TempDir& dir) {
  return {dir.write("mav0/cam0/sensor.yaml", euroc_sensor_yaml(kCam0Intrinsics, kCam0Distortion, kCam0T_BS)),
          dir.write("mav0/cam1/sensor.yaml", euroc_sensor_yaml(kCam1Intrinsics, kCam1Distortion, kCam1T_BS))};
}

std::string kalibr_camera(const std::string& name, const double* intrinsics, const double* distortion,
                          const std::string& extra) {
  return name + ":\n" + extra +
         "  camera_model: pinhole\n"
         "  intrinsics: " +
         list(intrinsics, 4) +
         "\n"
         "  distortion_model: radtan\n"
         "  distortion_coeffs: " +
         list(distortion, 4) +
         "\n"
         "  resolution: [752, 480]\n"
         "  rostopic: /" +
         name + "/image_raw\n";
}

std::string matrix_rows(const SE3d& T) {
  std::string out;
  for (int r = 0; r < 4; ++r) {
    double row[4];
    for (int c = 0; c < 4; ++c) row[c] = T.matrix()(r, c);
    out += "  - " + list(row, 4) + "\n";
  }
  return out;
}

std::string kalibr_camchain(const SE3d& T_cam1_cam0) {
  return kalibr_camera("cam0", kCam0Intrinsics, kCam0Distortion, "") +
         kalibr_camera("cam1", kCam1Intrinsics, kCam1Distortion, "  T_cn_cnm1:\n" + matrix_rows(T_cam1_cam0));
}

std::string cv_matrix_yaml(const std::string& key, const cv::Mat& m) {
  std::vector<double> values(m.begin<double>(), m.end<double>());
  return key + ": !!opencv-matrix\n   rows: " + std::to_string(m.rows) + "\n   cols: " + std::to_string(m.cols) +
         "\n   dt: d\n   data: " + list(values.data(), static_cast<int>(values.size())) + "\n";
}

// An ORB-SLAM2 style settings file; with the raw rig, also LEFT/RIGHT K, D, R, P computed with OpenCV's
// stereoRectify the way ORB-SLAM's example files were made.
std::string orbslam_yaml(double fx, double fy, double cx, double cy, double bf, const RawStereoRig* rig) {
  char head[512];
  std::snprintf(head, sizeof(head),
                "%%YAML:1.0\n"
                "Camera.type: \"PinHole\"\n"
                "Camera.fx: %.17g\nCamera.fy: %.17g\nCamera.cx: %.17g\nCamera.cy: %.17g\n"
                "Camera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\n"
                "Camera.width: 752\nCamera.height: 480\nCamera.fps: 20.0\n"
                "Camera.bf: %.17g\nCamera.RGB: 1\nThDepth: 35\n",
                fx, fy, cx, cy, bf);
  std::string text = head;
  if (rig) {
    const cv::Mat K0(rig->cam0.pinhole.K()), K1(rig->cam1.pinhole.K());
    const cv::Mat D0 = cv::Mat(rig->cam0.distortion, true).reshape(1, 1);
    const cv::Mat D1 = cv::Mat(rig->cam1.distortion, true).reshape(1, 1);
    cv::Mat R(3, 3, CV_64F), t(3, 1, CV_64F);
    for (int r = 0; r < 3; ++r) {
      t.at<double>(r) = rig->T_cam1_cam0.translation()(r);
      for (int c = 0; c < 3; ++c) R.at<double>(r, c) = rig->T_cam1_cam0.linear()(r, c);
    }
    cv::Mat R0, R1, P0, P1, Q;
    cv::stereoRectify(K0, D0, K1, D1, cv::Size(752, 480), R, t, R0, R1, P0, P1, Q, cv::CALIB_ZERO_DISPARITY, 0.0);
    text += "LEFT.height: 480\nLEFT.width: 752\n" + cv_matrix_yaml("LEFT.D", D0) + cv_matrix_yaml("LEFT.K", K0) +
            cv_matrix_yaml("LEFT.R", R0) + cv_matrix_yaml("LEFT.P", P0);
    text += "RIGHT.height: 480\nRIGHT.width: 752\n" + cv_matrix_yaml("RIGHT.D", D1) + cv_matrix_yaml("RIGHT.K", K1) +
            cv_matrix_yaml("RIGHT.R", R1) + cv_matrix_yaml("RIGHT.P", P1);
  }
  return text;
}

std::string orbslam_yaml_for(const StereoCalibration& c, const RawStereoRig* rig) {
  return orbslam_yaml(c.left.fx, c.left.fy, c.left.cx, c.left.cy, c.bf(), rig);
}

double bilinear(const cv::Mat& map, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  auto at = [&](int r, int c) { return static_cast<double>(map.at<float>(r, c)); };
  return (1 - ay) * ((1 - ax) * at(y0, x0) + ax * at(y0, x0 + 1)) +
         ay * ((1 - ax) * at(y0 + 1, x0) + ax * at(y0 + 1, x0 + 1));
}

Eigen::Vector2d project_raw(const RawCamera& cam, const Eigen::Vector3d& p) {
  std::vector<cv::Point3d> object{{p.x(), p.y(), p.z()}};
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(cam.pinhole.K()),
                    cv::Mat(cam.distortion, true), image);
  return {image[0].x, image[0].y};
}

// Largest distance (px) between where the rectification maps send a rectified pixel and where the raw rig
// actually sees the 3-D point behind it, over a grid of points at 2.5 m, in both images.
double max_map_error_px(const StereoCalibration& calib, const RawStereoRig& rig) {
  const double depth_m = 2.5;
  const double disparity_px = calib.disparity_from_depth(depth_m);
  double worst = 0;
  for (int v = 60; v <= 420; v += 60) {
    for (int u = 120; u <= 640; u += 65) {
      const Eigen::Vector3d p_rect = calib.left.unproject(Eigen::Vector2d(u, v), depth_m);
      const Eigen::Vector3d p_cam0 = calib.T_cam0_rect * p_rect;
      const Eigen::Vector2d raw_left = project_raw(rig.cam0, p_cam0);
      const Eigen::Vector2d raw_right = project_raw(rig.cam1, rig.T_cam1_cam0 * p_cam0);
      const Eigen::Vector2d map_left(calib.map_left_x.at<float>(v, u), calib.map_left_y.at<float>(v, u));
      const double ur = u - disparity_px;
      const Eigen::Vector2d map_right(bilinear(calib.map_right_x, ur, v), bilinear(calib.map_right_y, ur, v));
      worst = std::max({worst, (map_left - raw_left).norm(), (map_right - raw_right).norm()});
    }
  }
  return worst;
}

void expect_same_calibration(const StereoCalibration& a, const StereoCalibration& b, double map_tol_px) {
  EXPECT_NEAR(a.left.fx, b.left.fx, 1e-6);
  EXPECT_NEAR(a.left.fy, b.left.fy, 1e-6);
  EXPECT_NEAR(a.left.cx, b.left.cx, 1e-6);
  EXPECT_NEAR(a.left.cy, b.left.cy, 1e-6);
  EXPECT_EQ(a.left.size(), b.left.size());
  EXPECT_NEAR(a.baseline_m, b.baseline_m, 1e-9);
  EXPECT_EQ(a.needs_rectification, b.needs_rectification);
  EXPECT_LT((a.T_cam0_rect.matrix() - b.T_cam0_rect.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  if (a.needs_rectification && b.needs_rectification) {
    EXPECT_LE(cv::norm(a.map_left_x, b.map_left_x, cv::NORM_INF), map_tol_px);
    EXPECT_LE(cv::norm(a.map_left_y, b.map_left_y, cv::NORM_INF), map_tol_px);
    EXPECT_LE(cv::norm(a.map_right_x, b.map_right_x, cv::NORM_INF), map_tol_px);
    EXPECT_LE(cv::norm(a.map_right_y, b.map_right_y, cv::NORM_INF), map_tol_px);
  }
}

// ---------------------------------------------------------------------------------------------------------------

constexpr const char* kKitti06P0 =
    "7.070912000000e+02 0.000000000000e+00 6.018873000000e+02 0.000000000000e+00 0.000000000000e+00 "
    "7.070912000000e+02 1.831104000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 0.000000000000e+00";
constexpr const char* kKitti06P1 =
    "7.070912000000e+02 0.000000000000e+00 6.018873000000e+02 -3.798145000000e+02 0.000000000000e+00 "
    "7.070912000000e+02 1.831104000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 "
    "1.000000000000e+00 0.000000000000e+00";

void expect_kitti06(const StereoCalibration& c) {
  EXPECT_DOUBLE_EQ(c.left.fx, 707.0912);
  EXPECT_DOUBLE_EQ(c.left.fy, 707.0912);
  EXPECT_DOUBLE_EQ(c.left.cx, 601.8873);
  EXPECT_DOUBLE_EQ(c.left.cy, 183.1104);
  EXPECT_NEAR(c.baseline_m, 379.8145 / 707.0912, 1e-12);
  EXPECT_NEAR(c.baseline_m, 0.53716, 1e-4);
  EXPECT_EQ(c.left.size(), cv::Size(1226, 370));
  EXPECT_FALSE(c.needs_rectification);
}

TEST(CalibrationIo, KittiCalibLabelledAndUnlabelled) {
  TempDir dir;
  const cv::Size size(1226, 370);
  const std::string labelled =
      dir.write("labelled.txt", std::string("P0: ") + kKitti06P0 + "\nP1: " + kKitti06P1 + "\nP2: " + kKitti06P0 +
                                    "\nP3: " + kKitti06P1 + "\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  expect_kitti06(load_kitti_calib(labelled, size));
  const std::string bare = dir.write("bare.txt", std::string(kKitti06P0) + "\n" + kKitti06P1);  // no final newline
  expect_kitti06(load_kitti_calib(bare, size));
  // Bare P0/P1 followed by labelled extras, with CRLF line ends and a comment.
  const std::string mixed = dir.write("mixed.txt", std::string("# KITTI 06\r\n") + kKitti06P0 + "\r\n" + kKitti06P1 +
                                                       "\r\nP2: " + kKitti06P0 + "\r\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\r\n");
  expect_kitti06(load_kitti_calib(mixed, size));
  // Labels in another order.
  const std::string swapped = dir.write("swapped.txt", std::string("P1: ") + kKitti06P1 + "\nP0: " + kKitti06P0 + "\n");
  expect_kitti06(load_kitti_calib(swapped, size));
  expect_kitti06(load_calibration(bare, size));
}

TEST(CalibrationIo, KittiCalibWriteReadRoundTrip) {
  TempDir dir;
  StereoCalibration calib;
  calib.left = {718.856, 718.857, 607.1928, 185.2157, 1241, 376};
  calib.baseline_m = 0.537150588;
  const std::string path = dir.file("calib.txt");
  write_kitti_calib(path, calib);
  const StereoCalibration back = load_kitti_calib(path, calib.left.size());
  EXPECT_DOUBLE_EQ(back.left.fx, calib.left.fx);
  EXPECT_DOUBLE_EQ(back.left.fy, calib.left.fy);
  EXPECT_DOUBLE_EQ(back.left.cx, calib.left.cx);
  EXPECT_DOUBLE_EQ(back.left.cy, calib.left.cy);
  EXPECT_NEAR(back.baseline_m, calib.baseline_m, 1e-12);
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first.rfind("P0: ", 0), 0u) << first;

  StereoCalibration bad = calib;
  bad.baseline_m = -0.1;
  expect_input_error([&] { write_kitti_calib(dir.file("bad.txt"), bad); }, {dir.file("bad.txt"), "baseline"});
}

TEST(CalibrationIo, KittiCalibErrorsNameFileLineAndExpectation) {
  TempDir dir;
  const cv::Size size(1226, 370);
  const std::string p1_short = std::string(kKitti06P1).substr(0, std::string(kKitti06P1).rfind(' '));
  const std::string short_labelled = dir.write("a.txt", std::string("P0: ") + kKitti06P0 + "\nP1: " + p1_short + "\n");
  expect_input_error([&] { load_kitti_calib(short_labelled, size); },
                     {short_labelled + ": line 2: expected 12 numbers after 'P1:', found 11"});
  const std::string short_bare = dir.write("b.txt", std::string(kKitti06P0) + "\n" + p1_short + "\n");
  expect_input_error([&] { load_kitti_calib(short_bare, size); },
                     {short_bare, "line 2", "expected 12 numbers", "P1", "found 11"});
  const std::string word =
      dir.write("c.txt", std::string("P0: ") + kKitti06P0 + "\nP1: 7.07e+02 x 0 0 0 0 0 0 0 0 1 0\n");
  expect_input_error([&] { load_kitti_calib(word, size); }, {word, "line 2", "found 'x'"});
  const std::string with_nan =
      dir.write("d.txt", "P0: nan 0 601 0 0 707 183 0 0 0 1 0\nP1: " + std::string(kKitti06P1));
  expect_input_error([&] { load_kitti_calib(with_nan, size); }, {with_nan, "line 1", "NaN in P0"});
  const std::string only_p0 = dir.write("e.txt", std::string("P0: ") + kKitti06P0 + "\n");
  expect_input_error([&] { load_kitti_calib(only_p0, size); }, {only_p0, "P1", "found none"});
  const std::string left_of_p0 = dir.write(
      "f.txt", std::string(kKitti06P0) + "\n" + "707.0912 0 601.8873 379.8145 0 707.0912 183.1104 0 0 0 1 0\n");
  expect_input_error([&] { load_kitti_calib(left_of_p0, size); }, {left_of_p0, "positive baseline"});
  expect_input_error([&] { load_kitti_calib(dir.file("none.txt"), size); }, {dir.file("none.txt"), "file not found"});
  const std::string bare = dir.write("g.txt", std::string(kKitti06P0) + "\n" + kKitti06P1 + "\n");
  expect_input_error([&] { load_calibration(bare); }, {bare, "image size"});
}

TEST(CalibrationIo, OrbSlamYamlWithoutRectification) {
  TempDir dir;
  const std::string path = dir.write("orb.yaml", orbslam_yaml(435.2046959714599, 435.2046959714599, 367.4517211914062,
                                                              252.2008514404297, 47.90639384423901, nullptr));
  const StereoCalibration calib = load_orbslam_yaml(path);
  EXPECT_DOUBLE_EQ(calib.left.fx, 435.2046959714599);
  EXPECT_DOUBLE_EQ(calib.left.cx, 367.4517211914062);
  EXPECT_DOUBLE_EQ(calib.left.cy, 252.2008514404297);
  EXPECT_EQ(calib.left.size(), cv::Size(752, 480));
  EXPECT_NEAR(calib.baseline_m, 47.90639384423901 / 435.2046959714599, 1e-12);
  EXPECT_NEAR(calib.bf(), 47.90639384423901, 1e-9);
  EXPECT_FALSE(calib.needs_rectification);
  EXPECT_TRUE(calib.map_left_x.empty());
  const StereoCalibration detected = load_calibration(path);
  EXPECT_DOUBLE_EQ(detected.baseline_m, calib.baseline_m);
}

TEST(CalibrationIo, EurocSensorYamlGivesRawRig) {
  TempDir dir;
  const EurocFiles files = write_euroc_sensors(dir);
  const EurocCameraSensor cam0 = load_euroc_sensor(files.cam0);
  EXPECT_DOUBLE_EQ(cam0.camera.pinhole.fx, 458.654);
  EXPECT_DOUBLE_EQ(cam0.camera.pinhole.fy, 457.296);
  EXPECT_DOUBLE_EQ(cam0.camera.pinhole.cx, 367.215);
  EXPECT_DOUBLE_EQ(cam0.camera.pinhole.cy, 248.375);
  EXPECT_EQ(cam0.camera.pinhole.size(), cv::Size(752, 480));
  ASSERT_EQ(cam0.camera.distortion.size(), 4u);
  EXPECT_DOUBLE_EQ(cam0.camera.distortion[0], -0.28340811);
  EXPECT_NEAR(cam0.T_B_S.translation().y(), -0.064676986768, 1e-12);

  const RawStereoRig rig = load_euroc_rig(files.cam0, files.cam1);
  // cam1 sits ~11 cm to the right of cam0: x of cam0's centre in cam1 is about -0.11 m.
  EXPECT_NEAR(rig.T_cam1_cam0.translation().norm(), 0.1101, 5e-4);
  EXPECT_LT(rig.T_cam1_cam0.translation().x(), -0.10);
  EXPECT_LT(rotation_angle_rad(rig.T_cam1_cam0), 0.02);  // ~0.8 degrees between the two cameras

  const StereoCalibration calib = load_euroc_calibration(files.cam0, files.cam1);
  EXPECT_TRUE(calib.needs_rectification);
  EXPECT_NEAR(calib.baseline_m, rig.T_cam1_cam0.translation().norm(), 1e-9);
  EXPECT_EQ(calib.map_left_x.size(), cv::Size(752, 480));
  EXPECT_GT(calib.left.fx, 300.0);
  EXPECT_LT(calib.left.fx, 460.0);
  EXPECT_LT(max_map_error_px(calib, rig), 0.02);
  // Auto-detection pairs cam0/sensor.yaml with cam1/sensor.yaml beside it.
  expect_same_calibration(load_calibration(files.cam0), calib, 0.0);
  expect_input_error([&] { load_calibration(files.cam1); }, {files.cam1, "describes one camera"});
}

TEST(CalibrationIo, KalibrCamchainAgreesWithEurocSensorYaml) {
  TempDir dir;
  const EurocFiles files = write_euroc_sensors(dir);
  const RawStereoRig euroc_rig = load_euroc_rig(files.cam0, files.cam1);
  const std::string camchain = dir.write("camchain.yaml", kalibr_camchain(euroc_rig.T_cam1_cam0));

  const RawStereoRig rig = load_kalibr_camchain_rig(camchain);
  EXPECT_DOUBLE_EQ(rig.cam0.pinhole.fx, 458.654);
  EXPECT_DOUBLE_EQ(rig.cam1.pinhole.cy, 255.238);
  EXPECT_EQ(rig.cam1.distortion, std::vector<double>(kCam1Distortion, kCam1Distortion + 4));
  EXPECT_LT((rig.T_cam1_cam0.matrix() - euroc_rig.T_cam1_cam0.matrix()).cwiseAbs().maxCoeff(), 1e-12);

  const StereoCalibration kalibr = load_kalibr_camchain(camchain);
  const StereoCalibration euroc = load_euroc_calibration(files.cam0, files.cam1);
  expect_same_calibration(kalibr, euroc, 1e-3);
  EXPECT_LT(max_map_error_px(kalibr, rig), 0.02);
  expect_same_calibration(load_calibration(camchain), euroc, 1e-3);
}

TEST(CalibrationIo, OrbSlamYamlWithRectificationAgreesWithEurocAndKalibr) {
  TempDir dir;
  const EurocFiles files = write_euroc_sensors(dir);
  const RawStereoRig rig = load_euroc_rig(files.cam0, files.cam1);
  const StereoCalibration euroc = load_euroc_calibration(files.cam0, files.cam1);
  const StereoCalibration kalibr = load_kalibr_camchain(dir.write("camchain.yaml", kalibr_camchain(rig.T_cam1_cam0)));
  const std::string orb_path = dir.write("orb_rect.yaml", orbslam_yaml_for(euroc, &rig));

  const StereoCalibration orb = load_orbslam_yaml(orb_path);
  ASSERT_TRUE(orb.needs_rectification);
  EXPECT_EQ(orb.map_left_x.type(), CV_32FC1);
  EXPECT_EQ(orb.map_right_y.size(), cv::Size(752, 480));
  expect_same_calibration(orb, euroc, 1e-3);
  expect_same_calibration(orb, kalibr, 1e-3);
  // Each loader's maps agree with the physical rig, not only with each other.
  EXPECT_LT(max_map_error_px(orb, rig), 0.02);
  expect_same_calibration(load_calibration(orb_path), euroc, 1e-3);
}

TEST(CalibrationIo, SharedEurocSensorFiles) {
  AGVSLAM_REQUIRE_SHARED(mav0, "data/euroc_v101_f000-094/mav0");
  const RawStereoRig rig = load_euroc_rig(mav0 + "/cam0/sensor.yaml", mav0 + "/cam1/sensor.yaml");
  EXPECT_DOUBLE_EQ(rig.cam0.pinhole.fx, 458.654);
  EXPECT_DOUBLE_EQ(rig.cam0.pinhole.fy, 457.296);
  EXPECT_DOUBLE_EQ(rig.cam0.pinhole.cx, 367.215);
  EXPECT_DOUBLE_EQ(rig.cam0.pinhole.cy, 248.375);
  EXPECT_DOUBLE_EQ(rig.cam1.pinhole.fx, 457.587);
  EXPECT_NEAR(rig.T_cam1_cam0.translation().norm(), 0.1101, 5e-4);
}

TEST(CalibrationIo, EurocSensorYamlErrorsNameField) {
  TempDir dir;
  std::string text = euroc_sensor_yaml(kCam0Intrinsics, kCam0Distortion, kCam0T_BS);
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const std::size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return t.replace(at, from.size(), to);
  };
  const std::string three = dir.write("three.yaml", replaced("intrinsics: [458.654, ", "intrinsics: ["));
  expect_input_error([&] { load_euroc_sensor(three); },
                     {three + ": field 'intrinsics'", "expected 4 numbers [fu, fv, cu, cv], found 3"});
  const std::string no_tbs = dir.write("no_tbs.yaml", replaced("T_BS:", "T_XX:"));
  expect_input_error([&] { load_euroc_sensor(no_tbs); }, {no_tbs, "field 'T_BS'", "missing"});
  const std::string short_tbs = dir.write("short_tbs.yaml", replaced("[0.0148655429818, ", "["));
  expect_input_error([&] { load_euroc_sensor(short_tbs); }, {short_tbs, "field 'T_BS.data'", "found 15"});
  const std::string fisheye = dir.write("fisheye.yaml", replaced("camera_model: pinhole", "camera_model: omni"));
  expect_input_error([&] { load_euroc_sensor(fisheye); }, {fisheye, "field 'camera_model'", "'omni'"});
  const std::string word = dir.write("word.yaml", replaced("[752, 480]", "[752, abc]"));
  expect_input_error([&] { load_euroc_sensor(word); }, {word, "field 'resolution'", "'abc'"});
  const std::string nan_k = dir.write("nan.yaml", replaced("458.654", ".nan"));
  expect_input_error([&] { load_euroc_sensor(nan_k); }, {nan_k, "field 'intrinsics'", "NaN"});
  const std::string broken = dir.write("broken.yaml", "%YAML:1.0\nT_BS: [1, 2\nresolution: [752, 480]\n");
  expect_input_error([&] { load_euroc_sensor(broken); }, {broken, "line", "expected valid YAML"});
  expect_input_error([&] { load_euroc_rig(dir.file("nope0.yaml"), dir.file("nope1.yaml")); },
                     {dir.file("nope0.yaml"), "file not found"});
}

TEST(CalibrationIo, KalibrErrorsNameField) {
  TempDir dir;
  const SE3d T = make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.11, 0, 0));
  const std::string only_cam0 = dir.write("cam0.yaml", kalibr_camera("cam0", kCam0Intrinsics, kCam0Distortion, ""));
  expect_input_error([&] { load_kalibr_camchain(only_cam0); }, {only_cam0, "field 'cam1'", "missing"});

  std::string three_rows = kalibr_camchain(T);
  three_rows.erase(three_rows.rfind("  - "), std::string("  - [0, 0, 0, 1]\n").size());
  const std::string rows_path = dir.write("rows.yaml", three_rows);
  expect_input_error([&] { load_kalibr_camchain(rows_path); }, {rows_path, "field 'cam1.T_cn_cnm1'", "found 3 rows"});

  std::string bad_k = kalibr_camchain(T);
  bad_k.replace(bad_k.find("intrinsics: ["), std::string("intrinsics: [458.654, ").size(), "intrinsics: [");
  const std::string k_path = dir.write("k.yaml", bad_k);
  expect_input_error([&] { load_kalibr_camchain(k_path); },
                     {k_path, "field 'cam0.intrinsics'", "expected 4 numbers [fu, fv, pu, pv], found 3"});

  std::string equi = kalibr_camchain(T);
  equi.replace(equi.find("distortion_model: radtan"), std::string("distortion_model: radtan").size(),
               "distortion_model: equidistant");
  const std::string equi_path = dir.write("equi.yaml", equi);
  expect_input_error([&] { load_kalibr_camchain(equi_path); },
                     {equi_path, "field 'cam0.distortion_model'", "equidistant"});

  const SE3d swapped = make_se3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.11, 0, 0));
  const std::string swapped_path = dir.write("swapped.yaml", kalibr_camchain(swapped));
  expect_input_error([&] { load_kalibr_camchain(swapped_path); }, {swapped_path, "positive baseline"});
}

TEST(CalibrationIo, OrbSlamErrorsNameField) {
  TempDir dir;
  std::string no_bf = orbslam_yaml(435.2, 435.2, 367.4, 252.2, 47.9, nullptr);
  no_bf.replace(no_bf.find("Camera.bf"), 9, "Camera.xx");
  const std::string no_bf_path = dir.write("no_bf.yaml", no_bf);
  expect_input_error([&] { load_orbslam_yaml(no_bf_path); }, {no_bf_path, "field 'Camera.bf'", "missing"});

  const std::string negative = dir.write("neg.yaml", orbslam_yaml(-435.2, 435.2, 367.4, 252.2, 47.9, nullptr));
  expect_input_error([&] { load_orbslam_yaml(negative); }, {negative, "Camera.fx", "positive"});

  const std::string zero_bf = dir.write("zero_bf.yaml", orbslam_yaml(435.2, 435.2, 367.4, 252.2, 0.0, nullptr));
  expect_input_error([&] { load_orbslam_yaml(zero_bf); }, {zero_bf, "field 'Camera.bf'", "positive"});

  TempDir euroc_dir;
  const EurocFiles files = write_euroc_sensors(euroc_dir);
  const RawStereoRig rig = load_euroc_rig(files.cam0, files.cam1);
  std::string bad_p = orbslam_yaml_for(load_euroc_calibration(files.cam0, files.cam1), &rig);
  // Make LEFT.P a 3x3 matrix.
  const std::size_t p_at = bad_p.find("LEFT.P");
  const std::size_t cols_at = bad_p.find("cols: 4", p_at);
  bad_p.replace(cols_at, 7, "cols: 3");
  const std::size_t data_at = bad_p.find("data: [", p_at);
  const std::size_t end_at = bad_p.find(']', data_at);
  bad_p.replace(data_at, end_at - data_at + 1, "data: [435, 0, 367, 0, 435, 252, 0, 0, 1]");
  const std::string p_path = dir.write("p.yaml", bad_p);
  expect_input_error([&] { load_orbslam_yaml(p_path); },
                     {p_path, "field 'LEFT.P'", "expected a 3x4 matrix", "found 3x3"});

  std::string no_right = orbslam_yaml_for(load_euroc_calibration(files.cam0, files.cam1), &rig);
  no_right.replace(no_right.find("RIGHT.R"), 7, "RIGHT.X");
  const std::string no_right_path = dir.write("no_right.yaml", no_right);
  expect_input_error([&] { load_orbslam_yaml(no_right_path); }, {no_right_path, "field 'RIGHT.R'", "missing"});

  const std::string garbage = dir.write("garbage.yaml", "%YAML:1.0\nCamera.fx: [1, 2\n");
  expect_input_error([&] { load_orbslam_yaml(garbage); }, {garbage, "expected an OpenCV YAML file"});
}

TEST(CalibrationIo, LoadCalibrationRejectsUnknownContent) {
  TempDir dir;
  const std::string unknown = dir.write("unknown.txt", "hello: world\n");
  expect_input_error([&] { load_calibration(unknown); }, {unknown, "expected a calibration file"});
  expect_input_error([&] { load_calibration(dir.file("missing.yaml")); }, {dir.file("missing.yaml"), "file not found"});
}

TEST(CalibrationIo, SharedKitti06CalibUnlabelled) {
  AGVSLAM_REQUIRE_SHARED(path, "data/kitti06_f000-050/calib.txt");
  expect_kitti06(load_kitti_calib(path, cv::Size(1226, 370)));
  expect_kitti06(load_calibration(path, cv::Size(1226, 370)));
}

}  // namespace
}  // namespace agvslam::io
