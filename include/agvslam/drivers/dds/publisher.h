#pragma once
// The daemon's DDS pose output: PoseWithCovarianceStamped on rt/<ns>/pose, Odometry on rt/<ns>/odom, Status on
// rt/<ns>/status, all with ROS 2 default QoS; tf2_msgs/TFMessage on rt/tf (the sample's map -> base_link, or
// map -> odom -> base_link when it carries an odometry pose) and rt/tf_static (written once, transient local) with
// tf2_ros's QoS (DdsConfig::publish_tf, publish_tf_static).
//
// publish() never waits for the network: it copies the sample into a bounded queue (when full, the oldest
// waiting sample is dropped and counted) and the publisher's own thread writes it. write_now() writes on the
// caller's thread (benchmarks, tools that want no thread).

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "agvslam/drivers/dds/dds_config.h"
#include "agvslam/drivers/dds/participant.h"
#include "agvslam/drivers/dds/ros_messages.h"
#include "agvslam/drivers/pose_sample.h"

namespace agvslam::drivers::dds {

enum class Topic : int { kPose = 0, kOdom = 1, kStatus = 2, kTf = 3, kTfStatic = 4 };
const char* to_string(Topic topic);

struct DdsPublisherStats {
  uint64_t submitted = 0;           // publish() calls
  uint64_t published = 0;           // samples written (all enabled topics written without error)
  uint64_t dropped_queue_full = 0;  // samples dropped because the thread fell behind
  uint64_t write_errors = 0;        // dds_write calls that failed (e.g. timed out after max_blocking_ms)
};

class DdsPosePublisher {
 public:
  // Creates the participant, topics and writers, and starts the publisher thread. Throws DdsError naming the
  // domain or topic when Cyclone refuses; InputError for an invalid config.
  explicit DdsPosePublisher(const DdsConfig& config, bool start_thread = true);
  ~DdsPosePublisher();
  DdsPosePublisher(const DdsPosePublisher&) = delete;
  DdsPosePublisher& operator=(const DdsPosePublisher&) = delete;

  // Queues the sample for the publisher thread; never blocks on DDS. False when a waiting sample was dropped.
  bool publish(const PoseSample& sample);
  // Converts and writes the sample on the calling thread (the publisher thread uses the same function).
  // Returns true when every enabled topic was written.
  bool write_now(const PoseSample& sample);
  // rt/tf_static (publish_tf_static): the one static transform, T_parent_child stamped t_ns. Kept by the writer
  // (transient local) for subscribers that join later; a new call replaces it. False when not enabled or the
  // write failed.
  bool write_static_transform(int64_t t_ns, const SE3d& T_parent_child, const std::string& parent,
                              const std::string& child);

  // Waits until the queue is empty and every matched reliable reader acknowledged what was written, at most
  // `timeout`. True when both happened.
  bool flush(std::chrono::milliseconds timeout);
  // Readers currently matched on a topic (0 for a disabled topic).
  int matched_subscribers(Topic topic) const;
  // Waits until every enabled pose, odom and status topic has at least `count` matched readers, at most `timeout`
  // (tf has readers of its own: every node with a tf listener).
  bool wait_for_subscribers(int count, std::chrono::milliseconds timeout) const;

  DdsPublisherStats stats() const;
  const DdsConfig& config() const { return config_; }

 private:
  void run();

  DdsConfig config_;
  FrameIds frames_;
  Participant participant_;
  std::array<dds_entity_t, 5> writers_{};  // 0 when the topic is disabled; deleted with the participant

  // Bounded ring of waiting samples (allocated once).
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::vector<PoseSample> ring_;
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  bool writing_ = false;
  bool stop_ = false;
  std::thread thread_;

  std::atomic<uint64_t> submitted_{0};
  std::atomic<uint64_t> published_{0};
  std::atomic<uint64_t> dropped_{0};
  std::atomic<uint64_t> write_errors_{0};
};

}  // namespace agvslam::drivers::dds
