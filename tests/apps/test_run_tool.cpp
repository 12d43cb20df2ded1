// agvslam-run end to end: the KITTI 06 and EuRoC V1_01 excerpts (real data, ground truth) and a short simulator
// sequence with walking people (agvslam-sim), in all three --dynamic modes; trajectory files, JSON, bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "agvslam/io/dataset.h"
#include "common/test_data.h"
#include "io/rosbag_test_writer.h"

namespace agvslam {
namespace {
namespace fs = std::filesystem;

struct RunOutput {
  int rc = -1;
  std::string text;  // stdout (stderr dropped unless asked for)
  long frames = -1, tracked = -1, keyframes = -1, lost = -1;
  double ate_m = -1, drift_m = -1;
};

RunOutput run_tool(const std::string& args, bool keep_stderr = false) {
  RunOutput r;
  r.rc = test::run_command(
      "(" + test::tool_path("agvslam-run") + " " + args + (keep_stderr ? " 2>&1)" : " 2>/dev/null)"), &r.text);
  std::smatch m;
  const std::regex first(R"(^FRAMES (\d+) TRACKED (\d+) KEYFRAMES (\d+) LOST (\d+)\n)");
  if (std::regex_search(r.text, m, first)) {
    r.frames = std::stol(m[1]);
    r.tracked = std::stol(m[2]);
    r.keyframes = std::stol(m[3]);
    r.lost = std::stol(m[4]);
  }
  if (std::regex_search(r.text, m, std::regex(R"(ATE_RMSE_M ([0-9.]+))"))) r.ate_m = std::stod(m[1]);
  if (std::regex_search(r.text, m, std::regex(R"(DRIFT_M ([0-9.]+))"))) r.drift_m = std::stod(m[1]);
  return r;
}

std::size_t count_lines(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(f, line)) {
    if (!line.empty() && line[0] != '#') ++n;
  }
  return n;
}

TEST(RunTool, KittiExcerptMatchesOrbSlam2) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-kitti");
  const RunOutput r =
      run_tool("--dataset " + data + " --out " + dir + "/traj.txt --format kitti --dynamic off --mapping inline" +
               " --params-slam " AGVSLAM_SOURCE_DIR "/params/slam.yaml --params-features " AGVSLAM_SOURCE_DIR
               "/params/features_kitti.yaml --json " +
               dir + "/stats.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_EQ(r.frames, 51);
  EXPECT_EQ(r.tracked, 51);
  EXPECT_EQ(r.lost, 0);
  // ORB-SLAM2 stereo on the same frames on this machine: 0.054 m (median of three runs).
  EXPECT_GT(r.ate_m, 0.0) << r.text;
  EXPECT_LE(r.ate_m, 0.054) << r.text;
  EXPECT_EQ(count_lines(dir + "/traj.txt"), 51u);
  // The trajectory agrees with agvslam-eval's reading of it.
  std::string eval;
  ASSERT_EQ(test::run_command(
                test::tool_path("agvslam-eval") + " --gt " + data + "/poses.txt --est " + dir + "/traj.txt 2>/dev/null",
                &eval),
            0)
      << eval;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(eval, m, std::regex(R"(^ATE_RMSE_M ([0-9.]+))")));
  EXPECT_NEAR(std::stod(m[1]), r.ate_m, 1e-4);

  std::ifstream f(dir + "/stats.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["per_frame"].size(), 51u);
  for (const char* stage : {"extract", "stereo", "frame", "local_map", "keyframe", "tracking"}) {
    ASSERT_TRUE(j["timings"].contains(stage)) << stage;
    for (const char* stat : {"median_ms", "p95_ms", "p99_ms", "max_ms"})
      EXPECT_GE(j["timings"][stage][stat].get<double>(), 0.0);
  }
  EXPECT_GT(j["map"]["keyframes"].get<int>(), 2);
  EXPECT_TRUE(j["local_mapping"].contains("max_queue"));
  EXPECT_NEAR(j["ate"]["rmse_m"].get<double>(), r.ate_m, 1e-5);
}

TEST(RunTool, EurocStillCameraNoDriftNoLossThreadedMapping) {
  AGVSLAM_REQUIRE_SHARED(data, "data/euroc_v101_f000-094");
  const std::string dir = test::make_temp_dir("agvslam-run-euroc");
  const RunOutput r = run_tool("--dataset " + data + " --out " + dir +
                               "/traj.tum --dynamic off --mapping thread --json " + dir + "/stats.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_EQ(r.frames, 95);
  EXPECT_EQ(r.tracked, 95);
  EXPECT_EQ(r.lost, 0);
  EXPECT_GE(r.drift_m, 0.0);
  EXPECT_LT(r.drift_m, 0.01) << r.text;
  EXPECT_EQ(count_lines(dir + "/traj.tum"), 95u);
}

// A short stretch of scene3 (the straight aisle, people crossing and walking ahead from frame 22), rendered once.
const std::string& scene3_sequence() {
  static const std::string dir = [] {
    const std::string d = test::make_temp_dir("agvslam-run-sim") + "/scene3";
    std::string out;
    const int rc = test::run_command(
        test::tool_path("agvslam-sim") + " --scenario scene3 --seed 7 --squeeze-to 150 --threads 2 --out " + d, &out);
    EXPECT_EQ(rc, 0) << out;
    return d;
  }();
  return dir;
}

TEST(RunTool, SimulatorWithPeopleAllDynamicModes) {
  const std::string data = scene3_sequence();
  const std::string dir = test::make_temp_dir("agvslam-run-modes");
  double ate[3];
  const char* modes[3] = {"gt", "detector", "off"};
  for (int k = 0; k < 3; ++k) {
    const RunOutput r = run_tool("--dataset " + data + " --out " + dir + "/" + modes[k] + ".txt --dynamic " + modes[k] +
                                 " --mapping inline --json " + dir + "/" + modes[k] + ".json");
    ASSERT_EQ(r.rc, 0) << modes[k] << "\n" << r.text;
    EXPECT_EQ(r.tracked, 150) << modes[k];
    ate[k] = r.ate_m;
    // 150 frames, 5 m of the aisle.
    EXPECT_GT(r.ate_m, 0.0) << modes[k];
    EXPECT_LT(r.ate_m, 0.03) << modes[k] << "\n" << r.text;
  }
  // With masks, features stay off the people: the JSON records the masked pixels.
  std::ifstream f(dir + "/gt.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  long masked = 0;
  for (const auto& pf : j["per_frame"]) masked += pf["mask_pixels"].get<long>();
  EXPECT_GT(masked, 0);
  EXPECT_TRUE(j["timings"].contains("read"));
  std::ifstream fd(dir + "/detector.json");
  const nlohmann::json jd = nlohmann::json::parse(fd);
  EXPECT_TRUE(jd["timings"].contains("detector"));
  EXPECT_TRUE(jd["timings"].contains("frontend_sum"));
  std::printf("scene3 seed 7, 150 frames: ATE gt %.4f detector %.4f off %.4f m\n", ate[0], ate[1], ate[2]);
}

TEST(RunTool, BadInputExitsTwoNamingTheOption) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-bad");
  RunOutput r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --dynamic sometimes", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("--dynamic"), std::string::npos) << r.text;
  r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --dynamic gt", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("mask"), std::string::npos) << r.text;
  r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --frames 60:", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("51 frames"), std::string::npos) << r.text;
  r = run_tool("--dataset " + dir + "/nothing --out " + dir + "/t.txt", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("nothing"), std::string::npos) << r.text;
  r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --format euroc", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("--format"), std::string::npos) << r.text;
  { std::ofstream(dir + "/bad.yaml") << "tracking:\n  min_init_featurs: 3\n"; }
  r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --params-slam " + dir + "/bad.yaml", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("min_init_featurs"), std::string::npos) << r.text;
  r = run_tool("--dataset " + data + " --out " + dir + "/t.txt --mapping sometimes", true);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.text.find("--mapping"), std::string::npos) << r.text;
}

TEST(RunTool, FrameRangeAndFirstLine) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-range");
  const RunOutput r =
      run_tool("--dataset " + data + " --out " + dir + "/t.txt --dynamic off --mapping inline --frames 10:29");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_EQ(r.text.rfind("FRAMES 20 TRACKED ", 0), 0u) << r.text;
  EXPECT_EQ(count_lines(dir + "/t.txt"), static_cast<std::size_t>(r.tracked));
}

// A rosbag2 recording of the KITTI 06 excerpt's first 20 frames (left Image mono8, right CompressedImage png,
// camera_info on both sides) runs like the folder itself: the same trajectory, stamp for stamp.
TEST(RunTool, RosbagOfKittiExcerptGivesTheFolderTrajectory) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-rosbag");
  const io::KittiDataset kitti(data);
  test::write_kitti_bag(kitti, 20, dir + "/bag");
  const std::string common = " --dynamic off --mapping inline --params-slam " AGVSLAM_SOURCE_DIR
                             "/params/slam.yaml --params-features " AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml";
  const RunOutput folder = run_tool("--dataset " + data + " --frames 0:19 --out " + dir + "/folder.txt" + common);
  ASSERT_EQ(folder.rc, 0) << folder.text;
  const RunOutput bag = run_tool("--dataset " + dir + "/bag --out " + dir + "/bag.txt" + common);
  ASSERT_EQ(bag.rc, 0) << bag.text;
  EXPECT_EQ(bag.frames, 20);
  EXPECT_EQ(bag.tracked, folder.tracked);
  EXPECT_EQ(bag.lost, 0);
  auto read = [](const std::string& path) {
    std::ifstream f(path);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  };
  const std::string folder_trajectory = read(dir + "/folder.txt");
  EXPECT_EQ(count_lines(dir + "/bag.txt"), 20u);
  EXPECT_EQ(read(dir + "/bag.txt"), folder_trajectory);

  // The topics chosen by name give the same; a wrong topic exits 2 naming it.
  const RunOutput chosen = run_tool("--dataset '" + dir +
                                    "/bag?left=/kitti/camera_gray_left/image_raw&right=/kitti/camera_gray_right/"
                                    "image_raw/compressed' --out " +
                                    dir + "/chosen.txt" + common);
  ASSERT_EQ(chosen.rc, 0) << chosen.text;
  EXPECT_EQ(read(dir + "/chosen.txt"), folder_trajectory);
  const RunOutput wrong = run_tool("--dataset '" + dir + "/bag?left=/camera/left' --out " + dir + "/w.txt", true);
  EXPECT_EQ(wrong.rc, 2);
  EXPECT_NE(wrong.text.find("left=/camera/left"), std::string::npos) << wrong.text;

  // A damaged message (frame 5's left image cut short) is skipped and counted, the run goes on.
  ASSERT_TRUE(test::truncate_message(dir + "/bag/recording_0.db3", 1, 5, false, 100));
  const RunOutput damaged =
      run_tool("--dataset " + dir + "/bag --out " + dir + "/damaged.txt --json " + dir + "/damaged.json" + common);
  ASSERT_EQ(damaged.rc, 0) << damaged.text;
  EXPECT_EQ(damaged.frames, 19);
  std::ifstream f(dir + "/damaged.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["frames"]["skipped_unreadable"], 1);
}

}  // namespace
}  // namespace agvslam
