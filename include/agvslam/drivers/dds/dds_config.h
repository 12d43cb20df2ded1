#pragma once
// Configuration of the DDS pose output (the daemon reads it from its YAML file, section `dds`).

#include <string>

#include "agvslam/core/param_table.h"
#include "agvslam/drivers/dds/dds_security.h"

namespace agvslam::drivers::dds {

struct DdsConfig {
  // DDS domain id; a ROS 2 node sees the topics when its ROS_DOMAIN_ID is the same. 0..232 (ports stay < 65536).
  int domain_id = 0;
  // Network interface Cyclone DDS uses (name such as "eth0", "lo", or an address); empty: Cyclone's own choice
  // (its first multicast-capable interface). Ignored when `config_uri` is set.
  std::string network_interface;
  // A Cyclone DDS configuration (XML text or file:// URI) used instead of the one built from network_interface,
  // for site-specific settings (peers, SHM, ports). Empty: none.
  std::string config_uri;
  // ROS namespace of the topics: /<topic_namespace>/pose -> DDS topic "rt/<topic_namespace>/pose".
  std::string topic_namespace = "agvslam";
  bool publish_pose = true;    // rt/<ns>/pose, geometry_msgs/PoseWithCovarianceStamped
  bool publish_odom = true;    // rt/<ns>/odom, nav_msgs/Odometry
  bool publish_status = true;  // rt/<ns>/status, agvslam_msgs/Status
  // tf2_msgs/TFMessage on rt/tf (ROS 2's global /tf, not namespaced: tf is one tree per robot) while tracking:
  // map -> odom when the daemon integrates wheel odometry (and odom_frame_id is not the map frame), with that
  // odometry's odom -> base_link, else map -> base_link. QoS of tf2_ros's broadcaster: reliable, keep last 100,
  // volatile.
  bool publish_tf = true;
  // rt/tf_static once at start: base_link -> camera_frame_id (the rectified left camera, optical axes: z forward,
  // x right, y down), reliable, keep last 1, transient local (tf2_ros's static broadcaster), so a node that starts
  // later still receives it.
  bool publish_tf_static = true;
  std::string camera_frame_id = "camera_optical_frame";
  // REP-105 frame names. The pose is T_map_base; odometry carries the same pose (header.frame_id = odom_frame_id,
  // `map` by default because the SLAM pose is a map-frame pose that may jump at loop closure) and the body-frame
  // twist (child_frame_id = base_frame_id).
  std::string map_frame_id = "map";
  std::string odom_frame_id = "map";
  std::string base_frame_id = "base_link";
  // ROS 2 default QoS: reliable, keep last `history_depth`, volatile.
  int history_depth = 10;
  // Longest time one DDS write may block when the writer's history is full of unacknowledged samples; the
  // publisher's own thread does the writes, the caller never waits for them.
  int max_blocking_ms = 20;
  // Samples waiting for the publisher thread; when full the oldest is dropped (and counted).
  int queue_capacity = 8;
  // DDS Security credentials (the `dds_security` section; its own table, dds_security_params()).
  DdsSecurityConfig security;

  // Throws InputError(source, "dds.<key>" or "dds_security.<key>", "expected ...") for a value out of range.
  void validate(const std::string& source) const;
  // One line for the start-up echo.
  std::string describe() const;

  std::string pose_topic() const { return "rt/" + topic_namespace + "/pose"; }
  std::string odom_topic() const { return "rt/" + topic_namespace + "/odom"; }
  std::string status_topic() const { return "rt/" + topic_namespace + "/status"; }
  static std::string tf_topic() { return "rt/tf"; }
  static std::string tf_static_topic() { return "rt/tf_static"; }
};

// ROS 2 name tokens (letters, digits, underscores; not starting with a digit) separated by single '/', without a
// leading or trailing '/': a topic namespace such as robot1/slam.
bool is_ros_name(const std::string& name);

// The settings of the `dds` section (every field above, named alike).
const params::Table<DdsConfig>& dds_params();

}  // namespace agvslam::drivers::dds
