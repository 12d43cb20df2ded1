#include "agvslam/drivers/dds/dds_config.h"

#include <cctype>
#include <sstream>

#include "agvslam/core/error.h"

namespace agvslam::drivers::dds {
namespace {

// ROS 2 name tokens: letters, digits, underscores, separated by single '/', not starting with a digit.
bool valid_ros_namespace(const std::string& ns) {
  if (ns.empty() || ns.front() == '/' || ns.back() == '/') return false;
  char prev = '/';
  for (char c : ns) {
    if (c == '/') {
      if (prev == '/') return false;
    } else if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '_') {
      return false;
    } else if (prev == '/' && std::isdigit(static_cast<unsigned char>(c)) != 0) {
      return false;
    }
    prev = c;
  }
  return true;
}

}  // namespace

void DdsConfig::validate(const std::string& source) const {
  if (domain_id < 0 || domain_id > 232) throw InputError(source, "dds.domain_id", "expected an integer in 0..232");
  if (!valid_ros_namespace(topic_namespace)) {
    throw InputError(source, "dds.topic_namespace",
                     "expected a ROS name without leading or trailing '/' (letters, digits, '_', '/'), e.g. agvslam");
  }
  if (map_frame_id.empty()) throw InputError(source, "dds.map_frame_id", "expected a frame name, e.g. map");
  if (odom_frame_id.empty()) throw InputError(source, "dds.odom_frame_id", "expected a frame name, e.g. map or odom");
  if (base_frame_id.empty()) throw InputError(source, "dds.base_frame_id", "expected a frame name, e.g. base_link");
  if (history_depth < 1 || history_depth > 1000) {
    throw InputError(source, "dds.history_depth", "expected an integer in 1..1000");
  }
  if (max_blocking_ms < 0 || max_blocking_ms > 1000) {
    throw InputError(source, "dds.max_blocking_ms", "expected an integer in 0..1000 (ms)");
  }
  if (queue_capacity < 1 || queue_capacity > 1024) {
    throw InputError(source, "dds.queue_capacity", "expected an integer in 1..1024");
  }
  if (!publish_pose && !publish_odom && !publish_status) {
    throw InputError(source, "dds.publish_pose", "expected at least one of publish_pose, publish_odom, publish_status");
  }
}

std::string DdsConfig::describe() const {
  std::ostringstream s;
  s << "dds: domain " << domain_id << ", interface "
    << (!config_uri.empty() ? "(from config_uri)" : network_interface.empty() ? "(cyclone default)" : network_interface)
    << ", topics";
  if (publish_pose) s << ' ' << pose_topic();
  if (publish_odom) s << ' ' << odom_topic();
  if (publish_status) s << ' ' << status_topic();
  s << ", frames " << map_frame_id << "/" << odom_frame_id << " -> " << base_frame_id << ", QoS reliable keep-last "
    << history_depth << " volatile, max_blocking " << max_blocking_ms << " ms, queue " << queue_capacity;
  return s.str();
}

}  // namespace agvslam::drivers::dds
