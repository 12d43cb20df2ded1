#pragma once
// agvslamd's outputs, driven by the outputs thread one sample at a time:
//   DDS   rt/<ns>/pose and rt/<ns>/odom only for a tracking sample; rt/<ns>/status for every sample (two
//         DdsPosePublishers: one with pose+odom, one with status, each with its own writer thread, so a lost frame
//         publishes status alone and never a pose)
//   CAN   every sample (the frames carry the state bits; a sample that is not tracking carries the last good
//         pose, see PoseSampleBuilder), rate-limited by can.rate_hz; never blocks
//   trajectory file (TUM) of the tracking samples, and the per-sample JSON log (pose_log)
// publish() stamps latency_ns (capture -> handed to the outputs) just before handing the sample over.
//
// With odometry.source can, publish() first reads the odometry frames that arrived on the CAN socket (never
// waiting), feeds them and the sample to the OdometryMonitor, and fills sample.odometry_check, which the DDS status,
// the CAN frame AGVSLAM_ODOM_CHECK and the JSON log then carry; a warning goes to the log when the state turns to
// disagrees (at most every odometry.warn_every_s). Without an odometry input the outputs are as they were.

#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "agvslam/daemon/daemon_config.h"
#include "agvslam/daemon/odometry_monitor.h"
#include "agvslam/drivers/can/can_publisher.h"
#include "agvslam/drivers/can/odometry_input.h"
#include "agvslam/drivers/dds/publisher.h"
#include "agvslam/drivers/pose_sample.h"

namespace agvslam::daemon {

// Where one frame's time went (ms): waiting in the capture queue, in the detector (wall and the thread's CPU time),
// waiting for tracking, in tracking, waiting for the outputs thread. -1: not applicable.
struct StageTimes {
  double capture_queue_ms = -1, detector_ms = -1, detector_cpu_ms = -1, detected_queue_ms = -1, tracking_ms = -1,
         tracking_cpu_ms = -1, output_queue_ms = -1;
  int64_t tracked_mono_ns = 0;  // when tracking handed the sample over
};

// What the outputs thread hands over: the sample and where its frame came from (for the JSON log).
struct OutputItem {
  drivers::PoseSample sample;
  bool heartbeat = false;     // no frame behind it (status while nothing is processed)
  int64_t source_index = -1;  // dataset frame index (-1: camera or heartbeat)
  int64_t source_t_ns = 0;
  SE3d T_w_c = SE3d::Identity();  // the SLAM's camera pose (tracking samples), for trajectory.frame camera
  StageTimes times;
};

struct OutputStats {
  uint64_t samples = 0, tracking_samples = 0, heartbeats = 0;
  drivers::dds::DdsPublisherStats dds_pose, dds_status;
  bool can_enabled = false;
  drivers::can::CanPublisherStats can;
  std::string can_last_error;
  bool odometry_enabled = false;
  drivers::can::CanOdometryStats can_odometry;  // frames of the odometry message and what became of them
  uint64_t odometry_samples = 0;                // handed to the monitor
  uint64_t odometry_disagreements = 0;          // times the state turned to disagrees
  drivers::OdometryCheck odometry_check;        // the latest
};

// The check's figures as the JSON log and the statistics write them ({"state": "agrees", "distance_ratio": ...}).
nlohmann::json odometry_check_json(const drivers::OdometryCheck& check);

// A line-buffered append-only text file (the TUM trajectory, the JSON log); RAII over FILE*.
class TextFile {
 public:
  TextFile() = default;
  // Opens for writing (truncates); throws InputError(source, field, ...) when it cannot.
  TextFile(const std::string& path, const std::string& source, const std::string& field);
  ~TextFile();
  TextFile(TextFile&& other) noexcept;
  TextFile& operator=(TextFile&& other) noexcept;
  TextFile(const TextFile&) = delete;
  TextFile& operator=(const TextFile&) = delete;
  bool is_open() const { return file_ != nullptr; }
  void write_line(const char* text, std::size_t size);
  void flush();

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
};

class PoseOutputs {
 public:
  // Opens every enabled output. DDS failures throw (DdsError naming the domain/topic); CAN retries with back-off
  // (an absent interface is not an error: the bus may come up later); files throw InputError naming the field.
  // T_base_cam: the rectified left camera (the SLAM's camera) in base_link, published once on rt/tf_static.
  PoseOutputs(const DaemonConfig& config, const SE3d& T_base_cam);
  // The same with config.base_link's extrinsic (images without rectification).
  explicit PoseOutputs(const DaemonConfig& config);
  ~PoseOutputs();
  PoseOutputs(const PoseOutputs&) = delete;
  PoseOutputs& operator=(const PoseOutputs&) = delete;

  // Stamps item.sample.latency_ns and hands the sample to every output. Outputs thread only.
  void publish(OutputItem& item);
  // Flushes the files and waits up to `timeout` for DDS readers to acknowledge what was written.
  void flush(std::chrono::milliseconds timeout);
  OutputStats stats() const;
  // Waits until the DDS topics have `count` matched readers each (tests, benchmarks).
  bool wait_for_subscribers(int count, std::chrono::milliseconds timeout) const;

 private:
  const DaemonConfig& config_;
  // The status publisher is created first: it owns the DDS domain when one is created, so it must go last.
  std::unique_ptr<drivers::dds::DdsPosePublisher> dds_status_;
  std::unique_ptr<drivers::dds::DdsPosePublisher> dds_pose_;
  std::unique_ptr<drivers::can::CanPosePublisher> can_;
  std::unique_ptr<drivers::can::CanOdometryDecoder> can_odometry_;
  std::unique_ptr<OdometryMonitor> odometry_monitor_;
  drivers::OdometryCheckState odometry_state_ = drivers::OdometryCheckState::kOff;
  std::chrono::steady_clock::time_point last_odometry_warning_{};
  uint64_t odometry_disagreements_ = 0;
  uint32_t map_id_ = 0;  // of the last frame's sample: a change is logged
  // Wheel odometry integrated in the plane (x, y, yaw of base_link in odom) up to the last odometry sample, for
  // tf's odom frame.
  bool odom_started_ = false;
  OdometryRate last_rate_;
  double odom_x_m_ = 0, odom_y_m_ = 0, odom_yaw_rad_ = 0;
  void integrate_odometry(const OdometryRate& rate);
  // base_link in odom at t_ns (the last integrated pose moved on by the last rate); false when no odometry is
  // current (none yet, or older than odometry.stale_ms).
  bool odom_pose_at(int64_t t_ns, SE3d& T_odom_base) const;
  TextFile trajectory_, pose_log_;
  int unflushed_ = 0;
  uint64_t samples_ = 0, tracking_samples_ = 0, heartbeats_ = 0;
  mutable std::mutex stats_mutex_;             // stats() is read by the supervisor while the outputs thread publishes
  drivers::can::CanPublisherStats can_stats_;  // copied after each publish (CanPosePublisher is single-threaded)
  std::string can_last_error_;
  drivers::can::CanOdometryStats can_odometry_stats_;  // copied likewise, with the monitor's figures
  drivers::OdometryCheck odometry_check_;
  uint64_t odometry_samples_copy_ = 0, odometry_disagreements_copy_ = 0;

  // Reads the odometry frames that arrived and fills item.sample.odometry_check (odometry input configured).
  void check_odometry(OutputItem& item, bool tracking);
};

}  // namespace agvslam::daemon
