// agvslam-run's place-recognition and map options end to end on the KITTI 06 excerpt: --save-map, then
// --load-map --mode localise on a later part of the sequence (relocalised at once, map unchanged, poses in the
// saved frame), --blank, --repeat, and bad options or files exiting 2 with a message naming them; threaded mapping at
// 2x, 4x and unpaced speed and slowed on purpose never ends lost, and a long loss starts a new map that is reported
// (the map left behind saved with --save-earlier-maps).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <vector>

#include "common/test_data.h"

namespace agvslam {
namespace {

struct ToolRun {
  int rc = -1;
  std::string text;
};

ToolRun run_tool(const std::string& args) {
  ToolRun r;
  r.rc = test::run_command(test::tool_path("agvslam-run") + " " + args, &r.text);
  return r;
}

nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  return nlohmann::json::parse(f);
}

long relocalisation_first_tracked(const std::string& text) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(R"(RELOCALISATION first_tracked (-?\d+))"))) return -2;
  return std::stol(m[1]);
}

TEST(RunToolMaps, SaveThenLocaliseInTheSavedMap) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-maps");
  const std::string common = "--dataset " + data + " --dynamic off --mapping inline --params-features " +
                             AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml";
  ToolRun r =
      run_tool(common + " --out " + dir + "/map.tum --json " + dir + "/map.json --save-map " + dir + "/k06.agvmap");
  ASSERT_EQ(r.rc, 0) << r.text;
  const nlohmann::json saved = read_json(dir + "/map.json");
  ASSERT_TRUE(saved.contains("save_map")) << saved.dump();
  const long keyframes = saved["save_map"]["keyframes"].get<long>();
  const long points = saved["save_map"]["map_points"].get<long>();
  EXPECT_GE(keyframes, 10);
  EXPECT_EQ(saved["save_map"]["bytes"].get<long>(), static_cast<long>(std::filesystem::file_size(dir + "/k06.agvmap")));

  // Frames 25..50 in the saved map: the first frame relocalises, the map is not changed, and the poses are the
  // mapping run's (same world frame: the saved map's first keyframe).
  r = run_tool(common + " --frames 25:50 --load-map " + dir + "/k06.agvmap --mode localise --out " + dir +
               "/loc.tum --json " + dir + "/loc.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_EQ(relocalisation_first_tracked(r.text), 0) << r.text;
  const nlohmann::json loc = read_json(dir + "/loc.json");
  EXPECT_EQ(loc["load_map"]["keyframes"].get<long>(), keyframes);
  EXPECT_EQ(loc["load_map"]["map_points"].get<long>(), points);
  EXPECT_EQ(loc["map"]["keyframes"].get<long>(), keyframes) << "localisation mode changed the map";
  EXPECT_EQ(loc["frames"]["tracked"].get<long>(), 26);
  std::map<std::string, std::array<double, 3>> mapped;
  auto read_tum = [](const std::string& path) {
    std::map<std::string, std::array<double, 3>> out;
    std::ifstream f(path);
    std::string line, t;
    while (std::getline(f, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream in(line);
      double x, y, z;
      if (in >> t >> x >> y >> z) out[t] = {x, y, z};
    }
    return out;
  };
  mapped = read_tum(dir + "/map.tum");
  double worst = 0;
  int compared = 0;
  for (const auto& [t, p] : read_tum(dir + "/loc.tum")) {
    const auto it = mapped.find(t);
    if (it == mapped.end()) continue;
    worst = std::max(worst, std::hypot(p[0] - it->second[0], p[1] - it->second[1], p[2] - it->second[2]));
    ++compared;
  }
  EXPECT_EQ(compared, 26);
  EXPECT_LT(worst, 0.10) << "localised poses are not in the saved map's frame";

  // Extending the map (mode map) adds keyframes to it.
  r = run_tool(common + " --frames 25:50 --load-map " + dir + "/k06.agvmap --mode map --out " + dir +
               "/ext.tum --json " + dir + "/ext.json --save-map " + dir + "/k06b.agvmap");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_GT(read_json(dir + "/ext.json")["save_map"]["keyframes"].get<long>(), keyframes);
  std::filesystem::remove_all(dir);
}

TEST(RunToolMaps, BadOptionsAndFilesExitTwoNamingThem) {
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-maps-bad");
  const std::string common = "--dataset " + data + " --dynamic off --out " + dir + "/t.tum";
  struct Case {
    std::string args, named;
  };
  { std::ofstream(dir + "/corrupt.agvmap") << "AGVSMAP not really a map"; }
  const std::vector<Case> cases = {
      {"--loop maybe", "--loop"},
      {"--mode localise", "--mode"},
      {"--load-map " + dir + "/corrupt.agvmap", "--mode"},
      {"--load-map " + dir + "/corrupt.agvmap --mode somewhere", "--mode"},
      {"--load-map " + dir + "/corrupt.agvmap --mode localise", dir + "/corrupt.agvmap"},
      {"--load-map " + dir + "/missing.agvmap --mode map", dir + "/missing.agvmap"},
      {"--blank 9:3", "--blank"},
      {"--blank x", "--blank"},
      {"--repeat 0", "--repeat"},
      {"--save-map " + dir + "/no/such/folder/m.agvmap", dir + "/no/such/folder"},
      {"--params-place " + dir + "/missing.yaml", dir + "/missing.yaml"},
  };
  for (const Case& c : cases) {
    const ToolRun r = run_tool(common + " " + c.args);
    EXPECT_EQ(r.rc, 2) << c.args << "\n" << r.text;
    EXPECT_NE(r.text.find(c.named), std::string::npos) << c.args << ": the message does not name " << c.named << "\n"
                                                       << r.text;
  }
  std::filesystem::remove_all(dir);
}

TEST(RunToolMaps, BlankFramesAndRepeatedLaps) {
  AGVSLAM_REQUIRE_SHARED(data, "data/euroc_v101_f000-094");
  const std::string dir = test::make_temp_dir("agvslam-run-blank");
  // A still camera covered for frames 30..39: lost without poses, relocalised on the first uncovered frame (a map
  // of one keyframe: kept instead of reset, as a loaded map would be).
  { std::ofstream(dir + "/keep.yaml") << "tracking:\n  reset_max_keyframes: 0\n"; }
  ToolRun r =
      run_tool("--dataset " + data + " --dynamic off --mapping inline --blank 30:39 --frames 0:59 --params-slam " +
               dir + "/keep.yaml --out " + dir + "/b.tum --json " + dir + "/b.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  const nlohmann::json b = read_json(dir + "/b.json");
  EXPECT_EQ(b["frames"]["lost"].get<long>(), 10);
  EXPECT_EQ(b["frames"]["tracked"].get<long>(), 50);
  EXPECT_EQ(b["frames"]["resets"].get<long>(), 0);
  EXPECT_EQ(b["relocalisation"]["blank_recovered_after"].get<long>(), 0);
  // Two laps of frames 0..29: continuing time stamps, twice the frames.
  r = run_tool("--dataset " + data + " --dynamic off --mapping inline --frames 0:29 --repeat 2 --out " + dir +
               "/r.tum --json " + dir + "/r.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  const nlohmann::json rep = read_json(dir + "/r.json");
  EXPECT_EQ(rep["frames"]["processed"].get<long>(), 60);
  EXPECT_EQ(rep["frames"]["tracked"].get<long>(), 60);
  std::filesystem::remove_all(dir);
}

// A threaded run at --speed X (0: unpaced) with extra args; the JSON.
nlohmann::json run_threaded(const std::string& data, const std::string& dir, const std::string& name,
                            const std::string& args) {
  const ToolRun r = run_tool("--dataset " + data + " --dynamic off --params-features " +
                             AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml " + args + " --out " + dir + "/" + name +
                             ".tum --json " + dir + "/" + name + ".json");
  EXPECT_EQ(r.rc, 0) << r.text;
  return r.rc == 0 ? read_json(dir + "/" + name + ".json") : nlohmann::json();
}

// Mapping in its thread that cannot keep up (frames fed faster than real time, or mapping slowed on purpose) must
// not starve tracking of keyframes: every run ends tracked, in its first map, with an ATE near inline mapping's.
void expect_never_lost_for_good(const std::string& excerpt, const std::vector<std::string>& runs) {
  AGVSLAM_REQUIRE_SHARED(data, "data/" + excerpt);
  const std::string dir = test::make_temp_dir("agvslam-run-speed");
  const nlohmann::json inl = run_threaded(data, dir, "inline", "--mapping inline");
  ASSERT_TRUE(inl.contains("ate"));
  const double inline_ate = inl["ate"]["rmse_m"].get<double>();
  // Threaded runs differ from run to run; 0.2 % of the path above inline's is still "the same trajectory".
  const double bound_m = inline_ate + 0.002 * inl["ate"]["gt_path_m"].get<double>();
  for (const std::string& args : runs) {
    const nlohmann::json j = run_threaded(data, dir, "thread", "--mapping thread " + args);
    ASSERT_TRUE(j.contains("frames")) << args;
    const auto& frames = j["per_frame"];
    ASSERT_GE(frames.size(), 5u);
    for (std::size_t k = frames.size() - 5; k < frames.size(); ++k)
      EXPECT_EQ(frames[k]["state"].get<std::string>(), "ok") << args << ", frame " << k;
    EXPECT_EQ(j["frames"]["new_maps"].get<long>(), 0) << args;
    ASSERT_TRUE(j.contains("ate")) << args;
    const double ate = j["ate"]["rmse_m"].get<double>();
    std::printf("%s %s: lost %ld, keyframe waits %ld, ATE %.3f m (inline %.3f m)\n", excerpt.c_str(), args.c_str(),
                j["frames"]["lost"].get<long>(), j["frames"]["keyframe_waits"].get<long>(), ate, inline_ate);
    EXPECT_LT(ate, bound_m) << args;
  }
  std::filesystem::remove_all(dir);
}

const std::vector<std::string> kSpeeds = {"--speed 0", "--speed 2", "--speed 4"};
// Each local-mapping step 100 ms longer (a keyframe takes 0.4-0.6 s, several times the keyframe interval).
const std::vector<std::string> kSlowMapping = {"--speed 0 --test-slow-mapping-ms 100"};

TEST(RunToolMaps, ThreadedMappingNeverEndsLostOnKitti06) { expect_never_lost_for_good("kitti06_f000-050", kSpeeds); }
TEST(RunToolMaps, ThreadedMappingNeverEndsLostOnKitti01) { expect_never_lost_for_good("kitti01_f000-050", kSpeeds); }
TEST(RunToolMaps, SlowMappingNeverEndsLostOnKitti06) { expect_never_lost_for_good("kitti06_f000-050", kSlowMapping); }
TEST(RunToolMaps, SlowMappingNeverEndsLostOnKitti01) { expect_never_lost_for_good("kitti01_f000-050", kSlowMapping); }

TEST(RunToolMaps, LongLossReportsANewMap) {
  // Frames 10..25 of KITTI 06 covered: relocalisation cannot reach the old map 17 m back, a new map starts 1 s
  // of real frames later, and the tool reports it (MAPS line, map_id per frame), with ATE aligned per map.
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslam-run-newmap");
  const ToolRun r = run_tool("--dataset " + data + " --dynamic off --mapping inline --blank 10:25 --params-features " +
                             AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml --save-earlier-maps " + dir + " --out " +
                             dir + "/n.tum --json " + dir + "/n.json");
  ASSERT_EQ(r.rc, 0) << r.text;
  EXPECT_NE(r.text.find("MAPS 2 (new maps after a long loss: 1) LAST_STATE ok"), std::string::npos) << r.text;
  const nlohmann::json j = read_json(dir + "/n.json");
  EXPECT_EQ(j["frames"]["new_maps"].get<long>(), 1);
  const auto& frames = j["per_frame"];
  long first_new = -1;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (frames[k]["new_map"].get<bool>()) first_new = static_cast<long>(k);
    EXPECT_EQ(frames[k]["map_id"].get<long>(), first_new >= 0 ? 1 : 0) << "frame " << k;
    if (first_new >= 0) {
      EXPECT_EQ(frames[k]["state"].get<std::string>(), "ok") << "frame " << k;
    }
  }
  EXPECT_GT(first_new, 25);
  ASSERT_TRUE(j.contains("ate"));
  EXPECT_EQ(j["ate"]["per_map"].size(), 2u);
  EXPECT_LT(j["ate"]["rmse_m"].get<double>(), 0.1);
  ASSERT_EQ(j["earlier_map_files"].size(), 1u);
  EXPECT_TRUE(std::filesystem::exists(dir + "/map_0.agvmap"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace agvslam
