// agvslamd's configuration: the shipped files load and echo every section; relative paths follow the file; each
// kind of bad value is an InputError naming the file and the field; the camera-to-base_link extrinsic.
#include "agvslam/daemon/daemon_config.h"
#include "agvslam/io/dataset.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "agvslam/core/error.h"
#include "daemon_test_util.h"

namespace agvslam::daemon {
namespace {

namespace fs = std::filesystem;
using test::write_text;

std::string params(const std::string& name) { return std::string(AGVSLAM_SOURCE_DIR) + "/params/" + name; }

TEST(DaemonConfig, ShippedVehicleConfigLoadsWithTheStageFiles) {
  const DaemonConfig c = load_daemon_config(params("agvslamd.yaml"));
  EXPECT_EQ(c.source.type, SourceType::kV4l2);
  EXPECT_EQ(c.camera.left_device, "/dev/agvslam/left");
  EXPECT_EQ(c.camera.width, 752);
  EXPECT_EQ(c.calibration_file, fs::path(params("agvslamd_calibration_example.yaml")).lexically_normal().string());
  EXPECT_EQ(c.stage_files.slam, fs::path(params("slam.yaml")).lexically_normal().string());
  EXPECT_EQ(c.pipeline.dynamic, DynamicMode::kDetector);
  EXPECT_EQ(c.pipeline.mapping, MappingMode::kThread);
  EXPECT_TRUE(c.outputs.dds_enabled);
  EXPECT_TRUE(c.outputs.can_enabled);
  EXPECT_EQ(c.outputs.can.base_id, 0x300U);
  EXPECT_EQ(c.outputs.dds.topic_namespace, "agvslam");
  EXPECT_DOUBLE_EQ(c.base_link.x_m, 0.30);
  EXPECT_EQ(c.systemd.ready, ReadyWhen::kFirstFrame);
  // Every section is echoed.
  std::string all;
  for (const auto& line : c.describe()) all += line + "\n";
  for (const char* what :
       {"source: type=v4l2", "camera:", "calibration:", "stages:", "vocabulary:", "map:", "pipeline:", "base_link:",
        "covariance:", "dds:", "can:", "trajectory:", "log:", "systemd:", "tracking:", "orb:", "sgbm:"}) {
    EXPECT_NE(all.find(what), std::string::npos) << what << " missing from\n" << all;
  }
}

TEST(DaemonConfig, ShippedDatasetConfigLoads) {
  const DaemonConfig c = load_daemon_config(params("agvslamd_dataset.yaml"));
  EXPECT_EQ(c.source.type, SourceType::kDataset);
  EXPECT_TRUE(c.calibration_file.empty());
  EXPECT_EQ(c.outputs.dds.network_interface, "lo");
  EXPECT_FALSE(c.outputs.can_enabled);
}

TEST(DaemonConfig, MinimalFileTakesTheDefaultsAndResolvesPathsAgainstItsFolder) {
  const std::string dir = test::make_temp_dir("agvslamd-config");
  write_text(dir + "/d.yaml", "source:\n  type: dataset\n  dataset: seq\n  rate: 0\ntrajectory:\n  file: out/t.tum\n");
  const DaemonConfig c = load_daemon_config(dir + "/d.yaml");
  EXPECT_EQ(c.source.dataset, dir + "/seq");
  EXPECT_EQ(c.trajectory.file, dir + "/out/t.tum");
  EXPECT_TRUE(c.stage_files.slam.empty());  // built-in defaults
  EXPECT_EQ(c.pipeline.capture_queue, 2);
  EXPECT_EQ(c.pipeline.heartbeat_ms, 500);
  EXPECT_FALSE(c.outputs.can_enabled);
  EXPECT_TRUE(c.system.threaded_mapping);
  fs::remove_all(dir);
}

struct BadCase {
  const char* yaml;
  const char* field;
};

TEST(DaemonConfig, EveryKindOfBadSettingNamesTheFileAndTheField) {
  const std::string dir = test::make_temp_dir("agvslamd-config-bad");
  const std::string ok_source = "source:\n  type: dataset\n  dataset: /x\n";
  const std::vector<BadCase> cases = {
      {"sources:\n  type: dataset\n", "sources"},                                       // unknown section
      {"source:\n  type: dataset\n  datset: /x\n", "source.datset"},                    // typo in a key
      {"source:\n  type: usb\n", "source.type"},                                        // bad enum
      {"source:\n  type: dataset\n", "source.dataset"},                                 // required for dataset
      {"source:\n  type: dataset\n  dataset: /x\n  rate: -1\n", "source.rate"},         // out of range
      {"source:\n  type: dataset\n  dataset: /x\n  loop: sometimes\n", "source.loop"},  // bad bool
      {"source:\n  type: v4l2\n", "camera"},                                   // the camera section is required
      {"source:\n  type: v4l2\ncamera:\n  width: 752\n", "calibration.file"},  // and a calibration
      {"source:\n  type: v4l2\ncalibration:\n  file: c.yaml\ncamera:\n  width: -5\n", "camera.width"},
      {"pipeline:\n  capture_queue: many\n", "pipeline.capture_queue"},  // bad type
      {"pipeline:\n  capture_queue: 0\n", "pipeline.capture_queue"},
      {"pipeline:\n  dynamic: gt\n", "pipeline.dynamic"},
      {"pipeline:\n  mapping: later\n", "pipeline.mapping"},
      {"base_link:\n  yaw_deg: 1000\n", "base_link.yaw_deg"},
      {"covariance:\n  position_sd_m: 0\n", "covariance.position_sd_m"},
      {"dds:\n  domain_id: 300\n", "dds.domain_id"},
      {"dds:\n  topic_namespace: /bad/\n", "dds.topic_namespace"},
      {"dds:\n  wait_for_subscribers: -1\n", "dds.wait_for_subscribers"},
      {"can:\n  base_id: zz\n", "can.base_id"},
      {"can:\n  enabled: true\n  rate_hz: -3\n", "can.rate_hz"},
      {"odometry:\n  source: wheels\n", "odometry.source"},
      {"odometry:\n  source: can\n", "odometry.source"},  // CAN odometry needs the CAN output's interface
      {"odometry:\n  tolerance: 1.5\n", "odometry.tolerance"},
      {"odometry:\n  window_s: 0\n", "odometry.window_s"},
      {"can:\n  enabled: true\nodometry:\n  source: can\n", "can_odometry.dbc"},  // no DBC named
      {"can:\n  enabled: true\nodometry:\n  source: can\ncan_odometry:\n  dbc: /nonexistent/v.dbc\n",
       "can_odometry.dbc"},
      {"can:\n  enabled: true\nodometry:\n  source: can\ncan_odometry:\n  dbc: DBC\n  message: NOPE\n",
       "can_odometry.message"},
      {"can:\n  enabled: true\nodometry:\n  source: can\ncan_odometry:\n  dbc: DBC\n  speed_signal: Velocity\n",
       "can_odometry.speed_signal"},
      {"can:\n  enabled: true\nodometry:\n  source: can\ncan_odometry:\n  dbc: DBC\n  yaw_rate_unit: rpm\n",
       "can_odometry.yaw_rate_unit"},
      {"can_odometry:\n  dbcfile: x\n", "can_odometry.dbcfile"},
      {"trajectory:\n  frame: odom\n", "trajectory.frame"},
      {"trajectory:\n  file: /tmp/a\nlog:\n  pose_log: /tmp/a\n", "log.pose_log"},  // one file for two outputs
      {"log:\n  level: loud\n", "log.level"},
      {"systemd:\n  ready: never\n", "systemd.ready"},
      {"stages:\n  slam: /nonexistent/slam.yaml\n", "/nonexistent/slam.yaml"},  // a stage file that is missing
      {"source: [1, 2\n", "line"},                                              // YAML syntax
  };
  for (const BadCase& bc : cases) {
    const std::string path = dir + "/bad.yaml";
    const bool has_source =
        std::string(bc.yaml).rfind("source", 0) == 0 || std::string(bc.yaml).rfind("sources", 0) == 0;
    std::string yaml = bc.yaml;
    const std::size_t dbc = yaml.find("dbc: DBC");
    if (dbc != std::string::npos)
      yaml.replace(dbc, 8, "dbc: " + std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc");
    write_text(path, (has_source ? "" : ok_source) + yaml);
    try {
      load_daemon_config(path);
      ADD_FAILURE() << "no error for:\n" << bc.yaml;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(bc.field), std::string::npos) << "message '" << msg << "' should name " << bc.field;
      EXPECT_NE(msg.find("expected"), std::string::npos) << msg;
      if (std::string(bc.field).find('/') == std::string::npos) {
        EXPECT_EQ(msg.rfind(path, 0), 0U) << msg;
      }
    }
  }
  fs::remove_all(dir);
}

// files.write_dirs: every written file resolves inside the listed folders, ".." and symbolic links followed.
TEST(DaemonConfig, WrittenFilesStayInsideTheFoldersTheDaemonMayWrite) {
  const std::string dir = test::make_temp_dir("agvslamd-confine");
  fs::create_directories(dir + "/state");
  fs::create_directories(dir + "/elsewhere");
  fs::create_symlink(dir + "/elsewhere", dir + "/state/link");
  const std::string head = "source:\n  type: dataset\n  dataset: /x\nfiles:\n  write_dirs: state\n";
  const auto load = [&](const std::string& yaml) {
    write_text(dir + "/d.yaml", head + yaml);
    return load_daemon_config(dir + "/d.yaml");
  };
  const auto refused_field = [&](const std::string& yaml) -> std::string {
    try {
      load(yaml);
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("expected a file inside the folders the daemon may write (" + dir + "/state"),
                std::string::npos)
          << msg;
      return msg;
    }
    return "accepted";
  };
  // Inside: accepted, and the echo says where writes go.
  const DaemonConfig ok = load("trajectory:\n  file: state/t.tum\nlog:\n  file: state/logs/d.log\n");
  ASSERT_EQ(ok.files.write_roots.size(), 1U);
  EXPECT_EQ(ok.files.write_roots[0], dir + "/state");
  std::string echo;
  for (const auto& line : ok.describe()) echo += line + "\n";
  EXPECT_NE(echo.find("(writes only in " + dir + "/state)"), std::string::npos) << echo;

  EXPECT_NE(refused_field("trajectory:\n  file: /etc/t.tum\n").find("trajectory.file"), std::string::npos);
  EXPECT_NE(refused_field("log:\n  file: state/../d.log\n").find("log.file"), std::string::npos);
  EXPECT_NE(refused_field("log:\n  pose_log: state-old/p.jsonl\n").find("log.pose_log"), std::string::npos);
  // Through a symbolic link inside the folder to one outside it; the message gives where it leads.
  const std::string via_link = refused_field("trajectory:\n  final_file: state/link/f.tum\n");
  EXPECT_NE(via_link.find("trajectory.final_file"), std::string::npos);
  EXPECT_NE(via_link.find("resolves to " + dir + "/elsewhere/f.tum"), std::string::npos) << via_link;
  // A map file is written only when the map is saved.
  const std::string place = "stages:\n  place: " + std::string(AGVSLAM_SOURCE_DIR) + "/params/place.yaml\n";
  EXPECT_NE(refused_field(place + "map:\n  file: " + dir + "/m.agvmap\n").find("map.file"), std::string::npos);
  EXPECT_NO_THROW(load(place + "map:\n  file: " + dir + "/m.agvmap\n  save_on_stop: false\n"));

  // env: the service's folders from systemd; none set: not confined.
  write_text(dir + "/e.yaml", "source:\n  type: dataset\n  dataset: /x\ntrajectory:\n  file: /var/t.tum\n");
  ::setenv("STATE_DIRECTORY", (dir + "/state").c_str(), 1);
  ::setenv("LOGS_DIRECTORY", (dir + "/logs:" + dir + "/more").c_str(), 1);
  try {
    load_daemon_config(dir + "/e.yaml");
    ADD_FAILURE() << "a trajectory outside $STATE_DIRECTORY was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/state:" + dir + "/logs:" + dir + "/more"), std::string::npos)
        << e.what();
  }
  ::unsetenv("STATE_DIRECTORY");
  ::unsetenv("LOGS_DIRECTORY");
  EXPECT_TRUE(load_daemon_config(dir + "/e.yaml").files.write_roots.empty());
  fs::remove_all(dir);
}

TEST(DaemonConfig, CanOdometryFromTheShippedDbc) {
  const std::string dir = test::make_temp_dir("agvslamd-config-odometry");
  write_text(dir + "/o.yaml",
             "source:\n  type: dataset\n  dataset: /x\ncan:\n  enabled: true\n  base_id: 0x400\n"
             "odometry:\n  source: can\n  window_s: 8\ncan_odometry:\n  dbc: " +
                 std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc\n");
  const DaemonConfig c = load_daemon_config(dir + "/o.yaml");
  EXPECT_EQ(c.odometry.source, OdometrySource::kCan);
  EXPECT_DOUBLE_EQ(c.odometry.check.window_s, 8.0);
  EXPECT_DOUBLE_EQ(c.odometry.check.tolerance, 0.2);
  EXPECT_EQ(c.odometry.can.message, "VEHICLE_ODOMETRY");
  std::string all;
  for (const auto& line : c.describe()) all += line + "\n";
  EXPECT_NE(all.find("odometry: source=can"), std::string::npos) << all;
  EXPECT_NE(all.find("can_odometry: dbc="), std::string::npos) << all;
  // The shipped vehicle file reads no odometry (the outputs stay as they were) and echoes no can_odometry.
  const DaemonConfig shipped = load_daemon_config(params("agvslamd.yaml"));
  EXPECT_EQ(shipped.odometry.source, OdometrySource::kNone);
  EXPECT_EQ(shipped.odometry.can.dbc,
            fs::path(std::string(AGVSLAM_SOURCE_DIR) + "/deploy/agvslam.dbc").lexically_normal().string());
  fs::remove_all(dir);
}

TEST(DaemonConfig, DdsAndCanSectionsLoadAlone) {
  const std::string dir = test::make_temp_dir("agvslamd-config-sections");
  write_text(dir + "/o.yaml",
             "dds:\n  domain_id: 42\n  topic_namespace: robot1/slam\ncan:\n  interface: vcan3\n"
             "  base_id: 0x400\n  fd: true\n  rate_hz: 10\n");
  const auto d = load_dds_config(dir + "/o.yaml");
  EXPECT_EQ(d.domain_id, 42);
  EXPECT_EQ(d.pose_topic(), "rt/robot1/slam/pose");
  const auto c = load_can_config(dir + "/o.yaml");
  EXPECT_EQ(c.interface, "vcan3");
  EXPECT_EQ(c.base_id, 0x400U);
  EXPECT_TRUE(c.fd);
  EXPECT_DOUBLE_EQ(c.rate_hz, 10.0);
  fs::remove_all(dir);
}

TEST(DaemonConfig, DdsSecurityKeystoreFollowsTheFileAndABadOneStopsTheStart) {
  const std::string dir = test::make_temp_dir("agvslamd-config-security");
  std::string out;
  ASSERT_EQ(test::run_command(std::string(AGVSLAM_SOURCE_DIR) + "/deploy/make-keystore.sh " + dir + "/ks", &out), 0)
      << out;
  const std::string head = "source:\n  type: dataset\n  dataset: /x\ndds_security:\n";
  write_text(dir + "/s.yaml", head + "  enabled: true\n  keystore: ks\n  enclave: /agvslam/agvslamd\n");
  const DaemonConfig c = load_daemon_config(dir + "/s.yaml");
  EXPECT_TRUE(c.outputs.dds.security.enabled);
  EXPECT_EQ(c.outputs.dds.security.keystore, dir + "/ks");
  std::string all;
  for (const auto& line : c.describe()) all += line + "\n";
  EXPECT_NE(all.find("dds_security: enabled=true, keystore=" + dir + "/ks, enclave=/agvslam/agvslamd"),
            std::string::npos)
      << all;
  // The shipped file runs plain DDS and says so.
  all.clear();
  for (const auto& line : load_daemon_config(params("agvslamd.yaml")).describe()) all += line + "\n";
  EXPECT_NE(all.find("dds_security: enabled=false"), std::string::npos) << all;

  for (const auto& [yaml, field] : std::vector<std::pair<std::string, std::string>>{
           {"  enabled: true\n", "dds_security.keystore"},
           {"  enabled: true\n  keystore: ks\n  enclave: agvslam\n", "dds_security.enclave"},
           {"  enabled: yes please\n", "dds_security.enabled"},
           {"  keystor: ks\n", "keystor"}}) {
    write_text(dir + "/bad.yaml", head + yaml);
    try {
      load_daemon_config(dir + "/bad.yaml");
      ADD_FAILURE() << yaml;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }

  // A permissions file changed after signing stops the start, naming it.
  const std::string p7s = dir + "/ks/enclaves/agvslam/agvslamd/permissions.p7s";
  std::string text = test::read_text(p7s);
  text.replace(text.find("<default>DENY</default>"), 23, "<default>ALLOW</default>");
  write_text(p7s, text);
  try {
    load_daemon_config(dir + "/s.yaml");
    ADD_FAILURE() << "a tampered permissions file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(p7s + ": expected this enclave's permissions document signed by"),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(BaseLinkConfig, ForwardLookingCameraMapsTheOpticalAxesToReps103) {
  BaseLinkConfig b;
  b.x_m = 0.3;
  b.z_m = 0.5;
  const SE3d T = b.T_base_cam();
  // Optical z (forward) -> base x, optical x (right) -> base -y, optical y (down) -> base -z.
  EXPECT_TRUE(T.linear().col(2).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(T.linear().col(0).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE(T.linear().col(1).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(0.3, 0, 0.5)));
  // Turned 90 degrees to the left: it looks along base +y.
  b.yaw_deg = 90;
  EXPECT_TRUE(b.T_base_cam().linear().col(2).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // Pitched down by 10 degrees: the optical axis points below the horizon.
  b.yaw_deg = 0;
  b.pitch_deg = 10;
  const Eigen::Vector3d axis = b.T_base_cam().linear().col(2);
  EXPECT_NEAR(axis.z(), -std::sin(10 * M_PI / 180), 1e-12);
  // optical: false gives the optical frame directly.
  BaseLinkConfig o;
  o.optical = false;
  EXPECT_TRUE(o.T_base_cam().linear().isIdentity(1e-12));
}

TEST(FrameRange, ParsesInclusiveRangesAndRejectsBadOnes) {
  std::size_t a = 0, b = 0;
  io::parse_frame_range("", 10, "f", "source.frames", a, b);
  EXPECT_EQ(a, 0U);
  EXPECT_EQ(b, 9U);
  io::parse_frame_range("3:", 10, "f", "source.frames", a, b);
  EXPECT_EQ(a, 3U);
  EXPECT_EQ(b, 9U);
  io::parse_frame_range("2:20", 10, "f", "source.frames", a, b);
  EXPECT_EQ(b, 9U);
  for (const char* bad : {"5", "a:b", "7:3", "10:", "-1:2"}) {
    EXPECT_THROW(io::parse_frame_range(bad, 10, "f", "source.frames", a, b), InputError) << bad;
  }
}

}  // namespace
}  // namespace agvslam::daemon
