#include "agvslam/drivers/dds/ros_messages.h"

#include <cmath>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace agvslam::drivers::dds {
namespace {

constexpr int64_t kNsPerS = 1000000000;

// The message structs hold `char*` for strings; DDS only reads them on write.
char* borrow(const std::string& s) { return const_cast<char*>(s.c_str()); }

void fill_header(int64_t t_ns, const std::string& frame_id, std_msgs_msg_dds__Header_& h) {
  h.stamp = to_ros_time(t_ns);
  h.frame_id = borrow(frame_id);
}

void fill_quaternion(const Eigen::Matrix3d& R, geometry_msgs_msg_dds__Quaternion_& out) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  out.x = q.x();
  out.y = q.y();
  out.z = q.z();
  out.w = q.w();
}

void fill_pose_with_cov(const PoseSample& s, geometry_msgs_msg_dds__PoseWithCovariance_& out) {
  const Eigen::Vector3d& t = s.T_map_base.translation();
  out.pose.position.x = t.x();
  out.pose.position.y = t.y();
  out.pose.position.z = t.z();
  fill_quaternion(s.T_map_base.linear(), out.pose.orientation);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) out.covariance[r * 6 + c] = s.cov_pose(r, c);
  }
}

// A received string field for JSON: bytes that are not UTF-8 (a faulty or forged sample) become U+FFFD, as
// nlohmann's replace handler writes them, so that dumping the message cannot throw.
std::string utf8_text(const char* s) {
  if (s == nullptr) return "";
  const nlohmann::json text = std::string(s);
  return nlohmann::json::parse(text.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)).get<std::string>();
}

nlohmann::json header_json(const std_msgs_msg_dds__Header_& h) {
  return {{"stamp", {{"sec", h.stamp.sec}, {"nanosec", h.stamp.nanosec}}}, {"frame_id", utf8_text(h.frame_id)}};
}

nlohmann::json cov_json(const double (&c)[36]) {
  nlohmann::json a = nlohmann::json::array();
  for (double v : c) a.push_back(v);
  return a;
}

nlohmann::json pose_with_cov_json(const geometry_msgs_msg_dds__PoseWithCovariance_& p) {
  const auto& pos = p.pose.position;
  const auto& q = p.pose.orientation;
  return {{"pose",
           {{"position", {{"x", pos.x}, {"y", pos.y}, {"z", pos.z}}},
            {"orientation", {{"x", q.x}, {"y", q.y}, {"z", q.z}, {"w", q.w}}}}},
          {"covariance", cov_json(p.covariance)}};
}

}  // namespace

builtin_interfaces_msg_dds__Time_ to_ros_time(int64_t t_ns) {
  int64_t sec = t_ns / kNsPerS;
  int64_t nsec = t_ns % kNsPerS;
  if (nsec < 0) {
    nsec += kNsPerS;
    sec -= 1;
  }
  builtin_interfaces_msg_dds__Time_ t{};
  t.sec = static_cast<int32_t>(sec);
  t.nanosec = static_cast<uint32_t>(nsec);
  return t;
}

int64_t from_ros_time(const builtin_interfaces_msg_dds__Time_& t) {
  return static_cast<int64_t>(t.sec) * kNsPerS + static_cast<int64_t>(t.nanosec);
}

void fill_pose_msg(const PoseSample& s, const FrameIds& frames, PoseMsg& out) {
  fill_header(s.t_ns, frames.map, out.header);
  fill_pose_with_cov(s, out.pose);
}

void fill_odom_msg(const PoseSample& s, const FrameIds& frames, OdomMsg& out) {
  fill_header(s.t_ns, frames.odom, out.header);
  out.child_frame_id = borrow(frames.base);
  fill_pose_with_cov(s, out.pose);
  auto& tw = out.twist.twist;
  tw.linear.x = s.v_base_mps.x();
  tw.linear.y = s.v_base_mps.y();
  tw.linear.z = s.v_base_mps.z();
  tw.angular.x = s.w_base_radps.x();
  tw.angular.y = s.w_base_radps.y();
  tw.angular.z = s.w_base_radps.z();
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) out.twist.covariance[r * 6 + c] = s.cov_twist(r, c);
  }
}

void fill_status_msg(const PoseSample& s, const FrameIds& frames, StatusMsg& out) {
  fill_header(s.t_ns, frames.map, out.header);
  out.tracking_state = static_cast<uint8_t>(s.tracking_state);
  out.frame_index = s.frame_index;
  out.frames_processed = s.frames_processed;
  out.frames_dropped = s.frames_dropped;
  out.fps = s.fps;
  out.dynamic_pixel_fraction = s.dynamic_pixel_fraction;
  out.latency_ms = static_cast<float>(static_cast<double>(s.latency_ns) * 1e-6);
  out.odometry_check_state = static_cast<uint8_t>(s.odometry_check.state);
  out.odometry_distance_ratio = static_cast<float>(s.odometry_check.distance_ratio);
  out.odometry_speed_rmse_mps = static_cast<float>(s.odometry_check.speed_rmse_mps);
  out.odometry_heading_difference_deg = static_cast<float>(s.odometry_check.heading_difference_deg);
  out.map_id = s.map_id;
}

void fill_transform_msg(int64_t t_ns, const SE3d& T_parent_child, const std::string& parent, const std::string& child,
                        TransformMsg& out) {
  fill_header(t_ns, parent, out.header);
  out.child_frame_id = borrow(child);
  const Eigen::Vector3d& t = T_parent_child.translation();
  out.transform.translation.x = t.x();
  out.transform.translation.y = t.y();
  out.transform.translation.z = t.z();
  fill_quaternion(T_parent_child.linear(), out.transform.rotation);
}

SE3d from_transform_msg(const TransformMsg& m) {
  const auto& q = m.transform.rotation;
  const auto& t = m.transform.translation;
  return make_se3(Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized(), Eigen::Vector3d(t.x, t.y, t.z));
}

nlohmann::json to_json(const TfMsg& m) {
  nlohmann::json transforms = nlohmann::json::array();
  for (uint32_t i = 0; i < m.transforms._length; ++i) {
    const TransformMsg& tr = m.transforms._buffer[i];
    const auto& t = tr.transform.translation;
    const auto& q = tr.transform.rotation;
    transforms.push_back({{"header", header_json(tr.header)},
                          {"child_frame_id", tr.child_frame_id != nullptr ? tr.child_frame_id : ""},
                          {"transform",
                           {{"translation", {{"x", t.x}, {"y", t.y}, {"z", t.z}}},
                            {"rotation", {{"x", q.x}, {"y", q.y}, {"z", q.z}, {"w", q.w}}}}}});
  }
  return {{"transforms", transforms}};
}

nlohmann::json to_json(const PoseMsg& m) {
  return {{"header", header_json(m.header)}, {"pose", pose_with_cov_json(m.pose)}};
}

nlohmann::json to_json(const OdomMsg& m) {
  const auto& tw = m.twist.twist;
  return {{"header", header_json(m.header)},
          {"child_frame_id", utf8_text(m.child_frame_id)},
          {"pose", pose_with_cov_json(m.pose)},
          {"twist",
           {{"twist",
             {{"linear", {{"x", tw.linear.x}, {"y", tw.linear.y}, {"z", tw.linear.z}}},
              {"angular", {{"x", tw.angular.x}, {"y", tw.angular.y}, {"z", tw.angular.z}}}}},
            {"covariance", cov_json(m.twist.covariance)}}}};
}

nlohmann::json to_json(const StatusMsg& m) {
  return {{"header", header_json(m.header)},
          {"tracking_state", m.tracking_state},
          {"frame_index", m.frame_index},
          {"frames_processed", m.frames_processed},
          {"frames_dropped", m.frames_dropped},
          {"fps", m.fps},
          {"dynamic_pixel_fraction", m.dynamic_pixel_fraction},
          {"latency_ms", m.latency_ms},
          {"odometry_check_state", m.odometry_check_state},
          // NaN (no ratio) as null, so that two JSON copies of one message compare equal.
          {"odometry_distance_ratio",
           std::isnan(m.odometry_distance_ratio) ? nlohmann::json() : nlohmann::json(m.odometry_distance_ratio)},
          {"odometry_speed_rmse_mps", m.odometry_speed_rmse_mps},
          {"odometry_heading_difference_deg", m.odometry_heading_difference_deg},
          {"map_id", m.map_id}};
}

}  // namespace agvslam::drivers::dds
