#include "agvslam/daemon/pose_outputs.h"

#include <spdlog/spdlog.h>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "agvslam/core/error.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "agvslam/drivers/pose_sample_json.h"

namespace agvslam::daemon {

namespace dds = drivers::dds;

nlohmann::json odometry_check_json(const drivers::OdometryCheck& c) {
  // NaN (no ratio) is written as null.
  return {{"state", drivers::to_string(c.state)},
          {"distance_ratio", c.distance_ratio},
          {"speed_rmse_mps", c.speed_rmse_mps},
          {"heading_difference_deg", c.heading_difference_deg},
          {"window_s", c.window_s}};
}

TextFile::TextFile(const std::string& path, const std::string& source, const std::string& field) : path_(path) {
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) {
    throw InputError(source, field, "expected a writable file, " + path + ": " + std::strerror(errno));
  }
}

TextFile::~TextFile() {
  if (file_ != nullptr) std::fclose(file_);
}

TextFile::TextFile(TextFile&& other) noexcept : file_(other.file_), path_(std::move(other.path_)) {
  other.file_ = nullptr;
}

TextFile& TextFile::operator=(TextFile&& other) noexcept {
  if (this != &other) {
    if (file_ != nullptr) std::fclose(file_);
    file_ = other.file_;
    path_ = std::move(other.path_);
    other.file_ = nullptr;
  }
  return *this;
}

void TextFile::write_line(const char* text, std::size_t size) {
  if (file_ == nullptr) return;
  std::fwrite(text, 1, size, file_);
  std::fputc('\n', file_);
}

void TextFile::flush() {
  if (file_ != nullptr) std::fflush(file_);
}

PoseOutputs::PoseOutputs(const DaemonConfig& config) : PoseOutputs(config, config.base_link.T_base_cam()) {}

PoseOutputs::PoseOutputs(const DaemonConfig& config, const SE3d& T_base_cam) : config_(config) {
  if (config.outputs.dds_enabled) {
    const dds::DdsConfig& base = config.outputs.dds;
    if (base.publish_status) {
      dds::DdsConfig c = base;
      c.publish_pose = c.publish_odom = c.publish_tf = c.publish_tf_static = false;
      dds_status_ = std::make_unique<dds::DdsPosePublisher>(c);
    }
    if (base.publish_pose || base.publish_odom || base.publish_tf || base.publish_tf_static) {
      dds::DdsConfig c = base;
      c.publish_status = false;
      dds_pose_ = std::make_unique<dds::DdsPosePublisher>(c);
      if (base.publish_tf_static && !dds_pose_->write_static_transform(dds::realtime_now_ns(), T_base_cam,
                                                                       base.base_frame_id, base.camera_frame_id)) {
        spdlog::warn("dds: the static transform {} -> {} could not be written on {}", base.base_frame_id,
                     base.camera_frame_id, dds::DdsConfig::tf_static_topic());
      }
    }
  }
  if (config.odometry.source == OdometrySource::kCan) {
    can_odometry_ = std::make_unique<drivers::can::CanOdometryDecoder>(config.odometry.can, config.outputs.can.layout(),
                                                                       config.path);
    spdlog::info("odometry: reading {} on {}", can_odometry_->describe(), config.outputs.can.interface);
  }
  if (config.odometry.source != OdometrySource::kNone) {
    odometry_monitor_ = std::make_unique<OdometryMonitor>(config.odometry.check);
  }
  if (config.outputs.can_enabled) {
    std::vector<drivers::can::CanId> receive;
    if (can_odometry_) receive.push_back(drivers::can::CanId{can_odometry_->id(), can_odometry_->extended()});
    can_ = std::make_unique<drivers::can::CanPosePublisher>(config.outputs.can, receive);
    if (!can_->is_open()) {
      spdlog::warn("can: {} not available yet ({}); retrying with back-off", config.outputs.can.interface,
                   can_->last_error());
    }
  }
  if (!config.trajectory.file.empty()) trajectory_ = TextFile(config.trajectory.file, config.path, "trajectory.file");
  if (!config.log.pose_log.empty()) pose_log_ = TextFile(config.log.pose_log, config.path, "log.pose_log");
}

PoseOutputs::~PoseOutputs() {
  // The pose publisher first: the status publisher may own the DDS domain.
  dds_pose_.reset();
  dds_status_.reset();
}

namespace {

// The planar pose (x, y in m, yaw in rad) moved on by a speed and yaw rate held for dt_s (midpoint heading).
void advance_planar(double& x_m, double& y_m, double& yaw_rad, const OdometryRate& rate, double dt_s) {
  const double mid_yaw = yaw_rad + 0.5 * rate.yaw_rate_radps * dt_s;
  x_m += rate.speed_mps * dt_s * std::cos(mid_yaw);
  y_m += rate.speed_mps * dt_s * std::sin(mid_yaw);
  yaw_rad += rate.yaw_rate_radps * dt_s;
}

}  // namespace

void PoseOutputs::integrate_odometry(const OdometryRate& rate) {
  if (odom_started_) {
    const double dt_s = ns_to_s(rate.t_ns - last_rate_.t_ns);
    if (dt_s <= 0) return;  // out of order: the integration needs time order
    // A gap longer than stale_ms is bridged with the older rate as well: the odom frame must stay continuous.
    advance_planar(odom_x_m_, odom_y_m_, odom_yaw_rad_, last_rate_, dt_s);
  }
  odom_started_ = true;
  last_rate_ = rate;
}

bool PoseOutputs::odom_pose_at(int64_t t_ns, SE3d& T_odom_base) const {
  if (!odom_started_) return false;
  const double ahead_s = ns_to_s(t_ns - last_rate_.t_ns);
  if (ahead_s * 1000.0 > config_.odometry.check.stale_ms) return false;
  double x_m = odom_x_m_, y_m = odom_y_m_, yaw_rad = odom_yaw_rad_;
  // A frame captured before the last odometry sample gets that sample's pose.
  advance_planar(x_m, y_m, yaw_rad, last_rate_, std::max(ahead_s, 0.0));
  T_odom_base = make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())),
                         Eigen::Vector3d(x_m, y_m, 0.0));
  return true;
}

void PoseOutputs::check_odometry(OutputItem& item, bool tracking) {
  drivers::PoseSample& s = item.sample;
  if (can_ && can_odometry_) {
    can_->poll();
    for (const drivers::can::ReceivedCanFrame& r : can_->take_received()) {
      if (r.frame.id != can_odometry_->id() || r.frame.extended != can_odometry_->extended()) continue;
      if (auto rate = can_odometry_->decode(r.frame, r.t_ns)) {
        odometry_monitor_->add_odometry(*rate);
        integrate_odometry(*rate);
      }
    }
  }
  s.odom_valid = odom_pose_at(s.t_ns, s.T_odom_base);
  s.odometry_check = item.heartbeat ? odometry_monitor_->status_at(s.t_ns)
                                    : odometry_monitor_->add_pose(s.t_ns, s.T_map_base, tracking);
  const drivers::OdometryCheck& c = s.odometry_check;
  if (c.state != odometry_state_ && c.state == drivers::OdometryCheckState::kDisagrees) {
    ++odometry_disagreements_;
    const auto now = std::chrono::steady_clock::now();
    const auto every = std::chrono::duration<double>(config_.odometry.check.warn_every_s);
    if (odometry_disagreements_ == 1 || now - last_odometry_warning_ >= every) {
      spdlog::warn(
          "odometry: the pose disagrees with the wheel odometry over the last {:.1f} s: distance ratio {:.3f} "
          "(SLAM / odometry), heading difference {:.1f} deg, speed RMSE {:.3f} m/s (tolerance {:.0f} %; "
          "{} time(s) so far)",
          c.window_s, c.distance_ratio, c.heading_difference_deg, c.speed_rmse_mps,
          config_.odometry.check.tolerance * 100.0, odometry_disagreements_);
      last_odometry_warning_ = now;
    }
  }
  odometry_state_ = c.state;
}

void PoseOutputs::publish(OutputItem& item) {
  drivers::PoseSample& s = item.sample;
  const bool tracking = s.tracking_state == drivers::TrackingState::kTracking && !item.heartbeat;
  if (odometry_monitor_) check_odometry(item, tracking);
  if (!item.heartbeat && s.map_id != map_id_) {
    spdlog::warn(
        "slam: tracking was lost too long to relocalise; map {} started at the vehicle's position (frame {}): the "
        "pose jumps to its origin (DDS status map_id)",
        s.map_id, s.frame_index);
    map_id_ = s.map_id;
  }
  s.latency_ns = item.heartbeat ? 0 : dds::realtime_now_ns() - s.t_ns;
  if (tracking && dds_pose_) dds_pose_->publish(s);
  if (dds_status_) dds_status_->publish(s);
  drivers::can::CanPublishResult can_result;
  if (can_) can_result = can_->publish(s);

  if (tracking && trajectory_.is_open()) {
    const SE3d T = config_.trajectory.frame == TrajectoryFrame::kBaseLink ? s.T_map_base : item.T_w_c;
    Eigen::Quaterniond q(T.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1.0;
    const Eigen::Vector3d& t = T.translation();
    char line[256];
    const int64_t sec = s.t_ns / 1000000000LL, nsec = s.t_ns % 1000000000LL;
    const int n =
        std::snprintf(line, sizeof line, "%" PRId64 ".%09" PRId64 " %.10f %.10f %.10f %.12f %.12f %.12f %.12f", sec,
                      nsec, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    trajectory_.write_line(line, static_cast<std::size_t>(n));
    if (++unflushed_ >= config_.trajectory.flush_every) {
      trajectory_.flush();
      unflushed_ = 0;
    }
  }
  if (pose_log_.is_open()) {
    nlohmann::json j = {{"i", samples_},
                        {"t_ns", s.t_ns},
                        {"heartbeat", item.heartbeat},
                        {"source_index", item.source_index},
                        {"source_t_ns", item.source_t_ns},
                        {"sample", drivers::pose_sample_to_json(s)},
                        {"times_ms",
                         {{"capture_queue", item.times.capture_queue_ms},
                          {"detector", item.times.detector_ms},
                          {"detector_cpu", item.times.detector_cpu_ms},
                          {"detected_queue", item.times.detected_queue_ms},
                          {"tracking", item.times.tracking_ms},
                          {"tracking_cpu", item.times.tracking_cpu_ms},
                          {"output_queue", item.times.output_queue_ms}}},
                        {"dds", {{"pose", tracking && dds_pose_ != nullptr}, {"status", dds_status_ != nullptr}}}};
    if (can_) {
      j["can"] = {{"due", can_result.due},
                  {"sent", can_result.sent},
                  {"counter", can_result.counter},
                  {"frames_sent", can_result.frames_sent}};
    }
    if (odometry_monitor_) j["odometry_check"] = odometry_check_json(s.odometry_check);
    const std::string text = j.dump();
    pose_log_.write_line(text.data(), text.size());
    pose_log_.flush();  // a test or an operator tailing the file sees each sample as it goes
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++samples_;
  if (tracking) ++tracking_samples_;
  if (item.heartbeat) ++heartbeats_;
  if (can_) {
    can_stats_ = can_->stats();
    if (can_last_error_ != can_->last_error()) can_last_error_ = can_->last_error();
  }
  if (can_odometry_) can_odometry_stats_ = can_odometry_->stats();
  if (odometry_monitor_) {
    odometry_check_ = s.odometry_check;
    odometry_samples_copy_ = odometry_monitor_->odometry_samples();
    odometry_disagreements_copy_ = odometry_disagreements_;
  }
}

void PoseOutputs::flush(std::chrono::milliseconds timeout) {
  trajectory_.flush();
  pose_log_.flush();
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (auto* pub : {dds_pose_.get(), dds_status_.get()}) {
    if (pub == nullptr) continue;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (!pub->flush(std::max(left, std::chrono::milliseconds(0)))) {
      spdlog::warn("dds: not every sample was acknowledged by the subscribers within {} ms", timeout.count());
    }
  }
}

OutputStats PoseOutputs::stats() const {
  OutputStats s;
  if (dds_pose_) s.dds_pose = dds_pose_->stats();
  if (dds_status_) s.dds_status = dds_status_->stats();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  s.samples = samples_;
  s.tracking_samples = tracking_samples_;
  s.heartbeats = heartbeats_;
  s.can_enabled = can_ != nullptr;
  s.can = can_stats_;
  s.can_last_error = can_last_error_;
  s.odometry_enabled = odometry_monitor_ != nullptr;
  s.can_odometry = can_odometry_stats_;
  s.odometry_check = odometry_check_;
  s.odometry_disagreements = odometry_disagreements_copy_;
  s.odometry_samples = odometry_samples_copy_;
  return s;
}

bool PoseOutputs::wait_for_subscribers(int count, std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (auto* pub : {dds_pose_.get(), dds_status_.get()}) {
    if (pub == nullptr) continue;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (!pub->wait_for_subscribers(count, std::max(left, std::chrono::milliseconds(0)))) return false;
  }
  return true;
}

}  // namespace agvslam::daemon
