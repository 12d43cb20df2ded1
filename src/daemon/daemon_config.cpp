#include "agvslam/daemon/daemon_config.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "agvslam/core/error.h"
#include "agvslam/core/param_table.h"
#include "agvslam/features/features_config.h"

namespace agvslam::daemon {
namespace {

namespace fs = std::filesystem;
using params::Range;
using params::Text;

constexpr double kDegToRad = M_PI / 180.0;

std::string resolve(const fs::path& dir, const std::string& value) {
  if (value.empty()) return value;
  const fs::path p(value);
  return p.is_absolute() ? value : (dir / p).lexically_normal().string();
}

const params::EnumNames<SourceType>& source_type_names() {
  static const params::EnumNames<SourceType> names{{"v4l2", SourceType::kV4l2}, {"dataset", SourceType::kDataset}};
  return names;
}

const params::Table<SourceConfig>& source_params() {
  using S = SourceConfig;
  static const params::Table<S> table =
      params::Table<S>(
          "source",
          {
              {"type", &S::type, source_type_names()},
              {"dataset", &S::dataset, Text::any(), "a dataset folder"},
              {"rate", &S::rate, Range::any(), "x the dataset's rate", "0: as fast as the pipeline takes frames"},
              {"rate_hz", &S::rate_hz, Range::any(), "Hz", "0: use source.rate"},
              {"loop", &S::loop},
              {"frames", &S::frames, Text::any(), "an inclusive frame range A:B, \"\" = all"},
              {"wait_for_camera", &S::wait_for_camera},
          })
          .check(
              "dataset", [](const S& s) { return s.type != SourceType::kDataset || !s.dataset.empty(); },
              "a dataset folder (source.type dataset)")
          .check(
              "rate", [](const S& s) { return s.type != SourceType::kDataset || (s.rate >= 0 && s.rate <= 1000); },
              "a speed factor in [0, 1000] (0: as fast as the pipeline goes)")
          .check(
              "rate_hz",
              [](const S& s) { return s.type != SourceType::kDataset || (s.rate_hz >= 0 && s.rate_hz <= 1000); },
              "a rate in [0, 1000] Hz (0: use source.rate)");
  return table;
}

const params::Table<DaemonConfig>& calibration_params() {
  static const params::Table<DaemonConfig> table =
      params::Table<DaemonConfig>("calibration",
                                  {
                                      {"file", &DaemonConfig::calibration_file, Text::any(),
                                       "KITTI calib.txt, ORB-SLAM YAML or Kalibr camchain"},
                                  })
          .check(
              "file",
              [](const DaemonConfig& d) { return d.source.type != SourceType::kV4l2 || !d.calibration_file.empty(); },
              "a calibration file for the V4L2 camera (source.type v4l2)");
  return table;
}

const params::Table<StageFiles>& stages_params() {
  static const params::Table<StageFiles> table(
      "stages", {
                    {"features", &StageFiles::features, Text::any(), "params/features.yaml; \"\" = built-in defaults"},
                    {"slam", &StageFiles::slam, Text::any(), "params/slam.yaml; \"\" = built-in defaults"},
                    {"dynamic", &StageFiles::dynamic, Text::any(), "params/dynamic.yaml; \"\" = built-in defaults"},
                    {"stereo", &StageFiles::stereo, Text::any(), "params/stereo.yaml; \"\" = built-in defaults"},
                    {"place", &StageFiles::place, Text::any(), "params/place.yaml; \"\" = no vocabulary"},
                    {"semantic", &StageFiles::semantic, Text::any(), "params/semantic.yaml; \"\" = no semantic stage"},
                });
  return table;
}

const params::Table<PipelineConfig>& pipeline_params() {
  using P = PipelineConfig;
  static const params::EnumNames<DynamicMode> dynamic_names{{"detector", DynamicMode::kDetector},
                                                            {"off", DynamicMode::kOff}};
  static const params::EnumNames<MappingMode> mapping_names{{"thread", MappingMode::kThread},
                                                            {"inline", MappingMode::kInline}};
  static const params::Table<P> table(
      "pipeline",
      {
          {"dynamic", &P::dynamic, dynamic_names},
          {"mapping", &P::mapping, mapping_names},
          {"capture_queue", &P::capture_queue, Range::closed(1, 64), "frames"},
          {"output_queue", &P::output_queue, Range::closed(1, 1024), "samples"},
          {"frame_rate_hz", &P::frame_rate_hz, Range::closed(0, 1000), "Hz", "0: the camera's or dataset's"},
          {"opencv_threads", &P::opencv_threads, Range::closed(1, 64)},
          {"heartbeat_ms", &P::heartbeat_ms, Range::closed(10, 60000), "ms"},
          {"poll_ms", &P::poll_ms, Range::closed(1, 5000), "ms"},
      });
  return table;
}

const params::Table<BaseLinkConfig>& base_link_params() {
  using B = BaseLinkConfig;
  static const params::Table<B> table(
      "base_link",
      {
          {"x_m", &B::x_m, Range::closed(-100, 100), "m"},
          {"y_m", &B::y_m, Range::closed(-100, 100), "m"},
          {"z_m", &B::z_m, Range::closed(-100, 100), "m"},
          {"roll_deg", &B::roll_deg, Range::closed(-360, 360), "deg"},
          {"pitch_deg", &B::pitch_deg, Range::closed(-360, 360), "deg"},
          {"yaw_deg", &B::yaw_deg, Range::closed(-360, 360), "deg"},
          {"optical", &B::optical, "true: the angles are of the camera_link frame, false: of the optical frame"},
      });
  return table;
}

const params::Table<CovarianceConfig>& covariance_params() {
  using V = CovarianceConfig;
  static const params::Table<V> table(
      "covariance", {
                        {"position_sd_m", &V::position_sd_m, Range::left_open(0, 1000), "m"},
                        {"rotation_sd_deg", &V::rotation_sd_deg, Range::left_open(0, 1000), "deg"},
                        {"velocity_sd_mps", &V::velocity_sd_mps, Range::left_open(0, 1000), "m/s"},
                        {"angular_sd_degps", &V::angular_sd_degps, Range::left_open(0, 1000), "deg/s"},
                        {"reference_inliers", &V::reference_inliers, Range::at_least(1)},
                        {"min_inliers", &V::min_inliers, Range::at_least(1)},
                    });
  return table;
}

// The `dds` and `can` sections: the driver's settings plus the daemon's own about that output.
const params::Table<OutputsConfig>& dds_section_params() {
  using O = OutputsConfig;
  static const params::Table<O> table =
      params::Table<O>("dds",
                       {
                           {"enabled", &O::dds_enabled},
                           {"wait_for_subscribers", &O::dds_wait_for_subscribers, Range::closed(0, 100), "subscribers",
                            "0: do not wait"},
                           {"wait_timeout_s", &O::dds_wait_timeout_s, Range::left_open(0, 3600), "s"},
                       })
          .include(&O::dds, drivers::dds::dds_params());
  return table;
}

const params::Table<OutputsConfig>& can_section_params() {
  static const params::Table<OutputsConfig> table =
      params::Table<OutputsConfig>("can", {{"enabled", &OutputsConfig::can_enabled}})
          .include(&OutputsConfig::can, drivers::can::can_params());
  return table;
}

const params::Table<OdometryMonitorConfig>& odometry_check_params() {
  using M = OdometryMonitorConfig;
  static const params::Table<M> table(
      "odometry",
      {
          {"window_s", &M::window_s, Range::closed(1, 60), "s",
           "long against the pose noise and the odometry's stamp jitter, short enough to flag a divergence in seconds"},
          {"min_distance_m", &M::min_distance_m, Range::closed(0.05, 100), "m",
           "travel a window needs before its distance ratio is judged"},
          {"tolerance", &M::tolerance, Range::open(0, 1), "", "fraction: 0.2 flags a ratio outside 0.8..1.2"},
          {"min_yaw_rate_degps", &M::min_yaw_rate_degps, Range::closed(0.1, 180), "deg/s",
           "heading differences are judged against at least this rate times the window"},
          {"stale_ms", &M::stale_ms, Range::closed(10, 60000), "ms"},
          {"warn_every_s", &M::warn_every_s, Range::at_least(0), "s", "0: every time the state turns to disagrees"},
      });
  return table;
}

const params::Table<OdometryConfig>& odometry_params() {
  static const params::EnumNames<OdometrySource> source_names{{"none", OdometrySource::kNone},
                                                              {"can", OdometrySource::kCan}};
  static const params::Table<OdometryConfig> table =
      params::Table<OdometryConfig>("odometry", {{"source", &OdometryConfig::source, source_names}})
          .include(&OdometryConfig::check, odometry_check_params());
  return table;
}

const params::Table<OdometryConfig>& can_odometry_section_params() {
  static const params::Table<OdometryConfig> table =
      params::Table<OdometryConfig>("can_odometry", {})
          .include(&OdometryConfig::can, drivers::can::can_odometry_params());
  return table;
}

const params::Table<TrajectoryConfig>& trajectory_params() {
  using T = TrajectoryConfig;
  static const params::EnumNames<TrajectoryFrame> frame_names{{"base_link", TrajectoryFrame::kBaseLink},
                                                              {"camera", TrajectoryFrame::kCamera}};
  static const params::Table<T> table("trajectory", {
                                                        {"file", &T::file, Text::any(), "TUM; \"\" = none"},
                                                        {"frame", &T::frame, frame_names},
                                                        {"flush_every", &T::flush_every, Range::at_least(1), "poses"},
                                                        {"final_file", &T::final_file, Text::any(), "TUM; \"\" = none"},
                                                    });
  return table;
}

const params::Table<LogConfig>& log_params() {
  using L = LogConfig;
  static const params::Table<L> table(
      "log", {
                 {"file", &L::file, Text::any(), "\"\" = stderr only"},
                 {"level", &L::level, Text::one_of({"trace", "debug", "info", "warn", "error"})},
                 {"pose_log", &L::pose_log, Text::any(), "JSON lines; \"\" = none"},
                 {"stats_every_s", &L::stats_every_s, Range::at_least(0), "s", "0: only at stop"},
             });
  return table;
}

const params::Table<SystemdConfig>& systemd_params() {
  using Y = SystemdConfig;
  static const params::EnumNames<ReadyWhen> ready_names{{"first_frame", ReadyWhen::kFirstFrame},
                                                        {"startup", ReadyWhen::kStartup}};
  static const params::Table<Y> table("systemd",
                                      {
                                          {"ready", &Y::ready, ready_names},
                                          {"ready_timeout_s", &Y::ready_timeout_s, Range::left_open(0, 3600), "s"},
                                      });
  return table;
}

const params::Table<MapConfig>& map_params() {
  using M = MapConfig;
  // localise: track in the saved map without changing it; map: extend it. The other spellings are accepted too.
  static const params::EnumNames<slam::MapMode> mode_names{
      {"map", slam::MapMode::kMapping},           {"localise", slam::MapMode::kLocalisation},
      {"mapping", slam::MapMode::kMapping},       {"localisation", slam::MapMode::kLocalisation},
      {"localize", slam::MapMode::kLocalisation}, {"localization", slam::MapMode::kLocalisation}};
  static const params::Table<M> table =
      params::Table<M>("map",
                       {
                           {"file", &M::file, Text::any(), "\"\" = no map file"},
                           {"mode", &M::mode, mode_names},
                           {"save_on_stop", &M::save_on_stop},
                       })
          .check(
              "file",
              [](const M& m) { return m.file.empty() || m.mode != slam::MapMode::kLocalisation || fs::exists(m.file); },
              [](const M& m) { return "an existing map file in mode localise (" + m.file + " does not exist)"; });
  return table;
}

const params::Table<FilesConfig>& files_params() {
  static const params::Table<FilesConfig> table(
      "files", {{"write_dirs", &FilesConfig::write_dirs, Text::any(), "folders separated by ':'; env | \"\""}});
  return table;
}

std::vector<std::string> split_dirs(const std::string& list) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(':', start), list.size());
    if (end > start) out.push_back(list.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

// The canonical folders of files.write_dirs (relative ones against `dir`).
std::vector<std::string> write_roots(const std::string& write_dirs, const fs::path& dir) {
  std::vector<std::string> listed;
  if (write_dirs == "env") {
    for (const char* name : {"STATE_DIRECTORY", "LOGS_DIRECTORY"}) {
      const char* value = std::getenv(name);
      for (const std::string& d : split_dirs(value != nullptr ? value : "")) listed.push_back(d);
    }
  } else {
    listed = split_dirs(write_dirs);
  }
  std::vector<std::string> roots;
  for (const std::string& d : listed) roots.push_back(fs::weakly_canonical(dir / d).string());
  return roots;
}

std::string joined(const std::vector<std::string>& dirs) {
  std::string out;
  for (const std::string& d : dirs) out += (out.empty() ? "" : ":") + d;
  return out;
}

// The files the daemon's outputs name, with their fields.
std::vector<std::pair<const char*, std::string>> named_files(const DaemonConfig& c) {
  return {{"trajectory.file", c.trajectory.file},
          {"trajectory.final_file", c.trajectory.final_file},
          {"log.file", c.log.file},
          {"log.pose_log", c.log.pose_log},
          {"map.file", c.map.file}};
}

bool inside(const fs::path& root, const fs::path& p) {
  auto r = root.begin();
  auto q = p.begin();
  for (; r != root.end(); ++r, ++q) {
    if (r->empty()) continue;  // the empty last element of a root written with a trailing '/'
    if (q == p.end() || *r != *q) return false;
  }
  return true;
}

}  // namespace

const char* to_string(SourceType type) { return source_type_names().name(type); }

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

std::string BaseLinkConfig::describe() const { return base_link_params().describe(*this); }

std::string CovarianceConfig::describe() const { return covariance_params().describe(*this); }

std::string MapConfig::describe() const { return map_params().describe(*this); }

void DaemonConfig::validate() const {
  const std::string& p = path;
  source_params().validate(p, source);
  if (source.type == SourceType::kV4l2) camera.validate(p);
  calibration_params().validate(p, *this);
  pipeline_params().validate(p, pipeline);
  base_link_params().validate(p, base_link);
  covariance_params().validate(p, covariance);
  dds_section_params().validate(p, outputs);
  drivers::dds::dds_security_params().validate(p, outputs.dds.security);
  can_section_params().validate(p, outputs);
  odometry_params().validate(p, odometry);
  if (odometry.source == OdometrySource::kCan) {
    if (!outputs.can_enabled) {
      throw InputError(p, "odometry.source",
                       "expected none, or can.enabled true (the odometry frames are read on "
                       "the CAN output's interface), got can");
    }
    can_odometry_section_params().validate(p, odometry);
  }
  trajectory_params().validate(p, trajectory);
  log_params().validate(p, log);
  systemd_params().validate(p, systemd);
  map_params().validate(p, map);
  if (!map.file.empty() && stage_files.place.empty()) {
    throw InputError(p, "stages.place",
                     "expected the place params (vocabulary) when map.file is set: relocalising "
                     "in a saved map needs the vocabulary it was saved with");
  }
  // Two outputs writing one file would interleave.
  const std::vector<std::pair<const char*, std::string>> named = named_files(*this);
  for (std::size_t i = 0; i < named.size(); ++i) {
    for (std::size_t j = i + 1; j < named.size(); ++j) {
      if (!named[i].second.empty() && named[i].second == named[j].second) {
        throw InputError(p, named[j].first, std::string("expected a file other than ") + named[i].first + "'s");
      }
    }
  }
  check_write_confinement();
}

void DaemonConfig::check_write_confinement() const {
  if (files.write_roots.empty()) return;
  // The map file is only read in localisation mode or without save_on_stop.
  const bool map_written = map.mode == slam::MapMode::kMapping && map.save_on_stop;
  const std::string roots = joined(files.write_roots);
  for (const auto& [field, file] : named_files(*this)) {
    if (file.empty() || (std::string(field) == "map.file" && !map_written)) continue;
    const fs::path resolved = fs::weakly_canonical(file);
    bool ok = false;
    for (const std::string& r : files.write_roots) ok = ok || inside(r, resolved);
    if (!ok) {
      throw InputError(path, field,
                       "expected a file inside the folders the daemon may write (" + roots +
                           "; files.write_dirs), got " + file +
                           (resolved.string() != file ? " (resolves to " + resolved.string() + ")" : ""));
    }
  }
}

std::vector<std::string> DaemonConfig::describe() const {
  std::vector<std::string> out = {source_params().describe(source)};
  if (source.type == SourceType::kV4l2) out.push_back(camera.describe());
  out.push_back(calibration_params().describe(*this));
  out.push_back(stages_params().describe(stage_files));
  if (place) out.push_back(place->describe());
  out.push_back(map.describe());
  out.push_back(pipeline_params().describe(pipeline));
  out.push_back(base_link.describe());
  out.push_back(covariance.describe());
  out.push_back(dds_section_params().describe(outputs));
  out.push_back(outputs.dds.security.describe());
  out.push_back(can_section_params().describe(outputs));
  out.push_back(odometry_params().describe(odometry));
  if (odometry.source == OdometrySource::kCan) out.push_back(can_odometry_section_params().describe(odometry));
  out.push_back(trajectory_params().describe(trajectory));
  out.push_back(log_params().describe(log));
  out.push_back(systemd_params().describe(systemd));
  const std::string roots = joined(files.write_roots);
  out.push_back(files_params().describe(files) + " (writes " + (roots.empty() ? "not confined" : "only in " + roots) +
                ")");
  features::FeaturesConfig f;
  f.orb = system.orb;
  f.stereo_matching = system.stereo;
  for (const auto& line : f.describe()) out.push_back("  " + line);
  for (const auto& line : system.slam.describe()) out.push_back("  " + line);
  if (pipeline.dynamic == DynamicMode::kDetector) {
    for (const auto& line : detector.describe()) out.push_back("  " + line);
    for (const auto& line : stereo.describe()) out.push_back("  " + line);
    if (semantic) {
      for (const auto& line : semantic->describe()) out.push_back("  semantic " + line);
    }
  }
  return out;
}

drivers::dds::DdsConfig load_dds_config(const std::string& path, const std::string& section) {
  drivers::dds::DdsConfig c;
  const params::File file(path);
  drivers::dds::dds_params().read(file, section, c);
  drivers::dds::dds_security_params().read(file, c.security);
  c.validate(path);
  return c;
}

drivers::can::CanConfig load_can_config(const std::string& path, const std::string& section) {
  drivers::can::CanConfig c;
  drivers::can::can_params().read(params::File(path), section, c);
  c.validate(path);
  return c;
}

DaemonConfig load_daemon_config(const std::string& path) {
  const params::File in(path);
  DaemonConfig c;
  c.path = path;
  const auto camera = [&c](const params::File& f) {
    if (c.source.type != SourceType::kV4l2) return;  // the section is not read for a dataset
    f.require_section("camera");
    drivers::v4l2::camera_params().read(f, c.camera);
  };
  params::read_sections(in, {source_params().reader(c.source),
                             {"camera", camera},
                             calibration_params().reader(c),
                             stages_params().reader(c.stage_files),
                             pipeline_params().reader(c.pipeline),
                             base_link_params().reader(c.base_link),
                             covariance_params().reader(c.covariance),
                             dds_section_params().reader(c.outputs),
                             drivers::dds::dds_security_params().reader(c.outputs.dds.security),
                             can_section_params().reader(c.outputs),
                             odometry_params().reader(c.odometry),
                             can_odometry_section_params().reader(c.odometry),
                             trajectory_params().reader(c.trajectory),
                             log_params().reader(c.log),
                             systemd_params().reader(c.systemd),
                             map_params().reader(c.map),
                             files_params().reader(c.files)});
  const fs::path dir = fs::absolute(fs::path(path)).parent_path();
  for (std::string* f : {&c.source.dataset, &c.calibration_file, &c.stage_files.features, &c.stage_files.slam,
                         &c.stage_files.dynamic, &c.stage_files.stereo, &c.stage_files.place, &c.stage_files.semantic,
                         &c.trajectory.file, &c.trajectory.final_file, &c.log.file, &c.log.pose_log, &c.map.file,
                         &c.odometry.can.dbc, &c.outputs.dds.security.keystore}) {
    *f = resolve(dir, *f);
  }
  c.files.write_roots = write_roots(c.files.write_dirs, dir);
  c.validate();
  // The DDS Security keystore: a missing, tampered or expired file stops the daemon here, naming it.
  if (c.outputs.dds_enabled && c.outputs.dds.security.enabled) drivers::dds::check_enclave(c.outputs.dds.security);
  // The DBC, its message and signals: wrong ones stop the daemon here, not when the first frame arrives.
  if (c.odometry.source == OdometrySource::kCan)
    drivers::can::CanOdometryDecoder(c.odometry.can, c.outputs.can.layout(), path);

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
      throw InputError(c.stage_files.place, "vocabulary.file",
                       "expected an existing vocabulary file (" + c.place->vocabulary_file + " does not exist)");
    }
    c.system.direct_index_level = c.place->direct_index_level;
  }
  if (c.pipeline.dynamic == DynamicMode::kDetector) {
    if (!c.stage_files.dynamic.empty()) c.detector = dynamic::load_dynamic_config(c.stage_files.dynamic);
    if (!c.stage_files.stereo.empty()) c.stereo = stereo::load_stereo_config(c.stage_files.stereo);
    if (!c.stage_files.semantic.empty()) c.semantic = semantic::load_semantic_config(c.stage_files.semantic);
  }
  return c;
}

}  // namespace agvslam::daemon
