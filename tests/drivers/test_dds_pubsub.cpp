// DDS pose output end to end.
//  - In one process: DdsPosePublisher -> Cyclone DDS (pinned to lo, a domain of its own) -> DdsPoseSubscriber.
//  - Two processes in a private network namespace (unshare -n, lo up): agvslam-pose-replay publishes, agvslam-echo
//    subscribes; every sample arrives, in order, with values identical to what was published. Skips with a
//    message where unshare -n is not permitted (fails under CI=true).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "agvslam/drivers/dds/publisher.h"
#include "agvslam/drivers/dds/subscriber.h"
#include "common/test_data.h"
#include "dds_test_util.h"

namespace {

using namespace agvslam::drivers;
using namespace agvslam::drivers::dds;
using agvslam::make_se3;
using agvslam::SE3d;
using agvslam::test::read_json_lines;
namespace fs = std::filesystem;

// A domain id of this process's own, so concurrent test runs on one host do not meet.
int private_domain() { return 20 + static_cast<int>(getpid() % 200); }

TEST(DdsPubSub, InProcessEverySampleArrivesInOrderWithExactValues) {
  DdsConfig cfg;
  cfg.domain_id = private_domain();
  cfg.network_interface = "lo";
  cfg.topic_namespace = "agvslam_test";
  DdsPosePublisher pub(cfg);

  std::vector<nlohmann::json> got_pose, got_odom, got_status;
  SubscriberHandlers h;
  h.on_pose = [&](const PoseMsg& m, int64_t) { got_pose.push_back(to_json(m)); };
  h.on_odom = [&](const OdomMsg& m, int64_t) { got_odom.push_back(to_json(m)); };
  h.on_status = [&](const StatusMsg& m, int64_t) { got_status.push_back(to_json(m)); };
  DdsPoseSubscriber sub(cfg, h);
  ASSERT_TRUE(pub.wait_for_subscribers(1, std::chrono::seconds(10)));

  const int n = 60;
  const FrameIds frames;
  std::vector<nlohmann::json> want_pose, want_odom, want_status;
  for (int i = 0; i < n; ++i) {
    const PoseSample s = synthetic_pose_sample(static_cast<uint64_t>(i), 1700000000000000000LL + i * 50000000LL);
    PoseMsg p{};
    OdomMsg o{};
    StatusMsg st{};
    fill_pose_msg(s, frames, p);
    fill_odom_msg(s, frames, o);
    fill_status_msg(s, frames, st);
    want_pose.push_back(to_json(p));
    want_odom.push_back(to_json(o));
    want_status.push_back(to_json(st));
    pub.publish(s);
    // Keep within the reliable keep-last-10 history: let the subscriber take as we go.
    sub.poll(std::chrono::milliseconds(0));
    if (i % 5 == 4) {
      ASSERT_TRUE(pub.flush(std::chrono::seconds(5)));
    }
  }
  ASSERT_TRUE(pub.flush(std::chrono::seconds(10)));
  // The three topics are delivered independently: wait until each has every sample (under load the status topic
  // can be complete while the last poses are still in flight).
  auto complete = [&] {
    return static_cast<int>(got_pose.size()) >= n && static_cast<int>(got_odom.size()) >= n &&
           static_cast<int>(got_status.size()) >= n;
  };
  for (int k = 0; k < 100 && !complete(); ++k) sub.poll(std::chrono::milliseconds(100));
  EXPECT_EQ(pub.stats().published, static_cast<uint64_t>(n));
  EXPECT_EQ(pub.stats().dropped_queue_full, 0U);
  EXPECT_EQ(got_pose, want_pose);
  EXPECT_EQ(got_odom, want_odom);
  EXPECT_EQ(got_status, want_status);
  EXPECT_EQ(sub.matched_publishers(Topic::kPose), 1);
}

// With an odometry pose in the sample, rt/tf carries map -> odom and odom -> base_link, which chain to the
// published pose; without one, map -> base_link alone.
TEST(DdsPubSub, TfChainsMapOdomBaseToThePoseWhenOdometryIsCurrent) {
  DdsConfig cfg;
  cfg.domain_id = private_domain();
  cfg.network_interface = "lo";
  cfg.topic_namespace = "agvslam_tf";
  cfg.publish_pose = cfg.publish_odom = cfg.publish_status = cfg.publish_tf_static = false;
  cfg.odom_frame_id = "odom";
  DdsPosePublisher pub(cfg);
  std::vector<std::vector<std::pair<std::string, SE3d>>> got;
  SubscriberHandlers h;
  h.on_tf = [&](const TfMsg& m, int64_t) {
    std::vector<std::pair<std::string, SE3d>> transforms;
    for (uint32_t i = 0; i < m.transforms._length; ++i) {
      const TransformMsg& t = m.transforms._buffer[i];
      transforms.emplace_back(std::string(t.header.frame_id) + ">" + t.child_frame_id, from_transform_msg(t));
    }
    got.push_back(transforms);
  };
  DdsPoseSubscriber sub(cfg, h);
  for (int k = 0; k < 200 && pub.matched_subscribers(Topic::kTf) < 1; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(pub.matched_subscribers(Topic::kTf), 1);
  PoseSample with_odom = synthetic_pose_sample(9, 1700000000000000000LL);
  with_odom.odom_valid = true;
  with_odom.T_odom_base =
      make_se3(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(4.0, -1.5, 0.0));
  PoseSample without = synthetic_pose_sample(10, 1700000000050000000LL);
  ASSERT_TRUE(pub.write_now(with_odom));
  ASSERT_TRUE(pub.write_now(without));
  ASSERT_TRUE(pub.flush(std::chrono::seconds(5)));
  for (int k = 0; k < 100 && got.size() < 2; ++k) sub.poll(std::chrono::milliseconds(50));
  ASSERT_EQ(got.size(), 2U);
  ASSERT_EQ(got[0].size(), 2U);
  EXPECT_EQ(got[0][0].first, "map>odom");
  EXPECT_EQ(got[0][1].first, "odom>base_link");
  EXPECT_TRUE(got[0][1].second.isApprox(with_odom.T_odom_base, 1e-12));
  EXPECT_TRUE((got[0][0].second * got[0][1].second).isApprox(with_odom.T_map_base, 1e-9));
  ASSERT_EQ(got[1].size(), 1U);
  EXPECT_EQ(got[1][0].first, "map>base_link");
  EXPECT_TRUE(got[1][0].second.isApprox(without.T_map_base, 1e-12));
}

TEST(DdsPubSub, PublishNeverWaitsAndDropsTheOldestWhenTheThreadFallsBehind) {
  DdsConfig cfg;
  cfg.domain_id = private_domain() + 1;
  cfg.network_interface = "lo";
  cfg.queue_capacity = 4;
  DdsPosePublisher pub(cfg, /*start_thread=*/false);  // nobody drains the queue
  for (int i = 0; i < 10; ++i) {
    const bool kept = pub.publish(synthetic_pose_sample(static_cast<uint64_t>(i), i));
    EXPECT_EQ(kept, i < 4) << i;
  }
  EXPECT_EQ(pub.stats().submitted, 10U);
  EXPECT_EQ(pub.stats().dropped_queue_full, 6U);
  EXPECT_EQ(pub.stats().published, 0U);
  EXPECT_TRUE(pub.write_now(synthetic_pose_sample(0, 0)));  // nobody listens: a volatile write still succeeds
}

TEST(DdsPubSub, BadInterfaceIsAnErrorNamingIt) {
  DdsConfig cfg;
  cfg.domain_id = private_domain() + 2;
  cfg.network_interface = "agvnone0";
  try {
    DdsPosePublisher pub(cfg);
    FAIL() << "expected DdsError";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("agvnone0"), std::string::npos) << e.what();
  }
}

// ---- two processes in a network namespace ----

TEST(DdsTwoProcess, EverySamplePublishedArrivesInOrderWithExactValues) {
  REQUIRE_NETNS(ns);
  const std::string dir = agvslam::test::make_temp_dir("agvslam-dds");
  const int n = 200;
  const std::string script =
      "ip link set lo up && "
      "(" +
      agvslam::test::tool_path("agvslam-echo") + " --json --interface lo --count " + std::to_string(3 * n) +
      " --timeout 60 > " + dir + "/echo.jsonl 2> " + dir +
      "/echo.err & "
      "" +
      agvslam::test::tool_path("agvslam-pose-replay") + " --synthetic " + std::to_string(n) +
      " --rate 100 --dds --interface lo --wait-subscribers 1 --wait-timeout 30 --json > " + dir + "/sent.jsonl 2> " +
      dir + "/sent.err; echo replay=$?; wait $!; echo echo=$?)";
  std::string out;
  const int rc = agvslam::test::run_command(ns + " sh -c '" + script + "'", &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("replay=0"), std::string::npos) << out;
  EXPECT_NE(out.find("echo=0"), std::string::npos) << out;

  const auto sent = read_json_lines(dir + "/sent.jsonl");
  const auto got = read_json_lines(dir + "/echo.jsonl");
  std::map<std::string, std::vector<nlohmann::json>> want, have;
  for (const auto& line : sent) {
    if (!line.contains("dds")) continue;
    for (const char* topic : {"pose", "odom", "status"}) want[topic].push_back(line.at("dds").at(topic));
  }
  nlohmann::json summary;
  for (const auto& line : got) {
    if (line.contains("summary")) {
      summary = line.at("summary");
    } else {
      have[line.at("topic").get<std::string>()].push_back(line.at("msg"));
    }
  }
  for (const char* topic : {"pose", "odom", "status"}) {
    ASSERT_EQ(want[topic].size(), static_cast<std::size_t>(n)) << topic;
    ASSERT_EQ(have[topic].size(), static_cast<std::size_t>(n)) << topic << " samples received";
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(have[topic][static_cast<std::size_t>(i)], want[topic][static_cast<std::size_t>(i)])
          << topic << " sample " << i;
    }
  }
  ASSERT_TRUE(summary.contains("latency_ms")) << got.size();
  RecordProperty("latency_ms_median", std::to_string(summary["latency_ms"]["median"].get<double>()));
  RecordProperty("latency_ms_p99", std::to_string(summary["latency_ms"]["p99"].get<double>()));
  fs::remove_all(dir);
}

TEST(DdsTwoProcess, EchoTimesOutWithStatusOneWhenNothingArrives) {
  REQUIRE_NETNS(ns);
  std::string out;
  const int rc =
      agvslam::test::run_command(ns + " sh -c 'ip link set lo up && " + agvslam::test::tool_path("agvslam-echo") +
                                     " --interface lo --domain 7 --count 1 --timeout 1'",
                                 &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("timed out"), std::string::npos) << out;
}

TEST(DdsTools, BadOptionsExitTwo) {
  std::string out;
  EXPECT_EQ(agvslam::test::run_command(agvslam::test::tool_path("agvslam-echo") + " --topic posee", &out), 2) << out;
  EXPECT_EQ(agvslam::test::run_command(agvslam::test::tool_path("agvslam-echo") + " --domain 999", &out), 2) << out;
  EXPECT_NE(out.find("dds.domain_id"), std::string::npos) << out;
  EXPECT_EQ(agvslam::test::run_command(agvslam::test::tool_path("agvslam-pose-replay") + " --dds", &out), 2) << out;
  EXPECT_NE(out.find("--synthetic"), std::string::npos) << out;
}

}  // namespace
