#include "agvslam/io/calibration_io.h"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/io/trajectory_io.h"
#include "text_util.h"

namespace agvslam::io {
namespace fs = std::filesystem;
using detail::LineReader;

namespace {

std::string format_number(double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", value);
  return buf;
}

// Final checks shared by every loader: a positive focal length and baseline, finite values.
void validate_calibration(const StereoCalibration& calib, const std::string& path, const std::string& where) {
  const double values[] = {calib.left.fx, calib.left.fy, calib.left.cx, calib.left.cy, calib.baseline_m};
  detail::require_finite(values, 5, path, where, "calibration");
  if (!(calib.left.fx > 0) || !(calib.left.fy > 0)) {
    throw InputError(path, where,
                     "expected a positive focal length, found fx = " + format_number(calib.left.fx) +
                         ", fy = " + format_number(calib.left.fy));
  }
  if (!(calib.baseline_m > 0)) {
    throw InputError(path, where,
                     "expected a positive baseline (right camera at +x of the left one), found " +
                         format_number(calib.baseline_m) + " m");
  }
}

// ---------------------------------------------------------------------------------------------------------------
// KITTI calib.txt

struct KittiProjections {
  std::vector<double> P0, P1;
};

KittiProjections parse_kitti_projections(const std::string& path) {
  LineReader reader(path, detail::read_text_file(path));
  KittiProjections out;
  int bare_lines = 0;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const std::string where = reader.where();
    auto tokens = detail::split_tokens(line, false);
    std::string label;
    std::string context;
    if (!tokens.front().empty() && tokens.front().back() == ':') {
      label = std::string(tokens.front().substr(0, tokens.front().size() - 1));
      tokens.erase(tokens.begin());
      context = "after '" + label + ":'";
    } else if (const std::size_t colon = tokens.front().find(':'); colon != std::string_view::npos) {
      // "P0:7.07e+02 ..." without a blank after the colon.
      label = std::string(tokens.front().substr(0, colon));
      tokens.front().remove_prefix(colon + 1);
      if (tokens.front().empty()) tokens.erase(tokens.begin());
      context = "after '" + label + ":'";
    } else {
      // Unlabelled lines: the first is P0, the second P1 (KITTI odometry sequences sometimes come this way).
      ++bare_lines;
      label = bare_lines == 1 ? "P0" : bare_lines == 2 ? "P1" : "";
      context = "for " + (label.empty() ? std::string("an unlabelled line") : label) + " (unlabelled line " +
                std::to_string(bare_lines) + ")";
      if (label.empty()) continue;
    }
    std::vector<double>* target = nullptr;
    if (label == "P0" || label == "P_rect_00") target = &out.P0;
    if (label == "P1" || label == "P_rect_01") target = &out.P1;
    if (!target) continue;  // P2, P3, Tr, ...: not needed for the grey pair
    if (!target->empty()) throw InputError(path, where, "expected one " + label + " line, found a second one");
    if (tokens.size() != 12) {
      throw InputError(path, where, "expected 12 numbers " + context + ", found " + std::to_string(tokens.size()));
    }
    *target = detail::parse_numbers(tokens, path, where, label);
    detail::require_finite(target->data(), target->size(), path, where, label);
  }
  if (out.P0.empty()) throw InputError(path, "P0", "expected a 'P0:' line (or a first unlabelled line), found none");
  if (out.P1.empty()) throw InputError(path, "P1", "expected a 'P1:' line (or a second unlabelled line), found none");
  return out;
}

// ---------------------------------------------------------------------------------------------------------------
// YAML (yaml-cpp) helpers for Kalibr and EuRoC files.

std::string field_where(const std::string& field, const YAML::Node& node) {
  std::string where = "field '" + field + "'";
  const YAML::Mark mark = node.Mark();
  if (mark.line >= 0 && !node.IsNull()) where += " (line " + std::to_string(mark.line + 1) + ")";
  return where;
}

YAML::Node load_yaml(const std::string& path) {
  std::string text = detail::read_text_file(path);
  // OpenCV writes "%YAML:1.0", which yaml-cpp rejects: blank the directive, keeping the line count.
  if (text.rfind("%YAML", 0) == 0) {
    const std::size_t end = text.find('\n');
    text.replace(0, end == std::string::npos ? text.size() : end, "");
  }
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "line " + std::to_string(e.mark.line + 1), "expected valid YAML (" + e.msg + ")");
  }
}

YAML::Node require_field(const YAML::Node& parent, const std::string& key, const std::string& path,
                         const std::string& field_name) {
  if (!parent.IsMap()) throw InputError(path, "field '" + field_name + "'", "missing (parent is not a map)");
  YAML::Node node = parent[key];
  if (!node.IsDefined() || node.IsNull()) throw InputError(path, "field '" + field_name + "'", "missing");
  return node;
}

std::string yaml_string(const YAML::Node& node, const std::string& path, const std::string& field_name) {
  if (!node.IsScalar()) throw InputError(path, field_where(field_name, node), "expected a text value");
  return node.Scalar();
}

// A YAML scalar as a number: plain decimals plus YAML's own spellings of NaN and infinity (".nan", "-.inf"), so
// that those are reported as NaN/infinite values rather than as text.
bool yaml_scalar_to_double(const std::string& scalar, double& value) {
  if (detail::parse_double(scalar, value)) return true;
  std::string lower;
  for (char c : scalar) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == ".nan") {
    value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  if (lower == ".inf" || lower == "+.inf" || lower == "-.inf") {
    value = lower[0] == '-' ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    return true;
  }
  return false;
}

double yaml_number(const YAML::Node& node, const std::string& path, const std::string& field_name) {
  double value = 0;
  if (!node.IsScalar() || !yaml_scalar_to_double(node.Scalar(), value)) {
    throw InputError(
        path, field_where(field_name, node),
        "expected a number, found '" + (node.IsScalar() ? node.Scalar() : std::string("a list or map")) + "'");
  }
  detail::require_finite(&value, 1, path, field_where(field_name, node), "value");
  return value;
}

// A list of numbers; `expected` describes what the list holds, e.g. "4 numbers [fu, fv, cu, cv]".
std::vector<double> yaml_numbers(const YAML::Node& node, const std::string& path, const std::string& field_name,
                                 std::size_t expected_count, const std::string& expected) {
  const std::string where = field_where(field_name, node);
  if (!node.IsSequence()) throw InputError(path, where, "expected a list of " + expected);
  if (expected_count != 0 && node.size() != expected_count) {
    throw InputError(path, where, "expected " + expected + ", found " + std::to_string(node.size()));
  }
  std::vector<double> values;
  values.reserve(node.size());
  for (std::size_t k = 0; k < node.size(); ++k) {
    double value = 0;
    const YAML::Node item = node[k];
    if (!item.IsScalar() || !yaml_scalar_to_double(item.Scalar(), value)) {
      throw InputError(path, where,
                       "expected " + expected + ", element " + std::to_string(k + 1) + " is '" +
                           (item.IsScalar() ? item.Scalar() : std::string("a list or map")) + "'");
    }
    values.push_back(value);
  }
  detail::require_finite(values.data(), values.size(), path, where, "values");
  return values;
}

SE3d se3_from_4x4(const std::vector<double>& m, const std::string& path, const std::string& where) {
  const double tol = 1e-6;
  if (std::abs(m[12]) > tol || std::abs(m[13]) > tol || std::abs(m[14]) > tol || std::abs(m[15] - 1.0) > tol) {
    throw InputError(path, where, "expected a rigid transform with last row [0, 0, 0, 1]");
  }
  Eigen::Matrix3d R;
  R << m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10];
  return make_se3(detail::checked_rotation(R, path, where), Eigen::Vector3d(m[3], m[7], m[11]));
}

PinholeCamera pinhole_from(const std::vector<double>& intrinsics, const std::vector<double>& resolution,
                           const std::string& path, const std::string& intrinsics_where,
                           const std::string& resolution_where) {
  PinholeCamera cam;
  cam.fx = intrinsics[0];
  cam.fy = intrinsics[1];
  cam.cx = intrinsics[2];
  cam.cy = intrinsics[3];
  if (!(cam.fx > 0) || !(cam.fy > 0)) {
    throw InputError(
        path, intrinsics_where,
        "expected positive focal lengths, found fu = " + format_number(cam.fx) + ", fv = " + format_number(cam.fy));
  }
  if (!(resolution[0] >= 1 && resolution[1] >= 1 && resolution[0] < 1e6 && resolution[1] < 1e6) ||
      resolution[0] != std::floor(resolution[0]) || resolution[1] != std::floor(resolution[1])) {
    throw InputError(path, resolution_where, "expected two positive integers [width, height]");
  }
  cam.width = static_cast<int>(resolution[0]);
  cam.height = static_cast<int>(resolution[1]);
  return cam;
}

void require_pinhole_radtan(const std::string& model, const std::string& distortion_model, const std::string& path,
                            const std::string& model_field, const std::string& distortion_field) {
  if (model != "pinhole") {
    throw InputError(path, "field '" + model_field + "'", "expected 'pinhole', found '" + model + "'");
  }
  if (distortion_model != "radtan" && distortion_model != "radial-tangential" && distortion_model != "none") {
    throw InputError(path, "field '" + distortion_field + "'",
                     "expected 'radtan' (radial-tangential) or 'none', found '" + distortion_model + "'");
  }
}

RawCamera kalibr_camera(const YAML::Node& root, const std::string& name, const std::string& path) {
  const YAML::Node cam = require_field(root, name, path, name);
  RawCamera raw;
  const std::string model =
      yaml_string(require_field(cam, "camera_model", path, name + ".camera_model"), path, name + ".camera_model");
  const YAML::Node distortion_model_node = cam["distortion_model"];
  const std::string distortion_model = distortion_model_node.IsDefined() && !distortion_model_node.IsNull()
                                           ? yaml_string(distortion_model_node, path, name + ".distortion_model")
                                           : std::string("none");
  require_pinhole_radtan(model, distortion_model, path, name + ".camera_model", name + ".distortion_model");
  const YAML::Node intrinsics_node = require_field(cam, "intrinsics", path, name + ".intrinsics");
  const YAML::Node resolution_node = require_field(cam, "resolution", path, name + ".resolution");
  const auto intrinsics = yaml_numbers(intrinsics_node, path, name + ".intrinsics", 4, "4 numbers [fu, fv, pu, pv]");
  const auto resolution = yaml_numbers(resolution_node, path, name + ".resolution", 2, "2 numbers [width, height]");
  raw.pinhole = pinhole_from(intrinsics, resolution, path, field_where(name + ".intrinsics", intrinsics_node),
                             field_where(name + ".resolution", resolution_node));
  if (distortion_model != "none") {
    const YAML::Node d = require_field(cam, "distortion_coeffs", path, name + ".distortion_coeffs");
    raw.distortion = yaml_numbers(d, path, name + ".distortion_coeffs", 4, "4 numbers [k1, k2, p1, p2]");
  }
  return raw;
}

StereoCalibration rectify_checked(const RawStereoRig& rig, const std::string& path, const std::string& where) {
  if (rig.cam0.pinhole.size() != rig.cam1.pinhole.size()) {
    throw InputError(path, where,
                     "expected both cameras to have the same resolution, found " +
                         std::to_string(rig.cam0.pinhole.width) + "x" + std::to_string(rig.cam0.pinhole.height) +
                         " and " + std::to_string(rig.cam1.pinhole.width) + "x" +
                         std::to_string(rig.cam1.pinhole.height));
  }
  if (!(rig.T_cam1_cam0.translation().norm() > 1e-6)) {
    throw InputError(path, where, "expected a non-zero baseline between cam0 and cam1");
  }
  StereoCalibration calib = rectify_rig(rig);
  validate_calibration(calib, path, where);
  return calib;
}

// ---------------------------------------------------------------------------------------------------------------
// OpenCV FileStorage (ORB-SLAM) helpers.

bool cv_has(const cv::FileStorage& fs, const std::string& key) {
  const cv::FileNode node = fs[key];
  return !node.empty() && !node.isNone();
}

double cv_number(const cv::FileStorage& fs, const std::string& key, const std::string& path) {
  const cv::FileNode node = fs[key];
  if (node.empty() || node.isNone()) throw InputError(path, "field '" + key + "'", "missing");
  double value = 0;
  if (node.isInt()) {
    value = static_cast<double>(static_cast<int>(node));
  } else if (node.isReal()) {
    value = node.real();
  } else if (node.isString()) {
    // Tolerate quoted numbers; anything else is an error.
    if (!detail::parse_double(node.string(), value)) {
      throw InputError(path, "field '" + key + "'", "expected a number, found '" + node.string() + "'");
    }
  } else {
    throw InputError(path, "field '" + key + "'", "expected a number");
  }
  detail::require_finite(&value, 1, path, "field '" + key + "'", "value");
  return value;
}

cv::Mat cv_matrix(const cv::FileStorage& fs, const std::string& key, int rows, int cols, const std::string& path) {
  const cv::FileNode node = fs[key];
  if (node.empty() || node.isNone()) throw InputError(path, "field '" + key + "'", "missing");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception& e) {
    throw InputError(path, "field '" + key + "'", "expected an opencv-matrix (" + e.msg + ")");
  }
  if (m.empty()) throw InputError(path, "field '" + key + "'", "expected an opencv-matrix");
  m.convertTo(m, CV_64F);
  const bool size_ok = rows > 0 ? (m.rows == rows && m.cols == cols)
                                : (m.total() >= 4 && m.total() <= 14 && (m.rows == 1 || m.cols == 1));
  if (!size_ok) {
    const std::string expected = rows > 0 ? std::to_string(rows) + "x" + std::to_string(cols) + " matrix"
                                          : "1xN distortion vector (N = 4, 5, 8, 12 or 14)";
    throw InputError(path, "field '" + key + "'",
                     "expected a " + expected + ", found " + std::to_string(m.rows) + "x" + std::to_string(m.cols));
  }
  if (!cv::checkRange(m)) throw InputError(path, "field '" + key + "'", "NaN or infinite value in matrix");
  return m;
}

enum class CalibKind { kKitti, kOrbSlam, kKalibr, kEurocSensor, kUnknown };

CalibKind detect_calibration_kind(const std::string& path) {
  const std::string text = detail::read_text_file(path);
  if (text.find("Camera.fx") != std::string::npos || text.find("Camera1.fx") != std::string::npos) {
    return CalibKind::kOrbSlam;
  }
  if (text.find("T_cn_cnm1") != std::string::npos ||
      (text.find("cam0:") != std::string::npos && text.find("intrinsics") != std::string::npos)) {
    return CalibKind::kKalibr;
  }
  if (text.find("T_BS") != std::string::npos && text.find("intrinsics") != std::string::npos) {
    return CalibKind::kEurocSensor;
  }
  LineReader reader(path, text);
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto tokens = detail::split_tokens(line, false);
    const std::string_view first = tokens.front();
    if (first.rfind("P0", 0) == 0 || first.rfind("P_rect_00", 0) == 0 || first.rfind("calib_time", 0) == 0) {
      return CalibKind::kKitti;
    }
    double value = 0;
    if (tokens.size() == 12 && detail::parse_double(first, value)) return CalibKind::kKitti;
    break;
  }
  return CalibKind::kUnknown;
}

}  // namespace

// -------------------------------------------------------------------------------------------------------------------

StereoCalibration calibration_from_projections(const std::vector<double>& P_left, const std::vector<double>& P_right,
                                               cv::Size image_size, const std::string& source,
                                               const std::string& left_field, const std::string& right_field) {
  if (P_left.size() != 12 || P_right.size() != 12) {
    throw InputError(source, P_left.size() != 12 ? left_field : right_field, "expected a 3x4 projection matrix");
  }
  StereoCalibration calib;
  calib.left.fx = P_left[0];
  calib.left.fy = P_left[5];
  calib.left.cx = P_left[2];
  calib.left.cy = P_left[6];
  calib.left.width = image_size.width;
  calib.left.height = image_size.height;
  if (!(P_right[0] > 0)) {
    throw InputError(source, right_field,
                     "expected a positive focal length P[0,0], found " + format_number(P_right[0]));
  }
  calib.baseline_m = (P_left[3] - P_right[3]) / P_right[0];
  validate_calibration(calib, source, left_field + "/" + right_field);
  if (std::abs(P_right[0] - P_left[0]) > 1e-6 * P_left[0] || std::abs(P_right[6] - P_left[6]) > 1e-3) {
    throw InputError(source, right_field,
                     "expected a rectified pair (" + right_field + " with the same fx and cy as " + left_field +
                         "), found fx " + format_number(P_right[0]) + " vs " + format_number(P_left[0]) + ", cy " +
                         format_number(P_right[6]) + " vs " + format_number(P_left[6]));
  }
  calib.needs_rectification = false;
  return calib;
}

StereoCalibration load_kitti_calib(const std::string& path, cv::Size image_size) {
  const KittiProjections P = parse_kitti_projections(path);
  return calibration_from_projections(P.P0, P.P1, image_size, path, "P0", "P1");
}

void write_kitti_calib(const std::string& path, const StereoCalibration& calib) {
  validate_calibration(calib, path, "calibration to write");
  const PinholeCamera& c = calib.left;
  const double P0[12] = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  const double P1[12] = {c.fx, 0, c.cx, -c.fx * calib.baseline_m, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  std::string out;
  char buf[32];
  for (int camera = 0; camera < 2; ++camera) {
    out += camera == 0 ? "P0:" : "P1:";
    const double* P = camera == 0 ? P0 : P1;
    for (int k = 0; k < 12; ++k) {
      std::snprintf(buf, sizeof(buf), " %.12e", P[k]);
      out += buf;
    }
    out += '\n';
  }
  write_file_atomically(path, out);
}

StereoCalibration load_orbslam_yaml(const std::string& path) {
  detail::require_file(path);
  cv::FileStorage storage;
  try {
    if (!storage.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML)) {
      throw InputError(path, "", "expected an OpenCV YAML file (cv::FileStorage could not open it)");
    }
  } catch (const cv::Exception& e) {
    throw InputError(path, "", "expected an OpenCV YAML file (" + e.msg + ")");
  }

  StereoCalibration calib;
  const std::string prefix = cv_has(storage, "Camera.fx") ? "Camera." : "Camera1.";  // ORB-SLAM2 / ORB-SLAM3
  calib.left.fx = cv_number(storage, prefix + "fx", path);
  calib.left.fy = cv_number(storage, prefix + "fy", path);
  calib.left.cx = cv_number(storage, prefix + "cx", path);
  calib.left.cy = cv_number(storage, prefix + "cy", path);
  double bf = 0;
  if (cv_has(storage, "Camera.bf") || !cv_has(storage, "Stereo.b")) {
    bf = cv_number(storage, "Camera.bf", path);
  } else {
    bf = cv_number(storage, "Stereo.b", path) * calib.left.fx;
  }
  const bool has_rect = cv_has(storage, "LEFT.K");
  auto size_field = [&](const std::string& name) {
    std::string key = "Camera." + name;
    if (!cv_has(storage, key) && has_rect) key = "LEFT." + name;
    const double value = cv_number(storage, key, path);
    if (!(value >= 1 && value < 1e6) || value != std::floor(value)) {
      throw InputError(path, "field '" + key + "'", "expected a positive integer, found " + format_number(value));
    }
    return static_cast<int>(value);
  };
  calib.left.width = size_field("width");
  calib.left.height = size_field("height");
  if (!(calib.left.fx > 0)) {
    throw InputError(path, "field '" + prefix + "fx'",
                     "expected a positive focal length, found " + format_number(calib.left.fx));
  }
  calib.baseline_m = bf / calib.left.fx;
  if (!(calib.baseline_m > 0)) {
    throw InputError(path, "field 'Camera.bf'", "expected a positive baseline * fx, found " + format_number(bf));
  }
  validate_calibration(calib, path, "field 'Camera.*'");

  if (has_rect) {
    const cv::Mat K_l = cv_matrix(storage, "LEFT.K", 3, 3, path);
    const cv::Mat D_l = cv_matrix(storage, "LEFT.D", 0, 0, path);
    const cv::Mat R_l = cv_matrix(storage, "LEFT.R", 3, 3, path);
    const cv::Mat P_l = cv_matrix(storage, "LEFT.P", 3, 4, path);
    const cv::Mat K_r = cv_matrix(storage, "RIGHT.K", 3, 3, path);
    const cv::Mat D_r = cv_matrix(storage, "RIGHT.D", 0, 0, path);
    const cv::Mat R_r = cv_matrix(storage, "RIGHT.R", 3, 3, path);
    const cv::Mat P_r = cv_matrix(storage, "RIGHT.P", 3, 4, path);
    const cv::Size size = calib.left.size();
    cv::initUndistortRectifyMap(K_l, D_l, R_l, P_l(cv::Rect(0, 0, 3, 3)), size, CV_32FC1, calib.map_left_x,
                                calib.map_left_y);
    cv::initUndistortRectifyMap(K_r, D_r, R_r, P_r(cv::Rect(0, 0, 3, 3)), size, CV_32FC1, calib.map_right_x,
                                calib.map_right_y);
    calib.needs_rectification = true;
    // LEFT.R rotates raw cam0 coordinates into the rectified frame (p_rect = R * p_cam0).
    Eigen::Matrix3d R_rect_cam0;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R_rect_cam0(r, c) = R_l.at<double>(r, c);
    R_rect_cam0 = detail::checked_rotation(R_rect_cam0, path, "field 'LEFT.R'");
    calib.T_cam0_rect = make_se3(Eigen::Matrix3d(R_rect_cam0.transpose()), Eigen::Vector3d::Zero());
  } else if (cv_has(storage, "RIGHT.K") || cv_has(storage, "LEFT.P")) {
    throw InputError(path, "field 'LEFT.K'", "missing (raw images need LEFT.K/D/R/P and RIGHT.K/D/R/P)");
  }
  return calib;
}

RawStereoRig load_kalibr_camchain_rig(const std::string& path) {
  const YAML::Node root = load_yaml(path);
  RawStereoRig rig;
  rig.cam0 = kalibr_camera(root, "cam0", path);
  rig.cam1 = kalibr_camera(root, "cam1", path);
  const YAML::Node cam1 = root["cam1"];
  const YAML::Node T_node = require_field(cam1, "T_cn_cnm1", path, "cam1.T_cn_cnm1");
  const std::string where = field_where("cam1.T_cn_cnm1", T_node);
  if (!T_node.IsSequence() || T_node.size() != 4) {
    throw InputError(path, where,
                     "expected a 4x4 matrix (4 lists of 4 numbers), found " +
                         (T_node.IsSequence() ? std::to_string(T_node.size()) + " rows" : std::string("no list")));
  }
  std::vector<double> m;
  for (std::size_t r = 0; r < 4; ++r) {
    const auto row = yaml_numbers(T_node[r], path, "cam1.T_cn_cnm1 row " + std::to_string(r + 1), 4, "4 numbers");
    m.insert(m.end(), row.begin(), row.end());
  }
  rig.T_cam1_cam0 = se3_from_4x4(m, path, where);  // T_cn_cnm1 maps cam0 points into cam1
  return rig;
}

StereoCalibration load_kalibr_camchain(const std::string& path) {
  return rectify_checked(load_kalibr_camchain_rig(path), path, "field 'cam1.T_cn_cnm1'");
}

EurocCameraSensor load_euroc_sensor(const std::string& path) {
  const YAML::Node root = load_yaml(path);
  if (!root.IsMap()) throw InputError(path, "", "expected a YAML map (EuRoC sensor.yaml)");
  EurocCameraSensor sensor;
  const std::string model =
      yaml_string(require_field(root, "camera_model", path, "camera_model"), path, "camera_model");
  const std::string distortion_model =
      yaml_string(require_field(root, "distortion_model", path, "distortion_model"), path, "distortion_model");
  require_pinhole_radtan(model, distortion_model, path, "camera_model", "distortion_model");
  const YAML::Node intrinsics_node = require_field(root, "intrinsics", path, "intrinsics");
  const YAML::Node resolution_node = require_field(root, "resolution", path, "resolution");
  const auto intrinsics = yaml_numbers(intrinsics_node, path, "intrinsics", 4, "4 numbers [fu, fv, cu, cv]");
  const auto resolution = yaml_numbers(resolution_node, path, "resolution", 2, "2 numbers [width, height]");
  sensor.camera.pinhole = pinhole_from(intrinsics, resolution, path, field_where("intrinsics", intrinsics_node),
                                       field_where("resolution", resolution_node));
  if (distortion_model != "none") {
    sensor.camera.distortion =
        yaml_numbers(require_field(root, "distortion_coefficients", path, "distortion_coefficients"), path,
                     "distortion_coefficients", 4, "4 numbers [k1, k2, p1, p2]");
  }
  const YAML::Node T_node = require_field(root, "T_BS", path, "T_BS");
  const std::string where = field_where("T_BS", T_node);
  if (T_node.IsMap()) {
    const double rows = yaml_number(require_field(T_node, "rows", path, "T_BS.rows"), path, "T_BS.rows");
    const double cols = yaml_number(require_field(T_node, "cols", path, "T_BS.cols"), path, "T_BS.cols");
    if (rows != 4 || cols != 4) {
      throw InputError(path, where,
                       "expected rows: 4, cols: 4, found " + format_number(rows) + "x" + format_number(cols));
    }
    const auto data = yaml_numbers(require_field(T_node, "data", path, "T_BS.data"), path, "T_BS.data", 16,
                                   "16 numbers (4x4 row-major)");
    sensor.T_B_S = se3_from_4x4(data, path, where);
  } else {
    const auto data = yaml_numbers(T_node, path, "T_BS", 16, "16 numbers (4x4 row-major)");
    sensor.T_B_S = se3_from_4x4(data, path, where);
  }
  return sensor;
}

RawStereoRig load_euroc_rig(const std::string& cam0_sensor_yaml, const std::string& cam1_sensor_yaml) {
  const EurocCameraSensor cam0 = load_euroc_sensor(cam0_sensor_yaml);
  const EurocCameraSensor cam1 = load_euroc_sensor(cam1_sensor_yaml);
  RawStereoRig rig;
  rig.cam0 = cam0.camera;
  rig.cam1 = cam1.camera;
  rig.T_cam1_cam0 = cam1.T_B_S.inverse() * cam0.T_B_S;
  return rig;
}

StereoCalibration load_euroc_calibration(const std::string& cam0_sensor_yaml, const std::string& cam1_sensor_yaml) {
  return rectify_checked(load_euroc_rig(cam0_sensor_yaml, cam1_sensor_yaml), cam1_sensor_yaml, "field 'T_BS'");
}

StereoCalibration load_calibration(const std::string& path, std::optional<cv::Size> image_size) {
  switch (detect_calibration_kind(path)) {
    case CalibKind::kOrbSlam:
      return load_orbslam_yaml(path);
    case CalibKind::kKalibr:
      return load_kalibr_camchain(path);
    case CalibKind::kKitti:
      if (!image_size) {
        throw InputError(path, "image size",
                         "a KITTI calib.txt does not give the image size: expected it from the caller");
      }
      return load_kitti_calib(path, *image_size);
    case CalibKind::kEurocSensor: {
      // A sensor.yaml describes one camera; the stereo pair needs cam0/sensor.yaml and cam1/sensor.yaml.
      const fs::path p(path);
      const fs::path folder = p.parent_path();
      if (folder.filename() == "cam0") {
        const fs::path other = folder.parent_path() / "cam1" / p.filename();
        if (fs::exists(other)) return load_euroc_calibration(path, other.string());
      }
      throw InputError(path, "",
                       "expected a stereo calibration; an EuRoC sensor.yaml describes one camera (pass "
                       "mav0/cam0/sensor.yaml with mav0/cam1/sensor.yaml beside it)");
    }
    case CalibKind::kUnknown:
      break;
  }
  throw InputError(path, "",
                   "expected a calibration file: KITTI calib.txt (P0/P1 lines), ORB-SLAM YAML (Camera.fx, "
                   "Camera.bf), Kalibr camchain (cam0/cam1) or EuRoC mav0/cam0/sensor.yaml");
}

}  // namespace agvslam::io
