#include "agvslam/io/rosbag_dataset.h"

#include <spdlog/spdlog.h>
#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "agvslam/core/error.h"
#include "agvslam/io/calibration_io.h"
#include "cdr.h"
#include "ros_message_decode.h"
#include "text_util.h"

namespace agvslam::io {
namespace fs = std::filesystem;
using detail::CdrReader;

namespace {

constexpr const char* kImageType = "sensor_msgs/msg/Image";
constexpr const char* kCompressedImageType = "sensor_msgs/msg/CompressedImage";
constexpr const char* kCameraInfoType = "sensor_msgs/msg/CameraInfo";
constexpr const char* kOdometryType = "nav_msgs/msg/Odometry";
// Encapsulation header (4) + header.stamp (sec, nanosec): enough of a message to order and pair it.
constexpr std::size_t kStampPrefixBytes = 12;
constexpr std::size_t kMaxWarningsPerKind = 5;
constexpr double kDefaultRateHz = 10.0;

struct TopicInfo {
  std::string name, type, serialization_format;
};

bool is_image_type(const std::string& type) { return type == kImageType || type == kCompressedImageType; }

std::string list_topics(const std::vector<TopicInfo>& topics) {
  std::string text;
  for (const TopicInfo& t : topics) text += (text.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return text.empty() ? "no topics" : text;
}

const TopicInfo* find_topic(const std::vector<TopicInfo>& topics, const std::string& name) {
  for (const TopicInfo& t : topics) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

// A scalar string field of a metadata.yaml map; InputError naming the field when missing or not a string.
std::string yaml_string(const YAML::Node& node, const char* key, const std::string& path, const std::string& where) {
  const YAML::Node value = node[key];
  if (!value || !value.IsScalar()) {
    throw InputError(path, "field '" + where + key + "'", "missing (expected a string as ros2 bag record writes)");
  }
  return value.as<std::string>();
}

// "/cam/left/image_raw" and "/cam/left/image_raw/compressed" -> "/cam/left/camera_info".
std::string camera_info_topic(const std::string& image_topic, bool compressed) {
  std::string base = image_topic;
  const std::string suffix = "/compressed";
  if (compressed && base.size() > suffix.size() &&
      base.compare(base.size() - suffix.size(), suffix.size(), suffix) == 0)
    base.resize(base.size() - suffix.size());
  const auto slash = base.rfind('/');
  return (slash == std::string::npos ? std::string() : base.substr(0, slash)) + "/camera_info";
}

// True when a path element of the topic name contains `side` ("left" / "right"), any case.
bool names_side(const std::string& topic, const std::string& side) {
  std::string lower = topic;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower.find(side) != std::string::npos;
}

std::string size_text(const cv::Size& size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

}  // namespace

namespace detail {

CameraInfo decode_camera_info(CdrReader& in, const std::string& topic) {
  CameraInfo info;
  info.topic = topic;
  detail::read_header_stamp_ns(in);
  in.string("header.frame_id");
  info.height = static_cast<int>(in.u32("height"));
  info.width = static_cast<int>(in.u32("width"));
  info.distortion_model = in.string("distortion_model");
  info.d = in.f64_sequence("d");
  info.k = in.f64_array("k", 9);
  info.r = in.f64_array("r", 9);
  info.p = in.f64_array("p", 12);
  return info;
}

BagOdometrySample decode_odometry(CdrReader& in) {
  BagOdometrySample s;
  s.t_ns = detail::read_header_stamp_ns(in);
  s.frame_id = in.string("header.frame_id");
  s.child_frame_id = in.string("child_frame_id");
  Eigen::Vector3d position;
  for (int i = 0; i < 3; ++i) position[i] = in.f64("pose.pose.position");
  const double qx = in.f64("pose.pose.orientation"), qy = in.f64("pose.pose.orientation");
  const double qz = in.f64("pose.pose.orientation"), qw = in.f64("pose.pose.orientation");
  in.f64_array("pose.covariance", 36);
  for (int i = 0; i < 3; ++i) s.linear_mps[i] = in.f64("twist.twist.linear");
  for (int i = 0; i < 3; ++i) s.angular_radps[i] = in.f64("twist.twist.angular");
  in.f64_array("twist.covariance", 36);
  Eigen::Quaterniond q(qw, qx, qy, qz);
  // An unset orientation (all zero) is how some drivers say "no pose": the twist is still good.
  q = q.norm() > 1e-9 ? q.normalized() : Eigen::Quaterniond::Identity();
  s.T_frame_child = make_se3(q, position);
  return s;
}

cv::Mat decode_raw_image(CdrReader& in, const std::string& source, const std::string& context) {
  detail::read_header_stamp_ns(in);
  in.string("header.frame_id");
  const uint32_t height = in.u32("height"), width = in.u32("width");
  const std::string encoding = in.string("encoding");
  const bool data_big_endian = in.u8("is_bigendian") != 0;
  const uint32_t step = in.u32("step");
  std::size_t data_bytes = 0;
  const uint8_t* data = in.byte_sequence("data", data_bytes);

  // sensor_msgs/image_encodings names; conversion: cvtColor code to grey, -1 = none.
  struct Encoding {
    const char* name;
    int type, conversion;
  };
  static const Encoding kEncodings[] = {
      {"mono8", CV_8UC1, -1},
      {"8UC1", CV_8UC1, -1},
      {"mono16", CV_16UC1, -1},
      {"16UC1", CV_16UC1, -1},
      {"bgr8", CV_8UC3, cv::COLOR_BGR2GRAY},
      {"8UC3", CV_8UC3, cv::COLOR_BGR2GRAY},
      {"rgb8", CV_8UC3, cv::COLOR_RGB2GRAY},
      {"bgra8", CV_8UC4, cv::COLOR_BGRA2GRAY},
      {"8UC4", CV_8UC4, cv::COLOR_BGRA2GRAY},
      {"rgba8", CV_8UC4, cv::COLOR_RGBA2GRAY},
  };
  const auto known =
      std::find_if(std::begin(kEncodings), std::end(kEncodings), [&](const Encoding& e) { return encoding == e.name; });
  if (known == std::end(kEncodings)) {
    throw InputError(source, context + " field 'encoding'",
                     "expected mono8, mono16, bgr8, rgb8, bgra8 or rgba8, found '" + encoding + "'");
  }
  const int type = known->type, conversion = known->conversion;
  if (width == 0 || height == 0) {
    throw InputError(source, context + " field 'width'/'height'",
                     "expected a non-empty image, found " + std::to_string(width) + "x" + std::to_string(height));
  }
  const std::size_t row_bytes = static_cast<std::size_t>(width) * CV_ELEM_SIZE(type);
  if (step < row_bytes) {
    throw InputError(source, context + " field 'step'",
                     "expected at least " + std::to_string(row_bytes) + " bytes a row (" + std::to_string(width) +
                         " pixels of " + encoding + "), found " + std::to_string(step));
  }
  if (step % CV_ELEM_SIZE1(type) != 0) {
    throw InputError(source, context + " field 'step'",
                     "expected a multiple of the " + std::to_string(CV_ELEM_SIZE1(type)) + "-byte samples of " +
                         encoding + ", found " + std::to_string(step));
  }
  if (data_bytes < static_cast<std::size_t>(step) * height) {
    throw InputError(source, context + " field 'data'",
                     "expected step * height = " + std::to_string(static_cast<std::size_t>(step) * height) +
                         " bytes, found " + std::to_string(data_bytes));
  }
  const cv::Mat view(static_cast<int>(height), static_cast<int>(width), type, const_cast<uint8_t*>(data), step);
  cv::Mat grey;
  if (type == CV_16UC1) {
    cv::Mat wide = view.clone();
    const uint16_t probe = 1;
    const bool host_big_endian = *reinterpret_cast<const uint8_t*>(&probe) == 0;
    if (data_big_endian != host_big_endian) {
      for (int y = 0; y < wide.rows; ++y) {
        auto* row = wide.ptr<uint16_t>(y);
        for (int x = 0; x < wide.cols; ++x) row[x] = static_cast<uint16_t>((row[x] >> 8) | (row[x] << 8));
      }
    }
    wide.convertTo(grey, CV_8UC1, 1.0 / 256.0);  // keep the top 8 bits, as a PNG read as grey does
  } else if (conversion >= 0) {
    cv::cvtColor(view, grey, conversion);
  } else {
    grey = view.clone();
  }
  return grey;
}

cv::Mat decode_compressed_image(CdrReader& in, const std::string& source, const std::string& context) {
  detail::read_header_stamp_ns(in);
  in.string("header.frame_id");
  const std::string format = in.string("format");
  std::size_t data_bytes = 0;
  const uint8_t* data = in.byte_sequence("data", data_bytes);
  cv::Mat grey;
  if (data_bytes > 0) {
    const cv::Mat encoded(1, static_cast<int>(data_bytes), CV_8UC1, const_cast<uint8_t*>(data));
    grey = cv::imdecode(encoded, cv::IMREAD_GRAYSCALE);
  }
  if (grey.empty()) {
    throw InputError(source, context + " field 'data'",
                     "expected a PNG or JPEG image (format '" + format + "'), " + std::to_string(data_bytes) +
                         " bytes that cv::imdecode cannot decode");
  }
  return grey;
}

}  // namespace detail

using detail::CameraInfo;
using detail::decode_camera_info;
using detail::decode_compressed_image;
using detail::decode_odometry;
using detail::decode_raw_image;

// ---------------------------------------------------------------------------------------------------------------
// The .db3 files

struct RosbagDataset::Storage {
  struct File {
    std::string path;
    sqlite3* db = nullptr;
    std::map<std::string, int64_t> topic_ids;  // topics.name -> topics.id of this file
  };
  std::vector<File> files;

  ~Storage() {
    for (File& f : files) sqlite3_close(f.db);
  }

  [[noreturn]] static void fail(const File& f, const std::string& where, const std::string& what) {
    throw InputError(f.path, where, what + " (sqlite: " + sqlite3_errmsg(f.db) + ")");
  }

  // Opens a .db3 and reads its topics table; a file that is not a rosbag2 sqlite3 database is an InputError.
  void open(const std::string& path) {
    File f;
    f.path = path;
    if (sqlite3_open_v2(path.c_str(), &f.db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string message = f.db ? sqlite3_errmsg(f.db) : "out of memory";
      sqlite3_close(f.db);
      throw InputError(path, "", "expected a rosbag2 sqlite3 database, cannot open it (sqlite: " + message + ")");
    }
    files.push_back(f);
    File& file = files.back();
    sqlite3_stmt* check = nullptr;
    if (sqlite3_prepare_v2(file.db, "SELECT id, topic_id, timestamp, data FROM messages LIMIT 0", -1, &check,
                           nullptr) != SQLITE_OK) {
      sqlite3_finalize(check);
      fail(file, "table 'messages'",
           "expected a rosbag2 sqlite3 database with messages(id, topic_id, timestamp, data)");
    }
    sqlite3_finalize(check);
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(file.db, "SELECT id, name FROM topics", -1, &stmt, nullptr) != SQLITE_OK) {
      sqlite3_finalize(stmt);
      fail(file, "table 'topics'", "expected a rosbag2 sqlite3 database with topics(id, name, type, ...)");
    }
    int rc = SQLITE_OK;
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const auto* name = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
      if (name) file.topic_ids[name] = sqlite3_column_int64(stmt, 0);
    }
    sqlite3_finalize(stmt);
    if (rc != SQLITE_DONE) fail(file, "table 'topics'", "expected a readable topics table");
  }

  // messages.id of every message of `topic`, in recording order, each with its file index.
  std::vector<std::pair<std::size_t, int64_t>> message_ids(const std::string& topic) const {
    std::vector<std::pair<std::size_t, int64_t>> ids;
    for (std::size_t i = 0; i < files.size(); ++i) {
      const File& f = files[i];
      const auto it = f.topic_ids.find(topic);
      if (it == f.topic_ids.end()) continue;
      sqlite3_stmt* stmt = nullptr;
      if (sqlite3_prepare_v2(f.db, "SELECT id FROM messages WHERE topic_id = ?1 ORDER BY timestamp, id", -1, &stmt,
                             nullptr) != SQLITE_OK) {
        sqlite3_finalize(stmt);
        fail(f, "table 'messages'", "expected to list the messages of " + topic);
      }
      sqlite3_bind_int64(stmt, 1, it->second);
      int rc = SQLITE_OK;
      while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) ids.emplace_back(i, sqlite3_column_int64(stmt, 0));
      sqlite3_finalize(stmt);
      if (rc != SQLITE_DONE) fail(f, "table 'messages'", "expected to list the messages of " + topic);
    }
    return ids;
  }

  // The message's data column, or only its first max_bytes (0 = all).
  std::vector<uint8_t> read(std::size_t file, int64_t row_id, std::size_t max_bytes = 0) const {
    const File& f = files.at(file);
    sqlite3_blob* blob = nullptr;
    if (sqlite3_blob_open(f.db, "main", "messages", "data", row_id, 0, &blob) != SQLITE_OK) {
      sqlite3_blob_close(blob);
      fail(f, "messages.id " + std::to_string(row_id), "expected a readable message");
    }
    const auto size = static_cast<std::size_t>(sqlite3_blob_bytes(blob));
    std::vector<uint8_t> data(max_bytes > 0 ? std::min(size, max_bytes) : size);
    const int rc = data.empty() ? SQLITE_OK : sqlite3_blob_read(blob, data.data(), static_cast<int>(data.size()), 0);
    if (rc != SQLITE_OK) {
      sqlite3_blob_close(blob);
      fail(f, "messages.id " + std::to_string(row_id), "expected a readable message");
    }
    sqlite3_blob_close(blob);
    return data;
  }
};

// ---------------------------------------------------------------------------------------------------------------

RosbagTopics parse_rosbag_topics(const std::string& query, const std::string& source) {
  RosbagTopics topics;
  std::size_t start = 0;
  while (start <= query.size()) {
    const std::size_t end = std::min(query.find('&', start), query.size());
    const std::string item = query.substr(start, end - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq + 1 == item.size()) {
      throw InputError(source, "topic choice '" + item + "'",
                       "expected key=TOPIC pairs joined by '&' (keys left, right, odom)");
    }
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "left") {
      topics.left = value;
    } else if (key == "right") {
      topics.right = value;
    } else if (key == "odom") {
      topics.odometry = value;
    } else {
      throw InputError(source, "topic choice '" + item + "'", "expected one of the keys left, right, odom");
    }
    start = end + 1;
  }
  return topics;
}

RosbagDataset::RosbagDataset(const std::string& bag_dir, const std::string& calib_override, const RosbagTopics& chosen)
    : root_(bag_dir), storage_(std::make_unique<Storage>()) {
  // metadata.yaml
  const fs::path base(bag_dir);
  const std::string metadata_path = (base / "metadata.yaml").string();
  YAML::Node document;
  try {
    document = YAML::Load(detail::read_text_file(metadata_path));
  } catch (const YAML::Exception& e) {
    throw InputError(metadata_path, "line " + std::to_string(e.mark.line + 1), "expected YAML: " + e.msg);
  }
  // Subscripting a scalar or a sequence throws YAML::BadSubscript: every node is checked to be a map first.
  const YAML::Node info = document.IsMap() ? document["rosbag2_bagfile_information"] : YAML::Node();
  if (!info || !info.IsMap()) {
    throw InputError(metadata_path, "field 'rosbag2_bagfile_information'",
                     "missing (expected the metadata.yaml that ros2 bag record writes)");
  }
  const std::string prefix = "rosbag2_bagfile_information.";
  const std::string storage_id = yaml_string(info, "storage_identifier", metadata_path, prefix);
  if (storage_id == "mcap") {
    throw InputError(metadata_path, "field '" + prefix + "storage_identifier'",
                     "expected sqlite3, found mcap (convert the bag: ros2 bag convert with storage_id sqlite3)");
  }
  if (storage_id != "sqlite3") {
    throw InputError(metadata_path, "field '" + prefix + "storage_identifier'",
                     "expected sqlite3, found '" + storage_id + "'");
  }
  if (const YAML::Node compression = info["compression_format"];
      compression && compression.IsScalar() && !compression.as<std::string>().empty()) {
    throw InputError(metadata_path, "field '" + prefix + "compression_format'",
                     "expected an uncompressed bag, found '" + compression.as<std::string>() +
                         "' (decompress it: ros2 bag decompress)");
  }
  const YAML::Node files = info["relative_file_paths"];
  if (!files || !files.IsSequence() || files.size() == 0) {
    throw InputError(metadata_path, "field '" + prefix + "relative_file_paths'",
                     "missing (expected the list of the bag's .db3 files)");
  }
  const YAML::Node topic_list = info["topics_with_message_count"];
  if (!topic_list || !topic_list.IsSequence()) {
    throw InputError(metadata_path, "field '" + prefix + "topics_with_message_count'",
                     "missing (expected the list of the bag's topics)");
  }
  std::vector<TopicInfo> topics;
  for (std::size_t i = 0; i < topic_list.size(); ++i) {
    const std::string where = prefix + "topics_with_message_count[" + std::to_string(i) + "].topic_metadata.";
    const YAML::Node meta = topic_list[i].IsMap() ? topic_list[i]["topic_metadata"] : YAML::Node();
    if (!meta || !meta.IsMap()) {
      throw InputError(metadata_path, "field '" + where.substr(0, where.size() - 1) + "'",
                       "missing (expected name, type, serialization_format)");
    }
    topics.push_back({yaml_string(meta, "name", metadata_path, where), yaml_string(meta, "type", metadata_path, where),
                      yaml_string(meta, "serialization_format", metadata_path, where)});
  }

  // The .db3 files: relative to the bag folder (older bags name them relative to its parent).
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (!files[i].IsScalar()) {
      throw InputError(metadata_path, "field '" + prefix + "relative_file_paths[" + std::to_string(i) + "]'",
                       "expected a file name");
    }
    const std::string name = files[i].as<std::string>();
    fs::path path = base / name;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec) && fs::is_regular_file(base.parent_path() / name, ec))
      path = base.parent_path() / name;
    if (!fs::is_regular_file(path, ec)) {
      throw InputError(metadata_path, "field '" + prefix + "relative_file_paths[" + std::to_string(i) + "]'",
                       "expected the file " + path.string() + ", not found");
    }
    storage_->open(path.string());
  }

  // The image topics.
  auto check_image_topic = [&](const std::string& name, const char* side) {
    const TopicInfo* t = find_topic(topics, name);
    if (!t || !is_image_type(t->type)) {
      throw InputError(bag_dir, std::string("topic choice ") + side + "=" + name,
                       "expected an image topic of the bag (sensor_msgs/msg/Image or CompressedImage); the bag has " +
                           list_topics(topics));
    }
  };
  std::vector<TopicInfo> image_topics;
  for (const TopicInfo& t : topics) {
    if (is_image_type(t.type)) image_topics.push_back(t);
  }
  std::sort(image_topics.begin(), image_topics.end(),
            [](const TopicInfo& a, const TopicInfo& b) { return a.name < b.name; });
  left_topic_ = chosen.left;
  right_topic_ = chosen.right;
  if (left_topic_.empty() || right_topic_.empty()) {
    // image_transport recordings often hold T and T/compressed side by side: T is the same picture, lossless.
    const std::string suffix = "/compressed";
    std::vector<std::string> candidates, lefts, rights;
    for (const TopicInfo& t : image_topics) {
      const bool has_raw_twin = t.type == kCompressedImageType && t.name.size() > suffix.size() &&
                                t.name.compare(t.name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
                                find_topic(image_topics, t.name.substr(0, t.name.size() - suffix.size()));
      if (has_raw_twin || t.name == chosen.left || t.name == chosen.right) continue;
      candidates.push_back(t.name);
      if (names_side(t.name, "left")) lefts.push_back(t.name);
      if (names_side(t.name, "right")) rights.push_back(t.name);
    }
    if (left_topic_.empty() && lefts.size() == 1) left_topic_ = lefts.front();
    if (right_topic_.empty() && rights.size() == 1) right_topic_ = rights.front();
    if (lefts.empty() && rights.empty()) {
      if (left_topic_.empty() && right_topic_.empty() && candidates.size() == 2) {
        left_topic_ = candidates[0];
        right_topic_ = candidates[1];
        spdlog::warn("{}: no image topic names a side; {} taken as the left camera, {} as the right one", bag_dir,
                     left_topic_, right_topic_);
      } else if ((left_topic_.empty() != right_topic_.empty()) && candidates.size() == 1) {
        (left_topic_.empty() ? left_topic_ : right_topic_) = candidates[0];  // the other one was chosen
      }
    }
    if (left_topic_.empty() || right_topic_.empty()) {
      throw InputError(bag_dir, "image topics",
                       "expected one left and one right image topic (sensor_msgs/msg/Image or CompressedImage, "
                       "names with left / right, or exactly two), found " +
                           std::to_string(image_topics.size()) + " image topics among " + list_topics(topics) +
                           "; choose them with " + bag_dir + "?left=TOPIC&right=TOPIC");
    }
  }
  check_image_topic(left_topic_, "left");
  check_image_topic(right_topic_, "right");
  if (left_topic_ == right_topic_) {
    throw InputError(bag_dir, "topic choice", "expected two different image topics, found " + left_topic_ + " twice");
  }
  for (const std::string& name : {left_topic_, right_topic_}) {
    if (find_topic(topics, name)->serialization_format != "cdr") {
      throw InputError(metadata_path, "topic " + name + " serialization_format",
                       "expected cdr, found '" + find_topic(topics, name)->serialization_format + "'");
    }
  }
  left_compressed_ = find_topic(topics, left_topic_)->type == kCompressedImageType;
  right_compressed_ = find_topic(topics, right_topic_)->type == kCompressedImageType;

  // Header stamps of every image, read from the first bytes of each message only.
  std::size_t warnings_left = kMaxWarningsPerKind;
  struct Stamped {
    int64_t t_ns;
    MessageRef ref;
  };
  auto stamps_of = [&](const std::string& topic) {
    std::vector<Stamped> stamped;
    for (const auto& [file, row_id] : storage_->message_ids(topic)) {
      const std::vector<uint8_t> prefix_bytes = storage_->read(file, row_id, kStampPrefixBytes);
      try {
        CdrReader in(prefix_bytes.data(), prefix_bytes.size(), storage_->files[file].path,
                     "topic " + topic + " message id " + std::to_string(row_id));
        stamped.push_back({detail::read_header_stamp_ns(in), {file, row_id}});
      } catch (const InputError& e) {
        ++skipped_;
        if (warnings_left > 0) {
          --warnings_left;
          spdlog::warn("{}: image skipped: {}", bag_dir, e.what());
        }
      }
    }
    std::stable_sort(stamped.begin(), stamped.end(),
                     [](const Stamped& a, const Stamped& b) { return a.t_ns < b.t_ns; });
    return stamped;
  };
  const std::vector<Stamped> left = stamps_of(left_topic_), right = stamps_of(right_topic_);
  if (left.empty() || right.empty()) {
    throw InputError(bag_dir, "topic " + (left.empty() ? left_topic_ : right_topic_),
                     "expected image messages, found none");
  }

  // Pair by header stamp: the closest partner within half the left camera's median frame period.
  std::vector<int64_t> periods_ns;
  for (std::size_t i = 1; i < left.size(); ++i) {
    if (left[i].t_ns > left[i - 1].t_ns) periods_ns.push_back(left[i].t_ns - left[i - 1].t_ns);
  }
  int64_t period_ns = static_cast<int64_t>(1e9 / kDefaultRateHz);
  if (!periods_ns.empty()) {
    std::nth_element(periods_ns.begin(), periods_ns.begin() + periods_ns.size() / 2, periods_ns.end());
    period_ns = periods_ns[periods_ns.size() / 2];
  }
  const int64_t tolerance_ns = period_ns / 2;
  std::size_t unpaired = 0;
  auto skip = [&](const Stamped& image, const std::string& topic) {
    ++unpaired;
    if (warnings_left > 0) {
      --warnings_left;
      spdlog::warn("{}: {} image at t_ns={} has no partner within {} ms, frame skipped", bag_dir, topic, image.t_ns,
                   static_cast<double>(tolerance_ns) * 1e-6);
    }
  };
  std::size_t i = 0, j = 0;
  while (i < left.size() && j < right.size()) {
    const int64_t dt = left[i].t_ns - right[j].t_ns;
    if (std::abs(dt) < tolerance_ns || dt == 0) {
      if (j + 1 < right.size() && std::abs(left[i].t_ns - right[j + 1].t_ns) < std::abs(dt)) {
        skip(right[j++], right_topic_);
        continue;
      }
      if (i + 1 < left.size() && std::abs(left[i + 1].t_ns - right[j].t_ns) < std::abs(dt)) {
        skip(left[i++], left_topic_);
        continue;
      }
      if (!pairs_.empty() && left[i].t_ns == pairs_.back().t_ns) {
        skip(left[i++], left_topic_);  // a repeated stamp: one frame per time
        continue;
      }
      pairs_.push_back({left[i].t_ns, left[i].ref, right[j].ref});
      ++i;
      ++j;
    } else if (dt < 0) {
      skip(left[i++], left_topic_);
    } else {
      skip(right[j++], right_topic_);
    }
  }
  for (; i < left.size(); ++i) skip(left[i], left_topic_);
  for (; j < right.size(); ++j) skip(right[j], right_topic_);
  skipped_ += unpaired;
  if (skipped_ > 0) {
    spdlog::warn("{}: skipped {} images ({} without a partner within {} ms); {} stereo pairs", bag_dir, skipped_,
                 unpaired, static_cast<double>(tolerance_ns) * 1e-6, pairs_.size());
  }
  if (pairs_.empty()) {
    throw InputError(bag_dir, "topics " + left_topic_ + ", " + right_topic_,
                     "expected at least one left/right pair with header stamps within half a frame period, found "
                     "none");
  }
  if (pairs_.size() >= 2 && pairs_.back().t_ns > pairs_.front().t_ns) {
    rate_hz_ = static_cast<double>(pairs_.size() - 1) / ns_to_s(pairs_.back().t_ns - pairs_.front().t_ns);
  }
  image_size_ = read_image(pairs_.front().left, left_topic_, left_compressed_).size();

  // Calibration: a file given, else the camera_info messages beside the image topics.
  if (!calib_override.empty()) {
    calib_ = load_calibration(calib_override, image_size_);
    if (!calib_.needs_rectification && calib_.left.size() != image_size_) {
      throw InputError(calib_override, "image size",
                       "expected the calibration's size " + size_text(calib_.left.size()) +
                           " to match the bag's images (" + size_text(image_size_) + ")");
    }
  } else {
    const std::string left_info_topic = camera_info_topic(left_topic_, left_compressed_);
    const std::string right_info_topic = camera_info_topic(right_topic_, right_compressed_);
    auto first_info = [&](const std::string& topic) -> std::optional<CameraInfo> {
      const TopicInfo* t = find_topic(topics, topic);
      if (!t || t->type != kCameraInfoType) return std::nullopt;
      const auto ids = storage_->message_ids(topic);
      if (ids.empty()) return std::nullopt;
      const std::vector<uint8_t> data = storage_->read(ids.front().first, ids.front().second);
      CdrReader in(data.data(), data.size(), storage_->files[ids.front().first].path,
                   "topic " + topic + " message id " + std::to_string(ids.front().second));
      return decode_camera_info(in, topic);
    };
    const std::optional<CameraInfo> left_info = first_info(left_info_topic);
    const std::optional<CameraInfo> right_info = first_info(right_info_topic);
    if (!left_info || !right_info) {
      throw InputError(bag_dir, "calibration",
                       "expected sensor_msgs/msg/CameraInfo messages on " + left_info_topic + " and " +
                           right_info_topic +
                           " or a calibration file (agvslam-run --calib, agvslamd "
                           "calibration.file); the bag has " +
                           list_topics(topics));
    }
    const cv::Size info_size(left_info->width > 0 ? left_info->width : image_size_.width,
                             left_info->height > 0 ? left_info->height : image_size_.height);
    calib_ = calibration_from_projections(left_info->p, right_info->p, info_size, bag_dir,
                                          left_info_topic + " field 'p'", right_info_topic + " field 'p'");
    if (info_size != image_size_) {
      throw InputError(left_info_topic, "fields 'width'/'height'",
                       "expected the images' size " + size_text(image_size_) + ", found " + size_text(info_size));
    }
    auto is_raw = [](const CameraInfo& c) {
      const bool distorted = std::any_of(c.d.begin(), c.d.end(), [](double v) { return v != 0.0; });
      const bool rotated = c.r != std::vector<double>{1, 0, 0, 0, 1, 0, 0, 0, 1} &&
                           c.r != std::vector<double>(9, 0.0);  // all zero: r not filled in
      return distorted || rotated;
    };
    if (is_raw(*left_info) || is_raw(*right_info)) {
      auto maps = [&](const CameraInfo& c, cv::Mat& map_x, cv::Mat& map_y) {
        const cv::Mat K = cv::Mat(c.k, true).reshape(1, 3), R = cv::Mat(c.r, true).reshape(1, 3);
        const cv::Mat P = cv::Mat(c.p, true).reshape(1, 3)(cv::Rect(0, 0, 3, 3));
        if (c.distortion_model == "equidistant") {
          if (c.d.size() < 4) throw InputError(c.topic, "field 'd'", "expected 4 equidistant coefficients");
          const cv::Mat D = cv::Mat(std::vector<double>(c.d.begin(), c.d.begin() + 4), true);
          cv::fisheye::initUndistortRectifyMap(K, D, R, P, info_size, CV_32FC1, map_x, map_y);
        } else if (c.distortion_model == "plumb_bob" || c.distortion_model == "rational_polynomial" || c.d.empty()) {
          cv::initUndistortRectifyMap(K, cv::Mat(c.d, true), R, P, info_size, CV_32FC1, map_x, map_y);
        } else {
          throw InputError(
              c.topic, "field 'distortion_model'",
              "expected plumb_bob, rational_polynomial or equidistant, found '" + c.distortion_model + "'");
        }
      };
      maps(*left_info, calib_.map_left_x, calib_.map_left_y);
      maps(*right_info, calib_.map_right_x, calib_.map_right_y);
      calib_.needs_rectification = true;
      Eigen::Matrix3d R_rect_cam0;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R_rect_cam0(r, c) = left_info->r[static_cast<std::size_t>(3 * r + c)];
      R_rect_cam0 = detail::checked_rotation(R_rect_cam0, left_info_topic, "field 'r'");
      calib_.T_cam0_rect = make_se3(Eigen::Matrix3d(R_rect_cam0.transpose()), Eigen::Vector3d::Zero());
    }
    calib_from_bag_ = true;
  }

  // Wheel odometry.
  odometry_topic_ = chosen.odometry;
  if (!odometry_topic_.empty()) {
    const TopicInfo* t = find_topic(topics, odometry_topic_);
    if (!t || t->type != kOdometryType) {
      throw InputError(bag_dir, "topic choice odom=" + odometry_topic_,
                       "expected a nav_msgs/msg/Odometry topic of the bag; the bag has " + list_topics(topics));
    }
  } else {
    std::vector<std::string> candidates;
    for (const TopicInfo& t : topics) {
      if (t.type == kOdometryType) candidates.push_back(t.name);
    }
    if (candidates.size() == 1) {
      odometry_topic_ = candidates.front();
    } else if (candidates.size() > 1) {
      spdlog::warn("{}: {} odometry topics, none used; choose one with {}?odom=TOPIC", bag_dir, candidates.size(),
                   bag_dir);
    }
  }
  if (!odometry_topic_.empty()) {
    std::size_t bad = 0;
    for (const auto& [file, row_id] : storage_->message_ids(odometry_topic_)) {
      const std::vector<uint8_t> data = storage_->read(file, row_id);
      try {
        CdrReader in(data.data(), data.size(), storage_->files[file].path,
                     "topic " + odometry_topic_ + " message id " + std::to_string(row_id));
        odometry_.push_back(decode_odometry(in));
      } catch (const InputError& e) {
        if (bad++ < kMaxWarningsPerKind) spdlog::warn("{}: odometry message skipped: {}", bag_dir, e.what());
      }
    }
    std::stable_sort(odometry_.begin(), odometry_.end(),
                     [](const BagOdometrySample& a, const BagOdometrySample& b) { return a.t_ns < b.t_ns; });
  }
}

RosbagDataset::~RosbagDataset() = default;

cv::Mat RosbagDataset::read_image(const MessageRef& ref, const std::string& topic, bool compressed) const {
  std::vector<uint8_t> data;
  {
    const std::lock_guard<std::mutex> lock(storage_mutex_);
    data = storage_->read(ref.file, ref.row_id);
  }
  const std::string& source = storage_->files[ref.file].path;
  const std::string context = "topic " + topic + " message id " + std::to_string(ref.row_id);
  CdrReader in(data.data(), data.size(), source, context);
  cv::Mat grey = compressed ? decode_compressed_image(in, source, context) : decode_raw_image(in, source, context);
  if (!image_size_.empty() && grey.size() != image_size_) {
    throw InputError(source, context + " image size",
                     "expected " + size_text(image_size_) + " like the first frame, found " + size_text(grey.size()));
  }
  return grey;
}

StereoFrame RosbagDataset::frame(std::size_t i) const {
  const Pair& pair = pairs_.at(i);
  StereoFrame frame;
  frame.index = i;
  frame.t_ns = pair.t_ns;
  const cv::Mat left = read_image(pair.left, left_topic_, left_compressed_);
  const cv::Mat right = read_image(pair.right, right_topic_, right_compressed_);
  calib_.rectify(left, right, frame.left, frame.right);
  return frame;
}

std::vector<OdometryRate> RosbagDataset::wheel_odometry() const {
  std::vector<OdometryRate> rates;
  rates.reserve(odometry_.size());
  // REP-105: the twist is in the child (base) frame, x forward, z up.
  for (const BagOdometrySample& s : odometry_) rates.push_back({s.t_ns, s.linear_mps.x(), s.angular_radps.z()});
  return rates;
}

}  // namespace agvslam::io
