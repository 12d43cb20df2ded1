#pragma once
// A subscriber to the daemon's topics (what agvslam-echo and the tests use): readers with ROS 2 default QoS on
// the chosen topics, a wait set, and typed callbacks with the local receive time.

#include <chrono>
#include <cstdint>
#include <functional>

#include "agvslam/drivers/dds/dds_config.h"
#include "agvslam/drivers/dds/participant.h"
#include "agvslam/drivers/dds/publisher.h"
#include "agvslam/drivers/dds/ros_messages.h"

namespace agvslam::drivers::dds {

struct SubscriberHandlers {
  // recv_t_ns: CLOCK_REALTIME when the sample was taken from the reader (comparable with header.stamp on the
  // same host).
  std::function<void(const PoseMsg&, int64_t recv_t_ns)> on_pose;
  std::function<void(const OdomMsg&, int64_t recv_t_ns)> on_odom;
  std::function<void(const StatusMsg&, int64_t recv_t_ns)> on_status;
  // rt/tf (tf2_ros's listener QoS: reliable, keep last 100, volatile) and rt/tf_static (reliable, keep last 1,
  // transient local: a late subscriber still gets the static transforms).
  std::function<void(const TfMsg&, int64_t recv_t_ns)> on_tf;
  std::function<void(const TfMsg&, int64_t recv_t_ns)> on_tf_static;
};

class DdsPoseSubscriber {
 public:
  // Readers on the topics whose handler is set. Throws DdsError naming the domain/topic on failure.
  DdsPoseSubscriber(const DdsConfig& config, SubscriberHandlers handlers);
  ~DdsPoseSubscriber() = default;
  DdsPoseSubscriber(const DdsPoseSubscriber&) = delete;
  DdsPoseSubscriber& operator=(const DdsPoseSubscriber&) = delete;

  // Waits up to `timeout` for data, then takes everything available and calls the handlers (per topic in the
  // order the samples were written). Returns the number of samples delivered.
  int poll(std::chrono::milliseconds timeout);
  // Writers currently matched on a topic (0 when not subscribed).
  int matched_publishers(Topic topic) const;

 private:
  Participant participant_;
  SubscriberHandlers handlers_;
  std::array<dds_entity_t, 5> readers_{};
  DdsEntity waitset_;
};

// CLOCK_REALTIME now, nanoseconds since the UNIX epoch (the clock of PoseSample::t_ns and of ROS stamps).
int64_t realtime_now_ns();

}  // namespace agvslam::drivers::dds
