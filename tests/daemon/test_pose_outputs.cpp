// The daemon's outputs in one process (DDS pinned to lo, a domain of this test's own): a tracking sample goes out
// on pose, odom and status; a lost sample and a heartbeat only on status (never a pose); the trajectory file
// holds the tracking samples; the JSON log holds every sample with its SI values; an absent CAN interface is
// retried, not fatal.
#include "agvslam/daemon/pose_outputs.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "agvslam/core/error.h"
#include "agvslam/daemon/pose_builder.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "agvslam/drivers/pose_sample_json.h"
#include "agvslam/io/trajectory_io.h"
#include "daemon_test_util.h"

namespace agvslam::daemon {
namespace {

namespace dds = drivers::dds;

TEST(PoseOutputs, PoseOnlyWhileTrackingStatusAlwaysFilesAsPublished) {
  const std::string dir = test::make_temp_dir("agvslamd-outputs");
  DaemonConfig c;
  c.path = "test.yaml";
  c.outputs.dds_enabled = true;
  c.outputs.dds.domain_id = 100 + static_cast<int>(getpid() % 100);
  c.outputs.dds.network_interface = "lo";
  c.outputs.dds.topic_namespace = "agvslamd_test";
  c.outputs.can_enabled = true;
  c.outputs.can.interface = "agvnocan0";  // does not exist: retried with back-off, frames counted as dropped
  c.trajectory.file = dir + "/t.tum";
  c.log.pose_log = dir + "/poses.jsonl";
  PoseOutputs out(c);

  int poses = 0, odoms = 0;
  std::vector<int> status_states;
  dds::SubscriberHandlers h;
  h.on_pose = [&](const dds::PoseMsg&, int64_t) { ++poses; };
  h.on_odom = [&](const dds::OdomMsg&, int64_t) { ++odoms; };
  h.on_status = [&](const dds::StatusMsg& m, int64_t) { status_states.push_back(m.tracking_state); };
  dds::DdsPoseSubscriber sub(c.outputs.dds, h);
  ASSERT_TRUE(out.wait_for_subscribers(1, std::chrono::seconds(10)));

  const int64_t t0 = dds::realtime_now_ns() - 1000000000LL;  // captured a second ago
  std::vector<drivers::TrackingState> states = {drivers::TrackingState::kNotInitialized,
                                                drivers::TrackingState::kTracking, drivers::TrackingState::kTracking,
                                                drivers::TrackingState::kLost, drivers::TrackingState::kTracking};
  for (std::size_t i = 0; i < states.size(); ++i) {
    OutputItem item;
    item.sample = drivers::synthetic_pose_sample(i, t0 + static_cast<int64_t>(i) * 50000000LL);
    item.sample.tracking_state = states[i];
    item.source_index = static_cast<int64_t>(i);
    out.publish(item);
    EXPECT_GE(item.sample.latency_ns, 0);  // stamped at hand-over
    EXPECT_LT(item.sample.latency_ns, 60LL * 1000000000LL);
  }
  OutputItem hb;
  hb.heartbeat = true;
  PoseSampleBuilder::build_heartbeat(dds::realtime_now_ns(), true, hb.sample);
  out.publish(hb);
  out.flush(std::chrono::seconds(5));
  for (int k = 0; k < 100 && status_states.size() < 6; ++k) sub.poll(std::chrono::milliseconds(50));

  EXPECT_EQ(poses, 3);
  EXPECT_EQ(odoms, 3);
  EXPECT_EQ(status_states, (std::vector<int>{0, 1, 1, 3, 1, 3}));
  const OutputStats st = out.stats();
  EXPECT_EQ(st.samples, 6U);
  EXPECT_EQ(st.tracking_samples, 3U);
  EXPECT_EQ(st.heartbeats, 1U);
  EXPECT_TRUE(st.can_enabled);
  EXPECT_FALSE(st.can.open);
  EXPECT_EQ(st.can.frames_sent, 0U);

  // Trajectory: the three tracking samples, exactly their poses.
  const Trajectory traj = io::read_tum(c.trajectory.file);
  ASSERT_EQ(traj.size(), 3U);
  EXPECT_EQ(traj[0].t_ns, t0 + 50000000LL);
  const auto s1 = drivers::synthetic_pose_sample(1, 0);
  EXPECT_TRUE(traj[0].T_w_c.isApprox(s1.T_map_base, 1e-9));
  // JSON log: every sample, with the SI values and what CAN did.
  const auto lines = test::read_json_lines(c.log.pose_log);
  ASSERT_EQ(lines.size(), 6U);
  EXPECT_EQ(lines[3].at("sample").at("tracking_state"), 3);
  EXPECT_EQ(lines[3].at("dds").at("pose"), false);
  EXPECT_EQ(lines[1].at("dds").at("pose"), true);
  EXPECT_EQ(lines[5].at("heartbeat"), true);
  EXPECT_EQ(lines[2].at("source_index"), 2);
  EXPECT_EQ(lines[2].at("can").at("sent"), false);
  EXPECT_FALSE(lines[1].contains("odometry_check"));  // no odometry input: the log is as it was
  EXPECT_FALSE(st.odometry_enabled);
  EXPECT_EQ(lines[1].at("sample"), drivers::pose_sample_to_json([&] {
              auto s = drivers::synthetic_pose_sample(1, t0 + 50000000LL);
              s.tracking_state = drivers::TrackingState::kTracking;
              s.latency_ns = lines[1].at("sample").at("latency_ns").get<int64_t>();
              return s;
            }()));
  std::filesystem::remove_all(dir);
}

// tf: the static camera extrinsic reaches a subscriber that joins after it was written (transient local), and
// every tracking sample's pose goes out as map -> base_link on rt/tf, with ROS 2's type name.
TEST(PoseOutputs, TfStaticReachesALateSubscriberAndTfCarriesTheTrackingPoses) {
  DaemonConfig c;
  c.path = "test.yaml";
  c.outputs.dds_enabled = true;
  c.outputs.dds.domain_id = 100 + static_cast<int>((getpid() + 25) % 100);
  c.outputs.dds.network_interface = "lo";
  c.outputs.dds.topic_namespace = "agvslamd_tf_test";
  c.outputs.dds.map_frame_id = "map_a";
  c.outputs.dds.base_frame_id = "base_a";
  c.outputs.dds.camera_frame_id = "camera_a";
  const SE3d T_base_cam = make_se3(Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5), Eigen::Vector3d(0.3, -0.05, 0.5));
  PoseOutputs out(c, T_base_cam);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the static transform is written before anyone reads

  std::vector<SE3d> statics, poses;
  std::vector<std::string> static_frames, pose_frames;
  dds::SubscriberHandlers h;
  h.on_tf_static = [&](const dds::TfMsg& m, int64_t) {
    ASSERT_EQ(m.transforms._length, 1U);
    statics.push_back(dds::from_transform_msg(m.transforms._buffer[0]));
    static_frames.push_back(std::string(m.transforms._buffer[0].header.frame_id) + ">" +
                            m.transforms._buffer[0].child_frame_id);
  };
  h.on_tf = [&](const dds::TfMsg& m, int64_t) {
    ASSERT_EQ(m.transforms._length, 1U);
    poses.push_back(dds::from_transform_msg(m.transforms._buffer[0]));
    pose_frames.push_back(std::string(m.transforms._buffer[0].header.frame_id) + ">" +
                          m.transforms._buffer[0].child_frame_id);
  };
  dds::DdsPoseSubscriber sub(c.outputs.dds, h);
  for (int k = 0; k < 200 && sub.matched_publishers(dds::Topic::kTf) < 1; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(sub.matched_publishers(dds::Topic::kTf), 1);
  for (int k = 0; k < 100 && statics.empty(); ++k) sub.poll(std::chrono::milliseconds(50));
  ASSERT_EQ(statics.size(), 1U);
  EXPECT_EQ(static_frames[0], "base_a>camera_a");
  EXPECT_TRUE(statics[0].isApprox(T_base_cam, 1e-12));

  const int64_t t0 = dds::realtime_now_ns();
  std::vector<SE3d> tracked;
  for (uint64_t i = 0; i < 6; ++i) {
    OutputItem item;
    item.sample = drivers::synthetic_pose_sample(i, t0 + static_cast<int64_t>(i) * 50000000LL);
    item.sample.tracking_state = i == 3 ? drivers::TrackingState::kLost : drivers::TrackingState::kTracking;
    if (i != 3) tracked.push_back(item.sample.T_map_base);
    out.publish(item);
  }
  out.flush(std::chrono::seconds(5));
  for (int k = 0; k < 100 && poses.size() < tracked.size(); ++k) sub.poll(std::chrono::milliseconds(50));
  ASSERT_EQ(poses.size(), tracked.size());  // never a transform for a lost frame
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_EQ(pose_frames[k], "map_a>base_a");
    EXPECT_TRUE(poses[k].isApprox(tracked[k], 1e-12)) << k;
  }
}

// With DDS Security the daemon's two publishers (status; pose and odometry) use the agvslamd enclave of a keystore
// from deploy/make-keystore.sh; agvslam-echo with the reader enclave's credentials receives what they publish. The
// reader runs in another process: in this process's domain Cyclone 0.10 refuses a reader with other credentials.
TEST(PoseOutputs, WithDdsSecurityAnAuthenticatedReaderReceivesPoseOdomAndStatus) {
  const std::string dir = test::make_temp_dir("agvslamd-outputs-security");
  std::string out_text;
  ASSERT_EQ(test::run_command(std::string(AGVSLAM_SOURCE_DIR) + "/deploy/make-keystore.sh " + dir + "/ks", &out_text),
            0)
      << out_text;
  DaemonConfig c;
  c.path = "test.yaml";
  c.outputs.dds_enabled = true;
  c.outputs.dds.domain_id = 100 + static_cast<int>((getpid() + 50) % 100);
  c.outputs.dds.network_interface = "lo";
  c.outputs.dds.security.enabled = true;
  c.outputs.dds.security.keystore = dir + "/ks";
  c.outputs.dds.security.enclave = "/agvslam/agvslamd";
  c.outputs.can_enabled = false;
  test::ChildProcess echo({test::tool_path("agvslam-echo"), "--json", "--interface", "lo", "--domain",
                           std::to_string(c.outputs.dds.domain_id), "--keystore", dir + "/ks", "--enclave",
                           "/agvslam/reader", "--count", "9", "--timeout", "30"},
                          dir + "/echo.jsonl", dir + "/echo.err");
  ASSERT_TRUE(echo.started());
  PoseOutputs out(c);
  ASSERT_TRUE(out.wait_for_subscribers(1, std::chrono::seconds(20))) << test::read_text(dir + "/echo.err");
  for (std::size_t i = 0; i < 3; ++i) {
    OutputItem item;
    item.sample = drivers::synthetic_pose_sample(i, dds::realtime_now_ns());
    item.sample.tracking_state = drivers::TrackingState::kTracking;
    out.publish(item);
  }
  out.flush(std::chrono::seconds(5));
  ASSERT_EQ(echo.wait(std::chrono::seconds(30)), 0) << test::read_text(dir + "/echo.err");
  std::map<std::string, int> per_topic;
  for (const auto& line : test::read_json_lines(dir + "/echo.jsonl")) {
    if (line.contains("topic")) ++per_topic[line.at("topic").get<std::string>()];
  }
  EXPECT_EQ(per_topic, (std::map<std::string, int>{{"odom", 3}, {"pose", 3}, {"status", 3}}));
  std::filesystem::remove_all(dir);
}

// With odometry.source can and no odometry on the bus (here: no bus at all), every sample says so, the JSON log
// carries the check, and nothing waits for the odometry.
TEST(PoseOutputs, OdometryCheckWithoutOdometryReportsNoOdometry) {
  const std::string dir = test::make_temp_dir("agvslamd-outputs-odometry");
  DaemonConfig c;
  c.path = "test.yaml";
  c.outputs.dds_enabled = false;
  c.outputs.can_enabled = true;
  c.outputs.can.interface = "agvnocan0";
  c.odometry.source = OdometrySource::kCan;
  c.odometry.can.dbc = std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc";
  c.log.pose_log = dir + "/poses.jsonl";
  PoseOutputs out(c);
  const int64_t t0 = dds::realtime_now_ns();
  for (std::size_t i = 0; i < 3; ++i) {
    OutputItem item;
    item.sample = drivers::synthetic_pose_sample(i, t0 + static_cast<int64_t>(i) * 50000000LL);
    item.sample.tracking_state = drivers::TrackingState::kTracking;
    out.publish(item);
    EXPECT_EQ(item.sample.odometry_check.state, drivers::OdometryCheckState::kNoOdometry);
  }
  const OutputStats st = out.stats();
  EXPECT_TRUE(st.odometry_enabled);
  EXPECT_EQ(st.odometry_samples, 0U);
  EXPECT_EQ(st.odometry_check.state, drivers::OdometryCheckState::kNoOdometry);
  const auto lines = test::read_json_lines(c.log.pose_log);
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(lines[2].at("odometry_check").at("state"), "no_odometry");
  EXPECT_TRUE(lines[2].at("odometry_check").at("distance_ratio").is_null());  // NaN: not available
  std::filesystem::remove_all(dir);
}

TEST(PoseOutputs, AnUnwritableFileIsAnInputErrorNamingTheField) {
  DaemonConfig c;
  c.path = "test.yaml";
  c.outputs.dds_enabled = false;
  c.trajectory.file = "/nonexistent-dir/t.tum";
  try {
    PoseOutputs out(c);
    ADD_FAILURE() << "opened " << c.trajectory.file;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("test.yaml: trajectory.file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace agvslam::daemon
