#include "agvslam/daemon/daemon_config.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/features/features_config.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::daemon {
namespace {

namespace fs = std::filesystem;
using stereo::ParamsReader;

constexpr double kDegToRad = M_PI / 180.0;

std::string resolve(const fs::path& dir, const std::string& value) {
  if (value.empty()) return value;
  const fs::path p(value);
  return p.is_absolute() ? value : (dir / p).lexically_normal().string();
}

std::string fmt(const char* format, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, a);
  return buf;
}

const char* to_string(DynamicMode m) { return m == DynamicMode::kDetector ? "detector" : "off"; }
const char* to_string(MappingMode m) { return m == MappingMode::kThread ? "thread" : "inline"; }

void read_dds(const ParamsReader& in, const std::string& s, drivers::dds::DdsConfig& c, OutputsConfig* outputs) {
  if (outputs != nullptr) {
    in.check_keys(s, {"enabled", "wait_for_subscribers", "wait_timeout_s", "domain_id", "network_interface", "config_uri", "topic_namespace", "publish_pose",
                      "publish_odom", "publish_status", "map_frame_id", "odom_frame_id", "base_frame_id",
                      "history_depth", "max_blocking_ms", "queue_capacity"});
    in.read(s, "enabled", outputs->dds_enabled, "true or false");
    in.read(s, "wait_for_subscribers", outputs->dds_wait_for_subscribers, "an integer >= 0 (subscribers)");
    in.read(s, "wait_timeout_s", outputs->dds_wait_timeout_s, "seconds");
  } else {
    in.check_keys(s, {"domain_id", "network_interface", "config_uri", "topic_namespace", "publish_pose", "publish_odom",
                      "publish_status", "map_frame_id", "odom_frame_id", "base_frame_id", "history_depth",
                      "max_blocking_ms", "queue_capacity"});
  }
  in.read(s, "domain_id", c.domain_id, "an integer in 0..232 (ROS_DOMAIN_ID)");
  in.read(s, "network_interface", c.network_interface, "an interface name or address, e.g. eth0 or lo");
  in.read(s, "config_uri", c.config_uri, "Cyclone DDS XML or a file:// URI");
  in.read(s, "topic_namespace", c.topic_namespace, "a ROS namespace, e.g. agvslam");
  in.read(s, "publish_pose", c.publish_pose, "true or false");
  in.read(s, "publish_odom", c.publish_odom, "true or false");
  in.read(s, "publish_status", c.publish_status, "true or false");
  in.read(s, "map_frame_id", c.map_frame_id, "a frame name");
  in.read(s, "odom_frame_id", c.odom_frame_id, "a frame name");
  in.read(s, "base_frame_id", c.base_frame_id, "a frame name");
  in.read(s, "history_depth", c.history_depth, "an integer in 1..1000");
  in.read(s, "max_blocking_ms", c.max_blocking_ms, "an integer in 0..1000 (ms)");
  in.read(s, "queue_capacity", c.queue_capacity, "an integer in 1..1024");
  c.validate(in.path());
}

void read_can(const ParamsReader& in, const std::string& s, drivers::can::CanConfig& c, bool* enabled) {
  if (enabled != nullptr) {
    in.check_keys(s, {"enabled", "interface", "base_id", "extended_ids", "fd", "rate_hz", "send_velocity",
                      "send_stddev", "status_every", "reopen_min_ms", "reopen_max_ms"});
    in.read(s, "enabled", *enabled, "true or false");
  } else {
    in.check_keys(s, {"interface", "base_id", "extended_ids", "fd", "rate_hz", "send_velocity", "send_stddev",
                      "status_every", "reopen_min_ms", "reopen_max_ms"});
  }
  in.read(s, "interface", c.interface, "a SocketCAN interface name, e.g. can0");
  std::string id;
  in.read(s, "base_id", id, "a CAN id, e.g. 0x300");
  if (!id.empty()) {
    try {
      std::size_t used = 0;
      const unsigned long v = std::stoul(id, &used, 0);
      if (used != id.size() || v > 0x1FFFFFFFUL) throw std::invalid_argument(id);
      c.base_id = static_cast<uint32_t>(v);
    } catch (const std::exception&) {
      throw InputError(in.path(), s + ".base_id", "expected a CAN id such as 0x300 (got '" + id + "')");
    }
  }
  in.read(s, "extended_ids", c.extended_ids, "true or false");
  in.read(s, "fd", c.fd, "true or false");
  in.read(s, "rate_hz", c.rate_hz, "a rate in Hz (0: every pose)");
  in.read(s, "send_velocity", c.send_velocity, "true or false");
  in.read(s, "send_stddev", c.send_stddev, "true or false");
  in.read(s, "status_every", c.status_every, "an integer >= 1");
  in.read(s, "reopen_min_ms", c.reopen_min_ms, "an integer (ms)");
  in.read(s, "reopen_max_ms", c.reopen_max_ms, "an integer (ms)");
  c.validate(in.path());
}

}  // namespace

const char* to_string(SourceType type) { return type == SourceType::kV4l2 ? "v4l2" : "dataset"; }

SE3d BaseLinkConfig::T_base_cam() const {
  const Eigen::Matrix3d R_base_body = (Eigen::AngleAxisd(yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
                                       Eigen::AngleAxisd(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
                                       Eigen::AngleAxisd(roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                                          .toRotationMatrix();
  Eigen::Matrix3d R_body_cam = Eigen::Matrix3d::Identity();
  if (optical) {
    // Columns: the optical axes (x right, y down, z forward) in camera_link axes (x forward, y left, z up).
    R_body_cam << 0, 0, 1,  //
        -1, 0, 0,           //
        0, -1, 0;
  }
  return make_se3(Eigen::Matrix3d(R_base_body * R_body_cam), Eigen::Vector3d(x_m, y_m, z_m));
}

std::string BaseLinkConfig::describe() const {
  std::ostringstream s;
  s << "base_link: T_base_cam = camera at (" << x_m << ", " << y_m << ", " << z_m << ") m, roll " << roll_deg
    << " pitch " << pitch_deg << " yaw " << yaw_deg << " deg of its "
    << (optical ? "camera_link frame (x forward; optical frame z forward, x right, y down)" : "optical frame");
  return s.str();
}

std::string CovarianceConfig::describe() const {
  std::ostringstream s;
  s << "covariance (heuristic, the tracker gives none): sd position " << position_sd_m << " m, rotation "
    << rotation_sd_deg << " deg, velocity " << velocity_sd_mps << " m/s, angular " << angular_sd_degps
    << " deg/s at " << reference_inliers << " inliers, x sqrt(" << reference_inliers << " / max(inliers, "
    << min_inliers << "))";
  return s.str();
}

void DaemonConfig::validate() const {
  const std::string& p = path;
  if (source.type == SourceType::kDataset) {
    if (source.dataset.empty()) throw InputError(p, "source.dataset", "expected a dataset folder (source.type dataset)");
    if (!(source.rate >= 0) || source.rate > 1000) {
      throw InputError(p, "source.rate", "expected a speed factor in [0, 1000] (0: as fast as the pipeline goes)");
    }
    if (!(source.rate_hz >= 0) || source.rate_hz > 1000) {
      throw InputError(p, "source.rate_hz", "expected a rate in [0, 1000] Hz (0: use source.rate)");
    }
  } else {
    if (calibration_file.empty()) {
      throw InputError(p, "calibration.file", "expected a calibration file for the V4L2 camera (source.type v4l2)");
    }
    camera.validate(p);
  }
  const PipelineConfig& q = pipeline;
  if (q.capture_queue < 1 || q.capture_queue > 64) throw InputError(p, "pipeline.capture_queue", "expected an integer in 1..64");
  if (q.output_queue < 1 || q.output_queue > 1024) throw InputError(p, "pipeline.output_queue", "expected an integer in 1..1024");
  if (!(q.frame_rate_hz >= 0) || q.frame_rate_hz > 1000) {
    throw InputError(p, "pipeline.frame_rate_hz", "expected a rate in [0, 1000] Hz (0: the camera's or dataset's)");
  }
  if (q.opencv_threads < 1 || q.opencv_threads > 64) throw InputError(p, "pipeline.opencv_threads", "expected an integer in 1..64");
  if (q.heartbeat_ms < 10 || q.heartbeat_ms > 60000) throw InputError(p, "pipeline.heartbeat_ms", "expected an integer in 10..60000 (ms)");
  if (q.poll_ms < 1 || q.poll_ms > 5000) throw InputError(p, "pipeline.poll_ms", "expected an integer in 1..5000 (ms)");
  const BaseLinkConfig& b = base_link;
  for (const auto& [name, v] : {std::pair<const char*, double>{"base_link.x_m", b.x_m}, {"base_link.y_m", b.y_m},
                                {"base_link.z_m", b.z_m}}) {
    if (!std::isfinite(v) || std::abs(v) > 100) throw InputError(p, name, "expected a distance in [-100, 100] m");
  }
  for (const auto& [name, v] : {std::pair<const char*, double>{"base_link.roll_deg", b.roll_deg},
                                {"base_link.pitch_deg", b.pitch_deg}, {"base_link.yaw_deg", b.yaw_deg}}) {
    if (!std::isfinite(v) || std::abs(v) > 360) throw InputError(p, name, "expected an angle in [-360, 360] degrees");
  }
  const CovarianceConfig& c = covariance;
  for (const auto& [name, v] : {std::pair<const char*, double>{"covariance.position_sd_m", c.position_sd_m},
                                {"covariance.rotation_sd_deg", c.rotation_sd_deg},
                                {"covariance.velocity_sd_mps", c.velocity_sd_mps},
                                {"covariance.angular_sd_degps", c.angular_sd_degps}}) {
    if (!(v > 0) || !std::isfinite(v) || v > 1000) throw InputError(p, name, "expected a standard deviation > 0");
  }
  if (c.reference_inliers < 1) throw InputError(p, "covariance.reference_inliers", "expected an integer >= 1");
  if (c.min_inliers < 1) throw InputError(p, "covariance.min_inliers", "expected an integer >= 1");
  if (outputs.dds_enabled) outputs.dds.validate(p);
  if (outputs.dds_wait_for_subscribers < 0 || outputs.dds_wait_for_subscribers > 100) {
    throw InputError(p, "dds.wait_for_subscribers", "expected an integer in 0..100");
  }
  if (!(outputs.dds_wait_timeout_s > 0) || outputs.dds_wait_timeout_s > 3600) {
    throw InputError(p, "dds.wait_timeout_s", "expected seconds in (0, 3600]");
  }
  if (outputs.can_enabled) outputs.can.validate(p);
  if (trajectory.flush_every < 1) throw InputError(p, "trajectory.flush_every", "expected an integer >= 1 (poses)");
  if (!(log.stats_every_s >= 0)) throw InputError(p, "log.stats_every_s", "expected seconds >= 0 (0: only at stop)");
  if (!(systemd.ready_timeout_s > 0) || systemd.ready_timeout_s > 3600) {
    throw InputError(p, "systemd.ready_timeout_s", "expected seconds in (0, 3600]");
  }
  if (!map.file.empty()) {
    if (map.mode == slam::MapMode::kLocalisation && !fs::exists(map.file)) {
      throw InputError(p, "map.file", "expected an existing map file in mode localise (" + map.file + " does not exist)");
    }
    if (stage_files.place.empty()) {
      throw InputError(p, "stages.place", "expected the place params (vocabulary) when map.file is set: relocalising "
                                          "in a saved map needs the vocabulary it was saved with");
    }
  }
  // Two outputs writing one file would interleave.
  const std::vector<std::pair<const char*, std::string>> files = {
      {"trajectory.file", trajectory.file}, {"trajectory.final_file", trajectory.final_file},
      {"log.file", log.file}, {"log.pose_log", log.pose_log}, {"map.file", map.file}};
  for (std::size_t i = 0; i < files.size(); ++i) {
    for (std::size_t j = i + 1; j < files.size(); ++j) {
      if (!files[i].second.empty() && files[i].second == files[j].second) {
        throw InputError(p, files[j].first, std::string("expected a file other than ") + files[i].first + "'s");
      }
    }
  }
}

std::vector<std::string> DaemonConfig::describe() const {
  std::vector<std::string> out;
  std::ostringstream s;
  s << "source: " << to_string(source.type);
  if (source.type == SourceType::kDataset) {
    s << " " << source.dataset << ", "
      << (source.rate_hz > 0   ? fmt("%g Hz", source.rate_hz)
          : source.rate > 0    ? fmt("%g x its own rate", source.rate)
                               : std::string("as fast as the pipeline takes frames (none dropped)"))
      << (source.loop ? ", looped" : ", played once") << ", frames " << (source.frames.empty() ? "all" : source.frames);
  } else {
    s << ", " << (source.wait_for_camera ? "waits for a missing camera" : "exits when the camera cannot be opened");
  }
  out.push_back(s.str());
  if (source.type == SourceType::kV4l2) out.push_back(camera.describe());
  out.push_back("calibration: " + (calibration_file.empty() ? std::string("the dataset's own") : calibration_file));
  auto file_or_default = [](const std::string& f) { return f.empty() ? std::string("(built-in defaults)") : f; };
  out.push_back("stages: features " + file_or_default(stage_files.features) + ", slam " + file_or_default(stage_files.slam) +
                ", dynamic " + file_or_default(stage_files.dynamic) + ", stereo " + file_or_default(stage_files.stereo) +
                ", place " + (stage_files.place.empty() ? std::string("(none: no relocalisation by place recognition, no loop closing)")
                                                         : stage_files.place));
  if (place) {
    out.push_back("place: vocabulary " + place->vocabulary_file + ", direct index level " +
                  std::to_string(place->direct_index_level));
  }
  out.push_back(map.describe());
  std::ostringstream q;
  q << "pipeline: dynamic " << to_string(pipeline.dynamic) << ", mapping " << to_string(pipeline.mapping)
    << ", capture queue " << pipeline.capture_queue
    << (source.type == SourceType::kDataset && source.rate == 0 && source.rate_hz == 0 ? " (lossless: dataset at rate 0)"
                                                                                       : " (newest wins)")
    << ", output queue " << pipeline.output_queue
    << ", SLAM frame rate " << (pipeline.frame_rate_hz > 0 ? fmt("%g Hz", pipeline.frame_rate_hz) : std::string("from the source"))
    << ", OpenCV threads " << pipeline.opencv_threads << ", heartbeat " << pipeline.heartbeat_ms << " ms, poll "
    << pipeline.poll_ms << " ms";
  out.push_back(q.str());
  out.push_back(base_link.describe());
  out.push_back(covariance.describe());
  out.push_back(outputs.dds_enabled ? outputs.dds.describe() : std::string("dds: disabled"));
  if (outputs.dds_enabled && outputs.dds_wait_for_subscribers > 0) {
    out.push_back("dds: the first frame waits for " + std::to_string(outputs.dds_wait_for_subscribers) +
                  " subscriber(s) on every topic, at most " + fmt("%g s", outputs.dds_wait_timeout_s));
  }
  out.push_back(outputs.can_enabled ? outputs.can.describe() : std::string("can: disabled"));
  out.push_back("trajectory: " + (trajectory.file.empty() ? std::string("-") : trajectory.file) + " (" +
                (trajectory.frame == TrajectoryFrame::kBaseLink ? "T_map_base" : "T_w_c camera") + ", TUM, flush every " +
                std::to_string(trajectory.flush_every) + "), final " +
                (trajectory.final_file.empty() ? std::string("-") : trajectory.final_file));
  out.push_back("log: level " + log.level + ", file " + (log.file.empty() ? std::string("- (stderr only)") : log.file) +
                ", pose log " + (log.pose_log.empty() ? std::string("-") : log.pose_log) + ", statistics every " +
                fmt("%g s", log.stats_every_s));
  out.push_back(std::string("systemd: READY=1 ") +
                (systemd.ready == ReadyWhen::kFirstFrame ? "after the first processed frame, or " +
                                                               fmt("%g s", systemd.ready_timeout_s) + " without one"
                                                         : std::string("once the outputs are open")));
  features::FeaturesConfig f;
  f.orb = system.orb;
  f.stereo_matching = system.stereo;
  for (const auto& line : f.describe()) out.push_back("  " + line);
  for (const auto& line : system.slam.describe()) out.push_back("  " + line);
  if (pipeline.dynamic == DynamicMode::kDetector) {
    for (const auto& line : detector.describe()) out.push_back("  " + line);
    for (const auto& line : stereo.describe()) out.push_back("  " + line);
  }
  return out;
}

std::string MapConfig::describe() const {
  if (file.empty()) return "map: none (an empty map at every start, nothing saved)";
  return "map: " + file + ", mode " + slam::to_string(mode) +
         (mode == slam::MapMode::kLocalisation
              ? std::string(" (the file must exist; tracked in without changing it; nothing saved)")
              : std::string(" (loaded when it exists, else built; ") +
                    (save_on_stop ? "saved atomically at stop)" : "not saved: map.save_on_stop false)"));
}

drivers::dds::DdsConfig load_dds_config(const std::string& path, const std::string& section) {
  const ParamsReader in(path);
  drivers::dds::DdsConfig c;
  read_dds(in, section, c, nullptr);
  return c;
}

drivers::can::CanConfig load_can_config(const std::string& path, const std::string& section) {
  const ParamsReader in(path);
  drivers::can::CanConfig c;
  read_can(in, section, c, nullptr);
  return c;
}

DaemonConfig load_daemon_config(const std::string& path) {
  const ParamsReader in(path);
  const fs::path dir = fs::absolute(fs::path(path)).parent_path();
  in.check_sections({"source", "camera", "calibration", "stages", "pipeline", "base_link", "covariance", "dds", "can",
                     "trajectory", "log", "systemd", "map"});
  DaemonConfig c;
  c.path = path;

  in.check_keys("source", {"type", "dataset", "rate", "rate_hz", "loop", "frames", "wait_for_camera"});
  std::string type = to_string(c.source.type);
  in.read("source", "type", type, "v4l2 or dataset");
  if (type == "v4l2") {
    c.source.type = SourceType::kV4l2;
  } else if (type == "dataset") {
    c.source.type = SourceType::kDataset;
  } else {
    throw InputError(path, "source.type", "expected v4l2 or dataset (got '" + type + "')");
  }
  in.read("source", "dataset", c.source.dataset, "a dataset folder");
  c.source.dataset = resolve(dir, c.source.dataset);
  in.read("source", "rate", c.source.rate, "a speed factor (1: the dataset's rate, 0: as fast as possible)");
  in.read("source", "rate_hz", c.source.rate_hz, "a rate in Hz (0: use source.rate)");
  in.read("source", "loop", c.source.loop, "true or false");
  in.read("source", "frames", c.source.frames, "an inclusive frame range A:B");
  in.read("source", "wait_for_camera", c.source.wait_for_camera, "true or false");

  if (c.source.type == SourceType::kV4l2) c.camera = drivers::v4l2::load_v4l2_camera_config(path, "camera");

  in.check_keys("calibration", {"file"});
  in.read("calibration", "file", c.calibration_file, "a calibration file (KITTI calib.txt, ORB-SLAM YAML, Kalibr)");
  c.calibration_file = resolve(dir, c.calibration_file);

  in.check_keys("stages", {"features", "slam", "dynamic", "stereo", "place"});
  in.read("stages", "features", c.stage_files.features, "a params file (params/features.yaml)");
  in.read("stages", "slam", c.stage_files.slam, "a params file (params/slam.yaml)");
  in.read("stages", "dynamic", c.stage_files.dynamic, "a params file (params/dynamic.yaml)");
  in.read("stages", "stereo", c.stage_files.stereo, "a params file (params/stereo.yaml)");
  in.read("stages", "place", c.stage_files.place, "a params file (params/place.yaml: the vocabulary)");
  for (std::string* f : {&c.stage_files.features, &c.stage_files.slam, &c.stage_files.dynamic, &c.stage_files.stereo,
                         &c.stage_files.place}) {
    *f = resolve(dir, *f);
  }

  in.check_keys("pipeline", {"dynamic", "mapping", "capture_queue", "output_queue", "frame_rate_hz", "opencv_threads",
                             "heartbeat_ms", "poll_ms"});
  std::string dynamic = "detector", mapping = "thread";
  in.read("pipeline", "dynamic", dynamic, "detector or off");
  if (dynamic == "detector") {
    c.pipeline.dynamic = DynamicMode::kDetector;
  } else if (dynamic == "off") {
    c.pipeline.dynamic = DynamicMode::kOff;
  } else {
    throw InputError(path, "pipeline.dynamic", "expected detector or off (got '" + dynamic + "')");
  }
  in.read("pipeline", "mapping", mapping, "thread or inline");
  if (mapping == "thread") {
    c.pipeline.mapping = MappingMode::kThread;
  } else if (mapping == "inline") {
    c.pipeline.mapping = MappingMode::kInline;
  } else {
    throw InputError(path, "pipeline.mapping", "expected thread or inline (got '" + mapping + "')");
  }
  in.read("pipeline", "capture_queue", c.pipeline.capture_queue, "an integer in 1..64 (frames)");
  in.read("pipeline", "output_queue", c.pipeline.output_queue, "an integer in 1..1024 (samples)");
  in.read("pipeline", "frame_rate_hz", c.pipeline.frame_rate_hz, "a rate in Hz (0: from the source)");
  in.read("pipeline", "opencv_threads", c.pipeline.opencv_threads, "an integer in 1..64");
  in.read("pipeline", "heartbeat_ms", c.pipeline.heartbeat_ms, "an integer (ms)");
  in.read("pipeline", "poll_ms", c.pipeline.poll_ms, "an integer (ms)");

  in.check_keys("base_link", {"x_m", "y_m", "z_m", "roll_deg", "pitch_deg", "yaw_deg", "optical"});
  in.read("base_link", "x_m", c.base_link.x_m, "a distance (m)");
  in.read("base_link", "y_m", c.base_link.y_m, "a distance (m)");
  in.read("base_link", "z_m", c.base_link.z_m, "a distance (m)");
  in.read("base_link", "roll_deg", c.base_link.roll_deg, "an angle (degrees)");
  in.read("base_link", "pitch_deg", c.base_link.pitch_deg, "an angle (degrees)");
  in.read("base_link", "yaw_deg", c.base_link.yaw_deg, "an angle (degrees)");
  in.read("base_link", "optical", c.base_link.optical, "true or false");

  in.check_keys("covariance", {"position_sd_m", "rotation_sd_deg", "velocity_sd_mps", "angular_sd_degps",
                               "reference_inliers", "min_inliers"});
  in.read("covariance", "position_sd_m", c.covariance.position_sd_m, "a standard deviation (m)");
  in.read("covariance", "rotation_sd_deg", c.covariance.rotation_sd_deg, "a standard deviation (degrees)");
  in.read("covariance", "velocity_sd_mps", c.covariance.velocity_sd_mps, "a standard deviation (m/s)");
  in.read("covariance", "angular_sd_degps", c.covariance.angular_sd_degps, "a standard deviation (degrees/s)");
  in.read("covariance", "reference_inliers", c.covariance.reference_inliers, "an integer >= 1");
  in.read("covariance", "min_inliers", c.covariance.min_inliers, "an integer >= 1");

  read_dds(in, "dds", c.outputs.dds, &c.outputs);
  read_can(in, "can", c.outputs.can, &c.outputs.can_enabled);

  in.check_keys("trajectory", {"file", "frame", "flush_every", "final_file"});
  in.read("trajectory", "file", c.trajectory.file, "a file name (TUM)");
  c.trajectory.file = resolve(dir, c.trajectory.file);
  std::string frame = "base_link";
  in.read("trajectory", "frame", frame, "base_link or camera");
  if (frame == "base_link") {
    c.trajectory.frame = TrajectoryFrame::kBaseLink;
  } else if (frame == "camera") {
    c.trajectory.frame = TrajectoryFrame::kCamera;
  } else {
    throw InputError(path, "trajectory.frame", "expected base_link or camera (got '" + frame + "')");
  }
  in.read("trajectory", "flush_every", c.trajectory.flush_every, "an integer >= 1 (poses)");
  in.read("trajectory", "final_file", c.trajectory.final_file, "a file name (TUM)");
  c.trajectory.final_file = resolve(dir, c.trajectory.final_file);

  in.check_keys("log", {"file", "level", "pose_log", "stats_every_s"});
  in.read("log", "file", c.log.file, "a file name");
  c.log.file = resolve(dir, c.log.file);
  in.read("log", "level", c.log.level, "trace, debug, info, warn or error");
  if (c.log.level != "trace" && c.log.level != "debug" && c.log.level != "info" && c.log.level != "warn" &&
      c.log.level != "error") {
    throw InputError(path, "log.level", "expected trace, debug, info, warn or error (got '" + c.log.level + "')");
  }
  in.read("log", "pose_log", c.log.pose_log, "a file name (JSON lines)");
  c.log.pose_log = resolve(dir, c.log.pose_log);
  in.read("log", "stats_every_s", c.log.stats_every_s, "seconds (0: only at stop)");

  in.check_keys("systemd", {"ready", "ready_timeout_s"});
  std::string ready = "first_frame";
  in.read("systemd", "ready", ready, "first_frame or startup");
  if (ready == "first_frame") {
    c.systemd.ready = ReadyWhen::kFirstFrame;
  } else if (ready == "startup") {
    c.systemd.ready = ReadyWhen::kStartup;
  } else {
    throw InputError(path, "systemd.ready", "expected first_frame or startup (got '" + ready + "')");
  }
  in.read("systemd", "ready_timeout_s", c.systemd.ready_timeout_s, "seconds");

  in.check_keys("map", {"file", "mode", "save_on_stop"});
  in.read("map", "file", c.map.file, "a map file name");
  c.map.file = resolve(dir, c.map.file);
  std::string map_mode = "map";
  in.read("map", "mode", map_mode, "localise or map");
  if (map_mode == "map" || map_mode == "mapping") {
    c.map.mode = slam::MapMode::kMapping;
  } else if (map_mode == "localise" || map_mode == "localisation" || map_mode == "localize" || map_mode == "localization") {
    c.map.mode = slam::MapMode::kLocalisation;
  } else {
    throw InputError(path, "map.mode", "expected localise (track in the saved map without changing it) or map (extend "
                                       "it) (got '" + map_mode + "')");
  }
  in.read("map", "save_on_stop", c.map.save_on_stop, "true or false");

  c.validate();

  // The stage files (their own errors name them and their fields).
  if (!c.stage_files.slam.empty()) c.system.slam = slam::load_slam_config(c.stage_files.slam);
  if (!c.stage_files.features.empty()) {
    const features::FeaturesConfig f = features::load_features_config(c.stage_files.features);
    c.system.orb = f.orb;
    c.system.stereo = f.stereo_matching;
  }
  c.system.threaded_mapping = c.pipeline.mapping == MappingMode::kThread;
  if (!c.stage_files.place.empty()) {
    c.place = place::load_place_config(c.stage_files.place);
    if (!fs::is_regular_file(c.place->vocabulary_file)) {
      throw InputError(c.stage_files.place, "vocabulary.file", "expected an existing vocabulary file (" +
                                                                  c.place->vocabulary_file + " does not exist)");
    }
    c.system.direct_index_level = c.place->direct_index_level;
  }
  if (c.pipeline.dynamic == DynamicMode::kDetector) {
    if (!c.stage_files.dynamic.empty()) c.detector = dynamic::load_dynamic_config(c.stage_files.dynamic);
    if (!c.stage_files.stereo.empty()) c.stereo = stereo::load_stereo_config(c.stage_files.stereo);
  }
  return c;
}

}  // namespace agvslam::daemon
