// PoseSample -> ROS 2 messages: stamps, quaternion, covariance layout, frames; and the JSON agvslam-echo prints.

#include <gtest/gtest.h>

#include <cmath>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/drivers/dds/dds_config.h"
#include "agvslam/drivers/dds/participant.h"
#include "agvslam/drivers/dds/ros_messages.h"

namespace {

using namespace agvslam::drivers;
using namespace agvslam::drivers::dds;

TEST(RosMessages, TimeSplitsIntoSecondsAndNanoseconds) {
  auto t = to_ros_time(1700000000123456789LL);
  EXPECT_EQ(t.sec, 1700000000);
  EXPECT_EQ(t.nanosec, 123456789U);
  t = to_ros_time(-1);  // floor: -1 ns = -1 s + 999999999 ns
  EXPECT_EQ(t.sec, -1);
  EXPECT_EQ(t.nanosec, 999999999U);
  EXPECT_EQ(from_ros_time(to_ros_time(1700000000123456789LL)), 1700000000123456789LL);
  EXPECT_EQ(from_ros_time(to_ros_time(-1234567891LL)), -1234567891LL);
}

TEST(RosMessages, PoseOdomStatusCarryTheSample) {
  const PoseSample s = synthetic_pose_sample(17, 1700000000500000000LL);
  const FrameIds frames{"map", "odom", "base_link"};
  PoseMsg p{};
  fill_pose_msg(s, frames, p);
  EXPECT_STREQ(p.header.frame_id, "map");
  EXPECT_EQ(from_ros_time(p.header.stamp), s.t_ns);
  const auto& q = p.pose.pose.orientation;
  EXPECT_GE(q.w, 0.0);
  const Eigen::Quaterniond qe(q.w, q.x, q.y, q.z);
  EXPECT_NEAR(qe.norm(), 1.0, 1e-12);
  EXPECT_TRUE(qe.toRotationMatrix().isApprox(s.T_map_base.linear(), 1e-12));
  EXPECT_EQ(p.pose.pose.position.x, s.T_map_base.translation().x());
  EXPECT_EQ(p.pose.pose.position.z, s.T_map_base.translation().z());
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) EXPECT_EQ(p.pose.covariance[r * 6 + c], s.cov_pose(r, c));  // row-major
  }

  OdomMsg o{};
  fill_odom_msg(s, frames, o);
  EXPECT_STREQ(o.header.frame_id, "odom");
  EXPECT_STREQ(o.child_frame_id, "base_link");
  EXPECT_EQ(o.twist.twist.linear.x, s.v_base_mps.x());
  EXPECT_EQ(o.twist.twist.angular.z, s.w_base_radps.z());
  EXPECT_EQ(o.twist.covariance[35], s.cov_twist(5, 5));
  EXPECT_EQ(o.pose.pose.orientation.w, q.w);

  StatusMsg st{};
  fill_status_msg(s, frames, st);
  EXPECT_EQ(st.tracking_state, static_cast<uint8_t>(s.tracking_state));
  EXPECT_EQ(st.frame_index, s.frame_index);
  EXPECT_EQ(st.frames_dropped, s.frames_dropped);
  EXPECT_EQ(st.fps, s.fps);
  EXPECT_EQ(st.dynamic_pixel_fraction, s.dynamic_pixel_fraction);
  EXPECT_NEAR(st.latency_ms, static_cast<double>(s.latency_ns) * 1e-6, 1e-5);
  // Without an odometry input: state off, no ratio.
  EXPECT_EQ(st.odometry_check_state, 0);
  EXPECT_TRUE(std::isnan(st.odometry_distance_ratio));
  PoseSample checked = s;
  checked.odometry_check.state = OdometryCheckState::kDisagrees;
  checked.odometry_check.distance_ratio = 1.25;
  checked.odometry_check.speed_rmse_mps = 0.2;
  checked.odometry_check.heading_difference_deg = -3.5;
  fill_status_msg(checked, frames, st);
  EXPECT_EQ(st.odometry_check_state, 5);
  EXPECT_EQ(st.odometry_distance_ratio, 1.25F);
  EXPECT_EQ(st.odometry_speed_rmse_mps, 0.2F);
  EXPECT_EQ(st.odometry_heading_difference_deg, -3.5F);
  EXPECT_EQ(to_json(st).at("odometry_check_state"), 5);
  // The map the pose is in (a new map after a long loss).
  EXPECT_EQ(st.map_id, 0U);
  checked.map_id = 3;
  fill_status_msg(checked, frames, st);
  EXPECT_EQ(st.map_id, 3U);
  EXPECT_EQ(to_json(st).at("map_id"), 3);
}

TEST(RosMessages, JsonUsesRosFieldNamesAndRoundTripPrecision) {
  const PoseSample s = synthetic_pose_sample(5, 1700000000000000001LL);
  OdomMsg o{};
  const FrameIds frames;  // the message borrows its strings
  fill_odom_msg(s, frames, o);
  const nlohmann::json j = to_json(o);
  EXPECT_EQ(j.at("header").at("stamp").at("nanosec").get<uint32_t>(), 1U);
  EXPECT_EQ(j.at("header").at("frame_id"), "map");
  EXPECT_EQ(j.at("child_frame_id"), "base_link");
  EXPECT_EQ(j.at("pose").at("covariance").size(), 36U);
  // Printed and parsed back, doubles are bit-identical (the DDS tests compare two processes' outputs exactly).
  const nlohmann::json back = nlohmann::json::parse(j.dump());
  EXPECT_EQ(back.at("pose").at("pose").at("position").at("x").get<double>(), o.pose.pose.position.x);
  EXPECT_EQ(back.at("twist").at("twist").at("angular").at("z").get<double>(), o.twist.twist.angular.z);
  EXPECT_EQ(back, j);
}

// Found by tests/fuzz (dds_samples): a received frame_id that is not UTF-8 made agvslam-echo's dump() throw.
TEST(RosMessages, JsonOfStringsThatAreNotUtf8StillDumps) {
  char frame_id[] = "map\xff\xfe";
  char child[] = "base\xc3";
  OdomMsg m{};
  m.header.frame_id = frame_id;
  m.child_frame_id = child;
  const nlohmann::json j = to_json(m);
  EXPECT_EQ(j["header"]["frame_id"], "map\ufffd\ufffd");
  EXPECT_EQ(j["child_frame_id"], "base\ufffd");
  EXPECT_NO_THROW(j.dump());
}

TEST(RosMessages, TypeNamesFollowRmwCyclonedds) {
  EXPECT_STREQ(geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc.m_typename, kPoseTypeName);
  EXPECT_STREQ(nav_msgs_msg_dds__Odometry__desc.m_typename, kOdomTypeName);
  EXPECT_STREQ(agvslam_msgs_msg_dds__Status__desc.m_typename, kStatusTypeName);
  EXPECT_STREQ(kPoseTypeName, "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
  EXPECT_STREQ(kOdomTypeName, "nav_msgs::msg::dds_::Odometry_");
  EXPECT_STREQ(tf2_msgs_msg_dds__TFMessage__desc.m_typename, kTfTypeName);
  EXPECT_STREQ(kTfTypeName, "tf2_msgs::msg::dds_::TFMessage_");
}

TEST(RosMessages, TransformCarriesTheChildPoseInTheParent) {
  const PoseSample s = synthetic_pose_sample(23, 1700000000250000000LL);
  const std::string parent = "map", child = "base_link";
  TransformMsg m{};
  fill_transform_msg(s.t_ns, s.T_map_base, parent, child, m);
  EXPECT_STREQ(m.header.frame_id, "map");
  EXPECT_STREQ(m.child_frame_id, "base_link");
  EXPECT_EQ(from_ros_time(m.header.stamp), s.t_ns);
  EXPECT_GE(m.transform.rotation.w, 0.0);
  EXPECT_EQ(m.transform.translation.x, s.T_map_base.translation().x());
  EXPECT_TRUE(from_transform_msg(m).isApprox(s.T_map_base, 1e-12));
  TfMsg tf{};
  tf.transforms._length = tf.transforms._maximum = 1;
  tf.transforms._buffer = &m;
  const nlohmann::json j = to_json(tf);
  ASSERT_EQ(j.at("transforms").size(), 1U);
  EXPECT_EQ(j.at("transforms")[0].at("child_frame_id"), "base_link");
  EXPECT_EQ(j.at("transforms")[0].at("transform").at("rotation").at("w").get<double>(), m.transform.rotation.w);
}

// The ROS 2 package shipped for the status type (drivers/dds/ros2/agvslam_msgs/msg/Status.msg) must declare the
// same fields, in the same order, with the same types, as the IDL the daemon publishes with.
TEST(RosMessages, StatusMsgMatchesTheIdl) {
  const std::string root = AGVSLAM_SOURCE_DIR;
  std::ifstream msg(root + "/drivers/dds/ros2/agvslam_msgs/msg/Status.msg");
  std::ifstream idl(root + "/drivers/dds/idl/agvslam_ros2.idl");
  ASSERT_TRUE(msg && idl);
  const std::map<std::string, std::string> ros_to_idl = {{"std_msgs/Header", "std_msgs::msg::dds_::Header_"},
                                                         {"uint8", "uint8"},
                                                         {"uint64", "unsigned long long"},
                                                         {"uint32", "unsigned long"},
                                                         {"float32", "float"}};
  std::vector<std::string> from_msg, from_idl;
  std::string line;
  while (std::getline(msg, line)) {
    line = line.substr(0, line.find('#'));
    if (line.find_first_not_of(" \t") == std::string::npos || line.find('=') != std::string::npos) continue;
    std::istringstream in(line);
    std::string type, name;
    in >> type >> name;
    ASSERT_TRUE(ros_to_idl.count(type)) << type;
    from_msg.push_back(ros_to_idl.at(type) + " " + name);
  }
  bool inside = false;
  while (std::getline(idl, line)) {
    if (line.find("struct Status_") != std::string::npos) {
      inside = true;
      continue;
    }
    if (!inside) continue;
    if (line.find("};") != std::string::npos) break;
    line = line.substr(0, line.find("//"));
    const auto semi = line.find(';');
    if (semi == std::string::npos) continue;
    line = line.substr(0, semi);
    const auto b = line.find_first_not_of(' ');
    const auto sp = line.find_last_of(' ');
    from_idl.push_back(line.substr(b, sp - b) + " " + line.substr(sp + 1));
  }
  EXPECT_EQ(from_msg, from_idl);
  EXPECT_EQ(from_idl.size(), 13U);
}

TEST(DdsConfig, ValidatesDescribesAndBuildsCycloneXml) {
  DdsConfig c;
  EXPECT_NO_THROW(c.validate("agvslamd.yaml"));
  EXPECT_EQ(c.pose_topic(), "rt/agvslam/pose");
  EXPECT_EQ(c.odom_topic(), "rt/agvslam/odom");
  EXPECT_EQ(c.status_topic(), "rt/agvslam/status");
  EXPECT_NE(c.describe().find("history_depth=10"), std::string::npos) << c.describe();
  EXPECT_NE(c.describe().find("topics rt/agvslam/pose rt/agvslam/odom rt/agvslam/status"), std::string::npos)
      << c.describe();
  EXPECT_EQ(cyclone_config_xml(c), "");
  c.network_interface = "lo";
  EXPECT_NE(cyclone_config_xml(c).find("<NetworkInterface name=\"lo\"/>"), std::string::npos);
  c.network_interface = "192.168.1.5";
  EXPECT_NE(cyclone_config_xml(c).find("address=\"192.168.1.5\""), std::string::npos);
  c.config_uri = "file:///etc/agvslam/cyclonedds.xml";
  EXPECT_EQ(cyclone_config_xml(c), c.config_uri);

  for (auto bad : {std::make_pair(std::string("domain_id"), 233), std::make_pair(std::string("history_depth"), 0),
                   std::make_pair(std::string("queue_capacity"), 0)}) {
    DdsConfig d;
    if (bad.first == "domain_id") d.domain_id = bad.second;
    if (bad.first == "history_depth") d.history_depth = bad.second;
    if (bad.first == "queue_capacity") d.queue_capacity = bad.second;
    try {
      d.validate("agvslamd.yaml");
      ADD_FAILURE() << bad.first;
    } catch (const agvslam::InputError& e) {
      EXPECT_EQ(e.where(), "dds." + bad.first);
    }
  }
  for (const char* ns : {"", "/agvslam", "agvslam/", "a//b", "9lives", "a-b"}) {
    DdsConfig d;
    d.topic_namespace = ns;
    EXPECT_THROW(d.validate("x"), agvslam::InputError) << ns;
  }
  DdsConfig ok;
  ok.topic_namespace = "fleet/agv_07";
  EXPECT_NO_THROW(ok.validate("x"));
}

}  // namespace
