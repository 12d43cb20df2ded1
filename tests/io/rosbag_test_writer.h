#pragma once
// Test-side writer of rosbag2 recordings in the layout `ros2 bag record` produces with the sqlite3 storage
// (Humble, schema 3): BAG/metadata.yaml + BAG/<name>_0.db3 with the tables schema, metadata (empty), topics(id,
// name, type, serialization_format, offered_qos_profiles) and messages(id, topic_id, timestamp, data), data
// CDR-serialised. Its own encoder, kept
// apart from the reader under test so that a shared mistake cannot hide.

#include <sqlite3.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "agvslam/io/dataset.h"

namespace agvslam::test {

// XCDR1 with the 4-byte encapsulation header; alignment counts from the end of that header.
class CdrWriter {
 public:
  explicit CdrWriter(bool big_endian = false) : big_endian_(big_endian) {
    bytes_ = {0, static_cast<uint8_t>(big_endian ? 0 : 1), 0, 0};
  }
  void u8(uint8_t v) { bytes_.push_back(v); }
  void u32(uint32_t v) { put(&v, 4); }
  void i32(int32_t v) { put(&v, 4); }
  void f64(double v) { put(&v, 8); }
  void string(const std::string& s) {
    u32(static_cast<uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
  }
  void bytes(const uint8_t* data, std::size_t n) {
    u32(static_cast<uint32_t>(n));
    bytes_.insert(bytes_.end(), data, data + n);
  }
  void f64s(const std::vector<double>& values, bool with_count) {
    if (with_count) u32(static_cast<uint32_t>(values.size()));
    for (double v : values) f64(v);
  }
  void header(int64_t t_ns, const std::string& frame_id) {
    i32(static_cast<int32_t>(t_ns / 1'000'000'000));
    u32(static_cast<uint32_t>(t_ns % 1'000'000'000));
    string(frame_id);
  }
  const std::vector<uint8_t>& data() const { return bytes_; }

 private:
  void put(const void* v, std::size_t n) {
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
    uint8_t raw[8];
    std::memcpy(raw, v, n);
    const uint16_t probe = 1;
    const bool host_big = *reinterpret_cast<const uint8_t*>(&probe) == 0;
    if (host_big != big_endian_) {
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(raw[i], raw[n - 1 - i]);
    }
    bytes_.insert(bytes_.end(), raw, raw + n);
  }
  bool big_endian_;
  std::vector<uint8_t> bytes_;
};

// sensor_msgs/msg/Image of a CV_8UC1 (mono8), CV_8UC3 (bgr8 / rgb8) or CV_16UC1 (mono16) image.
inline std::vector<uint8_t> encode_image(int64_t t_ns, const cv::Mat& image, const std::string& encoding,
                                         bool big_endian = false) {
  CdrWriter w(big_endian);
  w.header(t_ns, "camera");
  w.u32(static_cast<uint32_t>(image.rows));
  w.u32(static_cast<uint32_t>(image.cols));
  w.string(encoding);
  w.u8(big_endian ? 1 : 0);
  const std::size_t step = image.cols * image.elemSize();
  w.u32(static_cast<uint32_t>(step));
  std::vector<uint8_t> pixels(step * image.rows);
  for (int y = 0; y < image.rows; ++y) std::memcpy(pixels.data() + y * step, image.ptr(y), step);
  if (image.elemSize1() == 2 && big_endian) {
    for (std::size_t i = 0; i + 1 < pixels.size(); i += 2) std::swap(pixels[i], pixels[i + 1]);
  }
  w.bytes(pixels.data(), pixels.size());
  return w.data();
}

// sensor_msgs/msg/CompressedImage, PNG.
inline std::vector<uint8_t> encode_png_image(int64_t t_ns, const cv::Mat& image, bool big_endian = false) {
  std::vector<uint8_t> png;
  cv::imencode(".png", image, png);
  CdrWriter w(big_endian);
  w.header(t_ns, "camera");
  w.string("png");
  w.bytes(png.data(), png.size());
  return w.data();
}

// sensor_msgs/msg/CameraInfo.
inline std::vector<uint8_t> encode_camera_info(int64_t t_ns, int width, int height, const std::vector<double>& d,
                                               const std::vector<double>& k, const std::vector<double>& r,
                                               const std::vector<double>& p, bool big_endian = false) {
  CdrWriter w(big_endian);
  w.header(t_ns, "camera");
  w.u32(static_cast<uint32_t>(height));
  w.u32(static_cast<uint32_t>(width));
  w.string("plumb_bob");
  w.f64s(d, true);
  w.f64s(k, false);
  w.f64s(r, false);
  w.f64s(p, false);
  w.u32(0);                              // binning_x
  w.u32(0);                              // binning_y
  for (int i = 0; i < 4; ++i) w.u32(0);  // roi x_offset, y_offset, height, width
  w.u8(0);                               // roi do_rectify
  return w.data();
}

// nav_msgs/msg/Odometry: position, orientation (x y z w), linear and angular velocity.
struct OdometryValues {
  int64_t t_ns = 0;
  double position[3] = {0, 0, 0};
  double orientation_xyzw[4] = {0, 0, 0, 1};
  double linear[3] = {0, 0, 0};
  double angular[3] = {0, 0, 0};
};
inline std::vector<uint8_t> encode_odometry(const OdometryValues& o) {
  CdrWriter w;
  w.header(o.t_ns, "odom");
  w.string("base_link");
  for (double v : o.position) w.f64(v);
  for (double v : o.orientation_xyzw) w.f64(v);
  for (int i = 0; i < 36; ++i) w.f64(0.01 * i);  // pose covariance
  for (double v : o.linear) w.f64(v);
  for (double v : o.angular) w.f64(v);
  for (int i = 0; i < 36; ++i) w.f64(0.0);  // twist covariance
  return w.data();
}

class BagWriter {
 public:
  // Creates dir/ and dir/<stem>_0.db3.
  explicit BagWriter(const std::string& dir, const std::string& stem = "recording") : dir_(dir) {
    std::filesystem::create_directories(dir);
    db_name_ = stem + "_0.db3";
    if (sqlite3_open((std::filesystem::path(dir) / db_name_).string().c_str(), &db_) != SQLITE_OK)
      throw std::runtime_error("cannot create the test bag");
    exec(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "INSERT INTO schema VALUES (3, 'humble');"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
        "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, "
        "data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
        "BEGIN;");
  }
  ~BagWriter() {
    if (db_) finish();
  }
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  int topic(const std::string& name, const std::string& type) {
    topics_.push_back({name, type, 0});
    const int id = static_cast<int>(topics_.size());
    exec("INSERT INTO topics VALUES (" + std::to_string(id) + ", '" + name + "', '" + type + "', 'cdr', '');");
    return id;
  }
  // recorded_ns: the recording time (messages.timestamp).
  void write(int topic_id, int64_t recorded_ns, const std::vector<uint8_t>& data) {
    sqlite3_stmt* stmt = nullptr;
    sqlite3_prepare_v2(db_, "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)", -1, &stmt, nullptr);
    sqlite3_bind_int(stmt, 1, topic_id);
    sqlite3_bind_int64(stmt, 2, recorded_ns);
    sqlite3_bind_blob(stmt, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
    if (sqlite3_step(stmt) != SQLITE_DONE) throw std::runtime_error("cannot write a test bag message");
    sqlite3_finalize(stmt);
    ++topics_.at(static_cast<std::size_t>(topic_id - 1)).count;
    ++message_count_;
    first_ns_ = std::min(first_ns_, recorded_ns);
    last_ns_ = std::max(last_ns_, recorded_ns);
  }
  // Commits, closes the .db3 and writes metadata.yaml as rosbag2 (version 5) does.
  void finish() {
    exec("COMMIT;");
    sqlite3_close(db_);
    db_ = nullptr;
    const int64_t start = message_count_ ? first_ns_ : 0, duration = message_count_ ? last_ns_ - first_ns_ : 0;
    std::ofstream out(std::filesystem::path(dir_) / "metadata.yaml");
    out << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  duration:\n"
        << "    nanoseconds: " << duration << "\n  starting_time:\n    nanoseconds_since_epoch: " << start
        << "\n  message_count: " << message_count_ << "\n  topics_with_message_count:\n";
    for (const Topic& t : topics_) {
      out << "    - topic_metadata:\n        name: " << t.name << "\n        type: " << t.type
          << "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: " << t.count
          << "\n";
    }
    out << "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - " << db_name_
        << "\n  files:\n    - path: " << db_name_
        << "\n      starting_time:\n        nanoseconds_since_epoch: " << start
        << "\n      duration:\n        nanoseconds: " << duration << "\n      message_count: " << message_count_
        << "\n";
  }
  const std::string& db_name() const { return db_name_; }

 private:
  struct Topic {
    std::string name, type;
    std::size_t count;
  };
  void exec(const std::string& sql) {
    char* error = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
      const std::string message = error ? error : "?";
      sqlite3_free(error);
      throw std::runtime_error("test bag: " + message);
    }
  }
  std::string dir_, db_name_;
  sqlite3* db_ = nullptr;
  std::vector<Topic> topics_;
  std::size_t message_count_ = 0;
  int64_t first_ns_ = INT64_MAX, last_ns_ = INT64_MIN;
};

// A rectified stereo pair's camera_info P matrices: P_left = [K 0], P_right = [K -fx*baseline].
inline std::vector<double> rectified_p(double fx, double fy, double cx, double cy, double tx) {
  return {fx, 0, cx, tx, 0, fy, cy, 0, 0, 0, 1, 0};
}

// Cuts the data of one message of topic_id (the `nth` by messages.timestamp, ascending or descending) to its first
// `bytes` bytes, as a recording cut short would leave it. False when sqlite refuses.
inline bool truncate_message(const std::string& db_path, int topic_id, int nth, bool descending, int bytes) {
  sqlite3* db = nullptr;
  if (sqlite3_open(db_path.c_str(), &db) != SQLITE_OK) return false;
  const std::string sql = "UPDATE messages SET data = substr(data, 1, " + std::to_string(bytes) +
                          ") WHERE id = (SELECT id FROM messages WHERE topic_id = " + std::to_string(topic_id) +
                          " ORDER BY timestamp " + (descending ? "DESC" : "ASC") + " LIMIT 1 OFFSET " +
                          std::to_string(nth) + ")";
  const bool ok = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) == SQLITE_OK && sqlite3_changes(db) == 1;
  sqlite3_close(db);
  return ok;
}

// The first `frames` frames of a KITTI-layout dataset as a bag: left sensor_msgs/Image mono8, right
// CompressedImage png (stamped with the dataset's times, recorded 3 ms later), camera_info on both sides from its
// rectified calibration, and the given odometry messages on /odom.
inline void write_kitti_bag(const io::KittiDataset& kitti, std::size_t frames, const std::string& bag_dir,
                            const std::vector<OdometryValues>& odometry = {}) {
  BagWriter bag(bag_dir);
  const int left = bag.topic("/kitti/camera_gray_left/image_raw", "sensor_msgs/msg/Image");
  const int right = bag.topic("/kitti/camera_gray_right/image_raw/compressed", "sensor_msgs/msg/CompressedImage");
  const int left_info = bag.topic("/kitti/camera_gray_left/camera_info", "sensor_msgs/msg/CameraInfo");
  const int right_info = bag.topic("/kitti/camera_gray_right/camera_info", "sensor_msgs/msg/CameraInfo");
  const StereoCalibration& calib = kitti.calibration();
  const std::vector<double> K = {calib.left.fx, 0, calib.left.cx, 0, calib.left.fy, calib.left.cy, 0, 0, 1};
  const std::vector<double> R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const PinholeCamera& c = calib.left;
  for (std::size_t i = 0; i < frames; ++i) {
    const int64_t t = kitti.timestamp_ns(i), recorded = t + 3'000'000;
    bag.write(left, recorded, encode_image(t, cv::imread(kitti.left_path(i), cv::IMREAD_GRAYSCALE), "mono8"));
    bag.write(right, recorded, encode_png_image(t, cv::imread(kitti.right_path(i), cv::IMREAD_GRAYSCALE)));
    bag.write(left_info, recorded,
              encode_camera_info(t, c.width, c.height, {0, 0, 0, 0, 0}, K, R, rectified_p(c.fx, c.fy, c.cx, c.cy, 0)));
    bag.write(right_info, recorded,
              encode_camera_info(t, c.width, c.height, {0, 0, 0, 0, 0}, K, R,
                                 rectified_p(c.fx, c.fy, c.cx, c.cy, -c.fx * calib.baseline_m)));
  }
  if (!odometry.empty()) {
    const int odom = bag.topic("/odom", "nav_msgs/msg/Odometry");
    for (const OdometryValues& o : odometry) bag.write(odom, o.t_ns, encode_odometry(o));
  }
}

}  // namespace agvslam::test
