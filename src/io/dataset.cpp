#include "agvslam/io/dataset.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "agvslam/core/error.h"
#include "agvslam/io/calibration_io.h"
#include "agvslam/io/rosbag_dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "text_util.h"

namespace agvslam::io {
namespace fs = std::filesystem;
using detail::LineReader;

namespace {

constexpr int64_t kEurocPairToleranceNs = 1'000'000;    // left/right stamps closer than 1 ms are one pair
constexpr int64_t kGroundTruthToleranceNs = 5'000'000;  // a frame gets ground truth within 5 ms
constexpr std::size_t kMaxWarningsPerKind = 5;

bool is_folder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

void require_folder(const std::string& root) {
  std::error_code ec;
  if (!fs::exists(root, ec)) throw InputError(root, "", "folder not found");
  if (!fs::is_directory(root, ec)) throw InputError(root, "", "expected a folder, found a file");
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Orders "2.png" before "10.png" when both names are numbers; otherwise plain lexicographic order.
bool image_name_less(const std::string& a, const std::string& b) {
  const std::string stem_a = fs::path(a).stem().string(), stem_b = fs::path(b).stem().string();
  if (all_digits(stem_a) && all_digits(stem_b)) {
    const std::size_t za = std::min(stem_a.find_first_not_of('0'), stem_a.size() - 1);
    const std::size_t zb = std::min(stem_b.find_first_not_of('0'), stem_b.size() - 1);
    const std::string_view va = std::string_view(stem_a).substr(za), vb = std::string_view(stem_b).substr(zb);
    if (va.size() != vb.size()) return va.size() < vb.size();
    if (va != vb) return va < vb;
  }
  return a < b;
}

std::vector<std::string> list_png_names(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".png") names.push_back(entry.path().filename().string());
  }
  if (ec) throw InputError(folder.string(), "", "cannot list the folder (" + ec.message() + ")");
  std::sort(names.begin(), names.end(), image_name_less);
  return names;
}

std::string size_text(const cv::Size& size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

cv::Mat read_grey(const std::string& path, const cv::Size& expected_size) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    throw InputError(path, "", is_file(path) ? "expected a readable image" : "file not found");
  }
  if (!expected_size.empty() && image.size() != expected_size) {
    throw InputError(
        path, "image size",
        "expected " + size_text(expected_size) + " like the first frame, found " + size_text(image.size()));
  }
  return image;
}

double rate_from_times(const std::vector<int64_t>& times_ns, double fallback_hz) {
  if (times_ns.size() < 2) return fallback_hz;
  const int64_t span_ns = times_ns.back() - times_ns.front();
  if (span_ns <= 0) return fallback_hz;
  return static_cast<double>(times_ns.size() - 1) / ns_to_s(span_ns);
}

SE3d interpolate(const SE3d& a, const SE3d& b, double alpha) {
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  const Eigen::Vector3d t = (1.0 - alpha) * a.translation() + alpha * b.translation();
  return make_se3(qa.slerp(alpha, qb), t);
}

struct CsvImage {
  int64_t t_ns = 0;
  std::string path;
};

// mav0/camN/data.csv: "#timestamp [ns],filename". Rows whose image is missing are dropped (counted in *missing).
std::vector<CsvImage> read_euroc_image_csv(const fs::path& cam_dir, std::size_t& missing, std::size_t& warnings_left) {
  const std::string csv_path = (cam_dir / "data.csv").string();
  LineReader reader(csv_path, detail::read_text_file(csv_path));
  std::vector<CsvImage> images;
  std::string_view line;
  while (reader.next(line)) {
    if (detail::is_blank_or_comment(line)) continue;
    const auto fields = detail::split_csv(line);
    if (fields.size() != 2 || fields[1].empty()) {
      throw InputError(
          csv_path, reader.where(),
          "expected 2 comma-separated fields 'timestamp [ns],filename', found " + std::to_string(fields.size()));
    }
    CsvImage image;
    if (!detail::parse_ns(fields[0], image.t_ns)) {
      throw InputError(csv_path, reader.where(),
                       "expected a time stamp in nanoseconds, found '" + std::string(fields[0]) + "'");
    }
    image.path = (cam_dir / "data" / std::string(fields[1])).string();
    if (!is_file(image.path)) {
      ++missing;
      if (warnings_left > 0) {
        --warnings_left;
        spdlog::warn("{}: {}: image {} is missing, frame skipped", csv_path, reader.where(), image.path);
      }
      continue;
    }
    images.push_back(std::move(image));
  }
  std::stable_sort(images.begin(), images.end(), [](const CsvImage& a, const CsvImage& b) { return a.t_ns < b.t_ns; });
  return images;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// KITTI

KittiDataset::KittiDataset(const std::string& root, const std::string& calib_override) : root_(root) {
  require_folder(root);
  const fs::path base(root);
  std::string left_name, right_name;
  if (is_folder(base / "image_0")) {
    left_name = "image_0";
    right_name = "image_1";
  } else if (is_folder(base / "image_l")) {
    left_name = "image_l";
    right_name = "image_r";
  } else {
    throw InputError(root, "layout", "expected a KITTI folder with image_0/ and image_1/ (or image_l/ and image_r/)");
  }
  left_dir_ = (base / left_name).string();
  right_dir_ = (base / right_name).string();
  if (!is_folder(right_dir_)) {
    throw InputError(root, right_name + "/", "folder not found (expected beside " + left_name + "/)");
  }
  left_names_ = list_png_names(left_dir_);
  right_names_ = list_png_names(right_dir_);
  if (left_names_.empty()) throw InputError(left_dir_, "", "expected .png images, found none");
  if (left_names_.size() != right_names_.size()) {
    throw InputError(right_dir_, "image count",
                     "expected " + std::to_string(left_names_.size()) + " .png images like " + left_name + "/, found " +
                         std::to_string(right_names_.size()));
  }
  for (std::size_t i = 0; i < left_names_.size(); ++i) {
    if (left_names_[i] != right_names_[i]) {
      spdlog::warn("{}: frame {}: left image {} is paired with right image {} (names differ)", root, i, left_names_[i],
                   right_names_[i]);
      break;
    }
  }
  image_size_ = read_grey(left_path(0), {}).size();

  const std::string calib_path = calib_override.empty() ? (base / "calib.txt").string() : calib_override;
  calib_ =
      calib_override.empty() ? load_kitti_calib(calib_path, image_size_) : load_calibration(calib_path, image_size_);
  if (!calib_.needs_rectification && calib_.left.size() != image_size_) {
    throw InputError(calib_path, "image size",
                     "expected the calibration's size " + size_text(calib_.left.size()) + " to match the images (" +
                         size_text(image_size_) + ")");
  }

  const fs::path times_path = base / "times.txt";
  if (is_file(times_path)) {
    times_ns_ = read_kitti_times(times_path.string());
    if (times_ns_.size() != left_names_.size()) {
      throw InputError(times_path.string(), "line count",
                       "expected " + std::to_string(left_names_.size()) + " time stamps (one per image pair in " +
                           left_name + "/), found " + std::to_string(times_ns_.size()));
    }
    for (std::size_t i = 1; i < times_ns_.size(); ++i) {
      if (times_ns_[i] <= times_ns_[i - 1]) {
        throw InputError(times_path.string(), "line " + std::to_string(i + 1),
                         "expected increasing time stamps, found " + detail::format_ns_as_seconds(times_ns_[i]) +
                             " after " + detail::format_ns_as_seconds(times_ns_[i - 1]));
      }
    }
    rate_hz_ = rate_from_times(times_ns_, 10.0);
  } else {
    rate_hz_ = 10.0;
    times_ns_.resize(left_names_.size());
    for (std::size_t i = 0; i < times_ns_.size(); ++i) times_ns_[i] = static_cast<int64_t>(i) * 100'000'000;
  }
}

std::string KittiDataset::left_path(std::size_t i) const { return (fs::path(left_dir_) / left_names_.at(i)).string(); }

std::string KittiDataset::right_path(std::size_t i) const {
  return (fs::path(right_dir_) / right_names_.at(i)).string();
}

StereoFrame KittiDataset::frame(std::size_t i) const {
  StereoFrame frame;
  frame.index = i;
  frame.t_ns = times_ns_.at(i);
  const cv::Mat left = read_grey(left_path(i), image_size_);
  const cv::Mat right = read_grey(right_path(i), image_size_);
  calib_.rectify(left, right, frame.left, frame.right);
  return frame;
}

std::optional<Trajectory> KittiDataset::ground_truth() const {
  const fs::path poses_path = fs::path(root_) / "poses.txt";
  if (!is_file(poses_path)) return std::nullopt;
  Trajectory poses = read_kitti_poses(poses_path.string());
  if (poses.size() > times_ns_.size()) {
    throw InputError(poses_path.string(), "line count",
                     "expected at most " + std::to_string(times_ns_.size()) + " poses (one per frame), found " +
                         std::to_string(poses.size()));
  }
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i].t_ns = times_ns_[i];
  return poses;
}

// An 8-bit single-channel ground-truth image of frame i in <root>/<folder>/, the images' size; empty Mat when absent.
cv::Mat KittiDataset::ground_truth_u8(const char* folder, std::size_t i, const char* content) const {
  const std::string path = (fs::path(root_) / folder / left_names_.at(i)).string();
  if (!is_file(path)) return {};
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty() || image.type() != CV_8UC1) {
    throw InputError(path, "", std::string("expected an 8-bit single-channel PNG ") + content);
  }
  if (image.size() != image_size_) {
    throw InputError(path, "image size",
                     "expected " + size_text(image_size_) + " like the images, found " + size_text(image.size()));
  }
  return image;
}

cv::Mat KittiDataset::ground_truth_mask(std::size_t i) const {
  return ground_truth_u8("mask_0", i, "mask (255 = moving object)");
}

cv::Mat KittiDataset::ground_truth_instances(std::size_t i) const {
  return ground_truth_u8("instance_0", i, "of object ids (0 = none)");
}

cv::Mat KittiDataset::ground_truth_disparity_px(std::size_t i) const {
  const std::string path = (fs::path(root_) / "disp_0" / left_names_.at(i)).string();
  if (!is_file(path)) return {};
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty() || raw.type() != CV_16UC1) {
    throw InputError(path, "", "expected a 16-bit single-channel PNG (disparity * 256, 0 = none)");
  }
  if (raw.size() != image_size_) {
    throw InputError(path, "image size",
                     "expected " + size_text(image_size_) + " like the images, found " + size_text(raw.size()));
  }
  cv::Mat disparity_px;
  raw.convertTo(disparity_px, CV_32FC1, 1.0 / 256.0);  // 0 stays 0 = no disparity
  return disparity_px;
}

// ---------------------------------------------------------------------------------------------------------------
// EuRoC

EurocDataset::EurocDataset(const std::string& root, const std::string& calib_override) : root_(root) {
  require_folder(root);
  const fs::path mav0 = fs::path(root) / "mav0";
  if (!is_folder(mav0)) throw InputError(root, "layout", "expected an EuRoC ASL folder with mav0/");
  const fs::path cam0_dir = mav0 / "cam0", cam1_dir = mav0 / "cam1";
  for (const fs::path& dir : {cam0_dir, cam1_dir}) {
    if (!is_folder(dir))
      throw InputError(dir.string(), "", "folder not found (EuRoC layout needs mav0/cam0 and mav0/cam1)");
  }

  // Pair left and right images by time stamp.
  std::size_t warnings_left = kMaxWarningsPerKind;
  std::size_t missing = 0;
  const std::vector<CsvImage> left = read_euroc_image_csv(cam0_dir, missing, warnings_left);
  const std::vector<CsvImage> right = read_euroc_image_csv(cam1_dir, missing, warnings_left);
  std::size_t unpaired = 0;
  auto skip = [&](const CsvImage& image, const char* side) {
    ++unpaired;
    if (warnings_left > 0) {
      --warnings_left;
      spdlog::warn("{}: {} image at t_ns={} has no partner within 1 ms, frame skipped", root, side, image.t_ns);
    }
  };
  std::size_t i = 0, j = 0;
  while (i < left.size() && j < right.size()) {
    const int64_t dt = left[i].t_ns - right[j].t_ns;
    if (std::abs(dt) <= kEurocPairToleranceNs) {
      // Prefer the closest partner when the next image on either side is nearer.
      if (j + 1 < right.size() && std::abs(left[i].t_ns - right[j + 1].t_ns) < std::abs(dt)) {
        skip(right[j++], "right");
        continue;
      }
      if (i + 1 < left.size() && std::abs(left[i + 1].t_ns - right[j].t_ns) < std::abs(dt)) {
        skip(left[i++], "left");
        continue;
      }
      pairs_.push_back({left[i].t_ns, left[i].path, right[j].path});
      ++i;
      ++j;
    } else if (dt < 0) {
      skip(left[i++], "left");
    } else {
      skip(right[j++], "right");
    }
  }
  for (; i < left.size(); ++i) skip(left[i], "left");
  for (; j < right.size(); ++j) skip(right[j], "right");
  skipped_ = missing + unpaired;
  if (skipped_ > 0) {
    spdlog::warn("{}: skipped {} listed frames ({} without an image, {} without a partner); {} stereo pairs", root,
                 skipped_, missing, unpaired, pairs_.size());
  }
  if (pairs_.empty()) {
    throw InputError((cam0_dir / "data.csv").string(), "",
                     "expected at least one left/right image pair (time stamps within 1 ms), found none");
  }
  std::vector<int64_t> times_ns;
  times_ns.reserve(pairs_.size());
  for (const Pair& pair : pairs_) times_ns.push_back(pair.t_ns);
  rate_hz_ = rate_from_times(times_ns, 20.0);

  image_size_ = read_grey(pairs_.front().left_path, {}).size();
  const std::string cam0_yaml = (cam0_dir / "sensor.yaml").string();
  const std::string cam1_yaml = (cam1_dir / "sensor.yaml").string();
  if (calib_override.empty()) {
    const EurocCameraSensor cam0 = load_euroc_sensor(cam0_yaml);
    T_B_cam0_ = cam0.T_B_S;
    calib_ = load_euroc_calibration(cam0_yaml, cam1_yaml);
    if (cam0.camera.pinhole.size() != image_size_) {
      throw InputError(cam0_yaml, "field 'resolution'",
                       "expected the image size " + size_text(image_size_) + " (of " + pairs_.front().left_path +
                           "), found " + size_text(cam0.camera.pinhole.size()));
    }
  } else {
    calib_ = load_calibration(calib_override, image_size_);
    if (is_file(cam0_yaml)) {
      T_B_cam0_ = load_euroc_sensor(cam0_yaml).T_B_S;
    } else {
      spdlog::warn("{}: not found; ground truth will assume cam0 = body frame", cam0_yaml);
    }
  }
}

StereoFrame EurocDataset::frame(std::size_t i) const {
  const Pair& pair = pairs_.at(i);
  StereoFrame frame;
  frame.index = i;
  frame.t_ns = pair.t_ns;
  const cv::Mat left = read_grey(pair.left_path, image_size_);
  const cv::Mat right = read_grey(pair.right_path, image_size_);
  calib_.rectify(left, right, frame.left, frame.right);
  return frame;
}

std::optional<Trajectory> EurocDataset::ground_truth() const {
  const fs::path gt_path = fs::path(root_) / "mav0" / "state_groundtruth_estimate0" / "data.csv";
  if (!is_file(gt_path)) return std::nullopt;
  Trajectory body = read_euroc_csv(gt_path.string());  // T_w_B (p_RS_R, q_RS)
  std::stable_sort(body.begin(), body.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.t_ns < b.t_ns; });
  const SE3d T_B_rect = T_B_cam0_ * calib_.T_cam0_rect;
  Trajectory trajectory;
  for (const Pair& pair : pairs_) {
    const int64_t t = pair.t_ns;
    const auto after = std::lower_bound(body.begin(), body.end(), t,
                                        [](const StampedPose& p, int64_t value) { return p.t_ns < value; });
    const StampedPose* next = after != body.end() ? &*after : nullptr;
    const StampedPose* prev = after != body.begin() ? &*(after - 1) : nullptr;
    SE3d T_w_B;
    if (next && next->t_ns == t) {
      T_w_B = next->T_w_c;
    } else if (prev && next && t - prev->t_ns <= kGroundTruthToleranceNs && next->t_ns - t <= kGroundTruthToleranceNs) {
      const double alpha = static_cast<double>(t - prev->t_ns) / static_cast<double>(next->t_ns - prev->t_ns);
      T_w_B = interpolate(prev->T_w_c, next->T_w_c, alpha);
    } else if (prev && t - prev->t_ns <= kGroundTruthToleranceNs && (!next || t - prev->t_ns <= next->t_ns - t)) {
      T_w_B = prev->T_w_c;
    } else if (next && next->t_ns - t <= kGroundTruthToleranceNs) {
      T_w_B = next->T_w_c;
    } else {
      continue;  // no ground truth within 5 ms
    }
    trajectory.push_back({t, T_w_B * T_B_rect});
  }
  if (trajectory.empty()) spdlog::warn("{}: no ground-truth sample within 5 ms of any frame", gt_path.string());
  return trajectory;
}

// ---------------------------------------------------------------------------------------------------------------

std::unique_ptr<StereoDataset> open_dataset(const std::string& path, const std::string& calib_override) {
  // "BAG?left=..&right=..": a rosbag2 folder with its topic choice (a folder whose name holds '?' stays whole).
  std::error_code ec;
  const std::size_t query_at = fs::exists(path, ec) ? std::string::npos : path.find('?');
  const std::string root = path.substr(0, query_at);
  if (is_file(fs::path(root) / "metadata.yaml")) {
    const RosbagTopics topics =
        query_at == std::string::npos ? RosbagTopics{} : parse_rosbag_topics(path.substr(query_at + 1), path);
    return std::make_unique<RosbagDataset>(root, calib_override, topics);
  }
  if (query_at != std::string::npos && is_folder(root)) {
    throw InputError(path, "topic choice",
                     "expected a rosbag2 folder (with metadata.yaml) before '?', " + root + " has no metadata.yaml");
  }
  require_folder(root);
  fs::path base = fs::path(root).lexically_normal();
  if (base.filename().empty()) base = base.parent_path();  // "seq/mav0/" -> "seq/mav0"
  if (is_folder(base / "mav0")) return std::make_unique<EurocDataset>(root, calib_override);
  // The mav0 folder itself was given.
  if (base.filename() == "mav0" && is_folder(base / "cam0") && is_folder(base / "cam1")) {
    return std::make_unique<EurocDataset>(base.parent_path().string(), calib_override);
  }
  if (is_folder(base / "image_0") || is_folder(base / "image_l")) {
    return std::make_unique<KittiDataset>(root, calib_override);
  }
  throw InputError(root, "layout",
                   "expected a KITTI odometry folder (image_0/ + image_1/ or image_l/ + image_r/), an EuRoC ASL "
                   "folder (mav0/cam0/, mav0/cam1/) or a rosbag2 folder (metadata.yaml + .db3)");
}

void parse_frame_range(const std::string& text, std::size_t size, const std::string& source, const std::string& field,
                       std::size_t& first, std::size_t& last) {
  if (size == 0) throw InputError(source, field, "expected a sequence with at least one frame");
  first = 0;
  last = size - 1;
  if (text.empty()) return;
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    throw InputError(source, field, "expected A:B (inclusive frame range, e.g. 0:199), got '" + text + "'");
  }
  auto parse = [&](const std::string& s, std::size_t& value) {
    if (s.empty()) return;
    std::size_t used = 0;
    long long v = -1;
    try {
      v = std::stoll(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != s.size() || v < 0)
      throw InputError(source, field, "expected non-negative integers in A:B, got '" + text + "'");
    value = static_cast<std::size_t>(v);
  };
  parse(text.substr(0, colon), first);
  parse(text.substr(colon + 1), last);
  if (first >= size) {
    throw InputError(source, field,
                     "expected a range inside the sequence's " + std::to_string(size) + " frames, got '" + text + "'");
  }
  last = std::min(last, size - 1);
  if (last < first) throw InputError(source, field, "expected A <= B, got '" + text + "'");
}

}  // namespace agvslam::io
