#include "agvslam/drivers/dds/dds_config.h"

#include <cctype>

namespace agvslam::drivers::dds {

bool is_ros_name(const std::string& ns) {
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

const params::Table<DdsConfig>& dds_params() {
  using params::Range;
  using params::Text;
  static const params::Table<DdsConfig> table =
      params::Table<DdsConfig>(
          "dds",
          {
              {"domain_id", &DdsConfig::domain_id, Range::closed(0, 232), "",
               "ROS_DOMAIN_ID; higher ids give ports >= 65536"},
              {"network_interface", &DdsConfig::network_interface, Text::any(), "\"\": Cyclone DDS's own choice"},
              {"config_uri", &DdsConfig::config_uri, Text::any(), "Cyclone DDS XML or a file:// URI"},
              {"topic_namespace", &DdsConfig::topic_namespace, Text::non_empty()},
              {"publish_pose", &DdsConfig::publish_pose},
              {"publish_odom", &DdsConfig::publish_odom},
              {"publish_status", &DdsConfig::publish_status},
              {"publish_tf", &DdsConfig::publish_tf},
              {"publish_tf_static", &DdsConfig::publish_tf_static},
              {"camera_frame_id", &DdsConfig::camera_frame_id, Text::non_empty(), "a frame name, e.g. camera_optical_frame"},
              {"map_frame_id", &DdsConfig::map_frame_id, Text::non_empty(), "a frame name, e.g. map"},
              {"odom_frame_id", &DdsConfig::odom_frame_id, Text::non_empty(), "a frame name, e.g. map or odom"},
              {"base_frame_id", &DdsConfig::base_frame_id, Text::non_empty(), "a frame name, e.g. base_link"},
              {"history_depth", &DdsConfig::history_depth, Range::closed(1, 1000), "samples"},
              {"max_blocking_ms", &DdsConfig::max_blocking_ms, Range::closed(0, 1000), "ms"},
              {"queue_capacity", &DdsConfig::queue_capacity, Range::closed(1, 1024), "samples"},
          })
          .check(
              "topic_namespace", [](const DdsConfig& c) { return is_ros_name(c.topic_namespace); },
              "a ROS name without leading or trailing '/' (letters, digits, '_', '/'), e.g. agvslam")
          .check(
              "publish_pose",
              [](const DdsConfig& c) {
                return c.publish_pose || c.publish_odom || c.publish_status || c.publish_tf || c.publish_tf_static;
              },
              "at least one of publish_pose, publish_odom, publish_status, publish_tf, publish_tf_static")
          .summary([](const DdsConfig& c) {
            std::string topics;
            if (c.publish_pose) topics += " " + c.pose_topic();
            if (c.publish_odom) topics += " " + c.odom_topic();
            if (c.publish_status) topics += " " + c.status_topic();
            if (c.publish_tf) topics += " " + DdsConfig::tf_topic();
            if (c.publish_tf_static) topics += " " + DdsConfig::tf_static_topic();
            return "topics" + topics;
          });
  return table;
}

void DdsConfig::validate(const std::string& source) const {
  dds_params().validate(source, *this);
  security.validate(source);
}

std::string DdsConfig::describe() const { return dds_params().describe(*this); }

}  // namespace agvslam::drivers::dds
