#pragma once
// agvslamd's configuration: one YAML file (params/agvslamd.yaml) with these sections, every key optional unless
// said otherwise (defaults below), relative paths relative to the folder of the file:
//
//   source       type v4l2 | dataset; dataset folder, playback rate, loop, frame range; wait for a camera
//   camera       the V4L2 stereo camera (the keys of params/camera_v4l2.yaml's `camera` section)
//   calibration  file: any format agvslam::io reads (KITTI calib.txt, ORB-SLAM YAML, Kalibr camchain)
//   stages       the params files of the other stages: features, slam, dynamic, stereo, place (the vocabulary;
//                "" = built-in defaults, place "" = no vocabulary: no relocalisation by place recognition, no loops)
//   pipeline     dynamic detector | off, mapping thread | inline, queue size, SLAM frame rate, heartbeat
//   base_link    camera-to-base_link extrinsic T_base_cam (x, y, z, roll, pitch, yaw of the camera)
//   covariance   the documented heuristic for the pose and twist covariance (the tracker gives none)
//   dds / can    the outputs (drivers::dds::DdsConfig / drivers::can::CanConfig keys plus `enabled`)
//   odometry     wheel odometry in (none | can) and the live check against it (OdometryMonitorConfig keys)
//   can_odometry the odometry message on the CAN bus (drivers::can::CanOdometryConfig keys; read with source can)
//   trajectory   the published poses as a TUM file, and the keyframe-refined trajectory at stop
//   log          log file (reopened on SIGHUP), level, per-sample JSON log, statistics period
//   systemd      when READY=1 is sent
//   map          the saved map: file, mode (localise | map), what to do when the file does not exist yet, save at stop
//
// load_daemon_config() reads the file and every file it names (stage params, calibration, the dataset's index)
// and validates everything: a bad value is an InputError naming the file, the field ("source.rate") and what was
// expected, before anything is opened or started. Each section's keys, ranges, units and echo are one table in
// src/daemon/daemon_config.cpp (camera, dds and can: the drivers' tables).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/daemon/odometry_monitor.h"
#include "agvslam/drivers/can/can_config.h"
#include "agvslam/drivers/can/odometry_input.h"
#include "agvslam/drivers/dds/dds_config.h"
#include "agvslam/drivers/v4l2/camera_config.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/place/place_config.h"
#include "agvslam/semantic/semantic_config.h"
#include "agvslam/slam/system.h"
#include "agvslam/stereo/stereo_config.h"

namespace agvslam::daemon {

enum class SourceType { kV4l2, kDataset };
const char* to_string(SourceType type);

struct SourceConfig {
  SourceType type = SourceType::kV4l2;
  // dataset: any folder agvslam::io reads (KITTI layout, agvslam-sim output, EuRoC ASL).
  std::string dataset;
  // dataset: playback speed as a multiple of the dataset's own rate (1 = real time); 0 = as fast as the pipeline
  // takes frames, none dropped (the capture queue then waits instead of dropping).
  double rate = 1.0;
  // dataset: a fixed playback rate in Hz instead of `rate` (0 = use `rate`).
  double rate_hz = 0.0;
  bool loop = false;   // dataset: start again at the first frame after the last (else: stop at the end)
  std::string frames;  // dataset: inclusive frame range "A:B" (either side may be empty); "" = all
  // v4l2: a camera that cannot be opened at start is retried with back-off (the daemon runs and reports its
  // state meanwhile); false: exit 1 with the device's error.
  bool wait_for_camera = true;
};

struct StageFiles {
  std::string features, slam, dynamic, stereo;  // resolved paths; "" = built-in defaults
  std::string place;                            // resolved; "" = no vocabulary (no place recognition)
  std::string semantic;                         // resolved; "" = no semantic stage (geometry alone)
};

// The saved map (slam::System::save_map / load_map; file format in agvslam/slam/map_io.h).
struct MapConfig {
  // "" = no map file: start with an empty map every time, save nothing.
  std::string file;
  // localise: track in the loaded map without changing it (the file must exist); map: extend it (or build one
  // when the file does not exist yet) and save it at stop.
  slam::MapMode mode = slam::MapMode::kMapping;
  // At stop (SIGTERM / SIGINT / end of a dataset), in mapping mode: write the map atomically (temporary file,
  // fsync, rename): a crash or power cut during the save leaves the previous file intact.
  bool save_on_stop = true;
  // A map file that exists but cannot be loaded (corrupt, truncated, another version, vocabulary or camera) stops
  // the daemon at start-up (exit 2) and is never overwritten; this is always so, there is no setting to ignore it.
  std::string describe() const;
};

// Where the daemon may write (section `files`): every file it writes (map, trajectories, log, pose log) must lie,
// after symbolic links and ".." are resolved, inside one of these folders, or the configuration is refused; so a
// changed or injected configuration cannot make the service overwrite files elsewhere on the vehicle.
struct FilesConfig {
  // "env": the folders systemd gives the service ($STATE_DIRECTORY and $LOGS_DIRECTORY, ':'-separated lists; when
  // neither is set, as in a developer's run, writes are not confined); "": not confined; otherwise folders
  // separated by ':' (relative ones against the file's folder).
  std::string write_dirs = "env";
  std::vector<std::string> write_roots;  // set at load: the folders above, canonical; empty = not confined
};

enum class DynamicMode { kDetector, kOff };
enum class MappingMode { kThread, kInline };

struct PipelineConfig {
  DynamicMode dynamic = DynamicMode::kDetector;
  MappingMode mapping = MappingMode::kThread;
  // Frames waiting between capture and processing; when full the oldest is dropped and counted (newest wins).
  int capture_queue = 2;
  // Samples waiting between tracking and the outputs thread (newest wins as well).
  int output_queue = 8;
  // The camera rate the SLAM assumes (keyframe spacing counts frames); 0 = camera.fps or the dataset's rate.
  double frame_rate_hz = 0.0;
  int opencv_threads = 1;  // OpenCV's threads inside a stage (1: one core per pipeline thread)
  // While no frame is processed for this long, a status sample (state lost) goes out every heartbeat_ms.
  int heartbeat_ms = 500;
  // Grab / pop time-outs of the loops (ms): how often a waiting thread checks for stop and proves it is alive.
  int poll_ms = 100;
};

// T_base_cam: the (raw) left camera in base_link (REP-103: x forward, y left, z up), given as the position and
// roll/pitch/yaw (degrees, applied z-y'-x'') of the camera's body frame. With `optical` (default) that body frame
// is the ROS camera_link convention (x along the optical axis, y left, z up) and the optical frame the SLAM uses
// (z forward, x right, y down) is rotated from it; without, the angles give the optical frame directly.
struct BaseLinkConfig {
  double x_m = 0, y_m = 0, z_m = 0;
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
  bool optical = true;
  SE3d T_base_cam() const;
  std::string describe() const;
};

// The tracker reports no covariance yet. Heuristic: standard deviations scale with sqrt(reference_inliers /
// inliers) (a pose from half the inliers is sqrt(2) less certain), floored at min_inliers; diagonal matrices.
struct CovarianceConfig {
  double position_sd_m = 0.02;    // per axis, at reference_inliers
  double rotation_sd_deg = 0.5;   // per axis
  double velocity_sd_mps = 0.05;  // per axis of the finite-difference twist
  double angular_sd_degps = 2.0;
  int reference_inliers = 200;
  int min_inliers = 10;
  std::string describe() const;
};

struct OutputsConfig {
  bool dds_enabled = true;
  drivers::dds::DdsConfig dds;
  // Before the first frame is captured, wait until every DDS topic has this many matched subscribers, at most
  // dds_wait_timeout_s (tests and benchmarks that must see every sample; 0 = do not wait, the vehicle default).
  int dds_wait_for_subscribers = 0;
  double dds_wait_timeout_s = 10;
  bool can_enabled = false;
  drivers::can::CanConfig can;
};

// Where wheel odometry comes from: none (no check, the outputs as without it) or the vehicle's odometry frames on
// the CAN output's interface (section can_odometry).
enum class OdometrySource { kNone, kCan };

struct OdometryConfig {
  OdometrySource source = OdometrySource::kNone;
  OdometryMonitorConfig check;
  drivers::can::CanOdometryConfig can;  // section can_odometry
};

enum class TrajectoryFrame { kBaseLink, kCamera };

struct TrajectoryConfig {
  // TUM file with the pose of every published sample (capture time stamps), written as the daemon runs (flushed
  // every flush_every poses and at stop). "" = none.
  std::string file;
  TrajectoryFrame frame = TrajectoryFrame::kBaseLink;  // base_link: T_map_base; camera: T_w_c of the SLAM
  int flush_every = 20;
  // At stop: the keyframe-refined trajectory of the left camera (TUM, T_w_c, the SLAM's own frame), as
  // agvslam-run --out writes it. "" = none.
  std::string final_file;
};

struct LogConfig {
  std::string file;            // also log to this file (appended; reopened on SIGHUP for logrotate). "" = stderr only
  std::string level = "info";  // trace, debug, info, warn, error
  // One JSON line per sample handed to the outputs (the sample's SI values, the source frame, what CAN did);
  // the format agvslam-pose-replay --json writes, so can_log_check reads it. "" = none.
  std::string pose_log;
  double stats_every_s = 10;  // a statistics line in the log every S seconds (0: only at stop)
};

enum class ReadyWhen { kFirstFrame, kStartup };

struct SystemdConfig {
  // first_frame: READY=1 once the first frame went through tracking and its sample reached the outputs, or after
  // ready_timeout_s without one (a vehicle booting with its camera unplugged still gets a running daemon that
  // reports "lost"); startup: as soon as the outputs are open.
  ReadyWhen ready = ReadyWhen::kFirstFrame;
  double ready_timeout_s = 20;
};

struct DaemonConfig {
  std::string path;  // the YAML file
  SourceConfig source;
  drivers::v4l2::V4l2CameraConfig camera;
  std::string calibration_file;  // resolved; "" = the dataset's own
  StageFiles stage_files;
  PipelineConfig pipeline;
  BaseLinkConfig base_link;
  CovarianceConfig covariance;
  OutputsConfig outputs;
  OdometryConfig odometry;
  TrajectoryConfig trajectory;
  LogConfig log;
  SystemdConfig systemd;
  MapConfig map;
  FilesConfig files;

  // Loaded from the stage files (defaults when a file is not given).
  slam::SystemConfig system;
  dynamic::DynamicDetectorConfig detector;
  stereo::StereoConfig stereo;
  std::optional<place::PlaceConfig> place;           // set when stages.place names a file
  std::optional<semantic::SemanticConfig> semantic;  // set when stages.semantic names a file (with the detector)

  // Throws InputError(path, "section.key", "expected ...").
  void validate() const;
  // Throws InputError naming the field of a written file that lies outside files.write_roots (none: no check).
  void check_write_confinement() const;
  // Every setting, a line each, for the start-up echo.
  std::vector<std::string> describe() const;
};

// Reads `path` and the stage files it names, validates, resolves relative paths against the file's folder.
DaemonConfig load_daemon_config(const std::string& path);

// The `dds` and `can` sections alone (the keys of DdsConfig / CanConfig), for tools that share the daemon's file.
drivers::dds::DdsConfig load_dds_config(const std::string& path, const std::string& section = "dds");
drivers::can::CanConfig load_can_config(const std::string& path, const std::string& section = "can");

}  // namespace agvslam::daemon
