#pragma once
// PoseSample -> ROS 2 messages (the C structs idlc generates from drivers/dds/idl/agvslam_ros2.idl), and the
// messages -> JSON lines that agvslam-echo prints. Pure functions: no DDS entity involved.

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "agvslam/drivers/pose_sample.h"
#include "agvslam_ros2.h"  // generated: geometry_msgs_msg_dds__PoseWithCovarianceStamped_ etc.

namespace agvslam::drivers::dds {

using PoseMsg = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;
using OdomMsg = nav_msgs_msg_dds__Odometry_;
using StatusMsg = agvslam_msgs_msg_dds__Status_;
using TransformMsg = geometry_msgs_msg_dds__TransformStamped_;
using TfMsg = tf2_msgs_msg_dds__TFMessage_;

// DDS type names, exactly as rmw_cyclonedds names the ROS types (see the IDL for the sources).
inline constexpr const char* kPoseTypeName = "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
inline constexpr const char* kOdomTypeName = "nav_msgs::msg::dds_::Odometry_";
inline constexpr const char* kStatusTypeName = "agvslam_msgs::msg::dds_::Status_";
inline constexpr const char* kTfTypeName = "tf2_msgs::msg::dds_::TFMessage_";

// Frame names the messages point to (their char* fields borrow these strings: keep them alive while the message
// is in use).
struct FrameIds {
  std::string map = "map";
  std::string odom = "map";
  std::string base = "base_link";
};

// t_ns (UNIX epoch ns) -> builtin_interfaces/Time (floor division: negative times keep 0 <= nanosec < 1e9).
builtin_interfaces_msg_dds__Time_ to_ros_time(int64_t t_ns);
int64_t from_ros_time(const builtin_interfaces_msg_dds__Time_& t);

// Fill a message from a sample. The orientation is the unit quaternion of T_map_base with w >= 0.
void fill_pose_msg(const PoseSample& s, const FrameIds& frames, PoseMsg& out);
void fill_odom_msg(const PoseSample& s, const FrameIds& frames, OdomMsg& out);
void fill_status_msg(const PoseSample& s, const FrameIds& frames, StatusMsg& out);
// One transform: child's pose T_parent_child in parent (tf's convention: it maps child coordinates to parent's),
// stamped t_ns; the rotation with w >= 0. The message borrows both names.
void fill_transform_msg(int64_t t_ns, const SE3d& T_parent_child, const std::string& parent, const std::string& child,
                        TransformMsg& out);
SE3d from_transform_msg(const TransformMsg& m);
// The messages borrow the frame names: a temporary FrameIds would leave them dangling.
void fill_pose_msg(const PoseSample&, FrameIds&&, PoseMsg&) = delete;
void fill_odom_msg(const PoseSample&, FrameIds&&, OdomMsg&) = delete;
void fill_status_msg(const PoseSample&, FrameIds&&, StatusMsg&) = delete;

// JSON objects with the ROS field names ({"header": {"stamp": {"sec":.., "nanosec":..}, "frame_id":..}, ...}).
// Doubles are printed with round-trip precision, so two processes' outputs compare exactly.
nlohmann::json to_json(const PoseMsg& m);
nlohmann::json to_json(const OdomMsg& m);
nlohmann::json to_json(const StatusMsg& m);
nlohmann::json to_json(const TfMsg& m);

}  // namespace agvslam::drivers::dds
