// agvslam-vocab end to end: trains on a short simulator sequence (written by agvslam-sim) and on a folder of
// images, reads the file back, evaluates it (loop revisits and the map/query relocalisation mode), and rejects bad
// input with exit status 2 and a message naming the option or file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "agvslam/place/vocabulary.h"
#include "common/test_data.h"

namespace agvslam {
namespace {
namespace fs = std::filesystem;

// The static loop, 40 frames (the whole lap), rendered once per build folder (rendering is the slow part, and
// ctest runs every test of this file in its own process): rendered into a temporary folder, then renamed.
const std::string& loop_sequence() {
  static const std::string dir = [] {
    const fs::path d = fs::path(test::binary_dir()) / "test_data" / "place" / "static_s61";
    if (!fs::exists(d / "scenario.json")) {
      fs::create_directories(d.parent_path());
      const std::string tmp = test::make_temp_dir("agvslam-vocab-tool-render") + "/static_s61";
      std::string out;
      const int rc = test::run_command(
          test::tool_path("agvslam-sim") + " --scenario static --seed 61 --squeeze-to 40 --threads 2 --out " + tmp,
          &out);
      EXPECT_EQ(rc, 0) << out;
      std::error_code ec;
      fs::rename(tmp, d, ec);  // fails harmlessly when another test process got there first
      fs::remove_all(fs::path(tmp).parent_path(), ec);
    }
    return d.string();
  }();
  return dir;
}

std::string vocab() { return test::tool_path("agvslam-vocab"); }

TEST(VocabTool, TrainsWritesAFileThatLoadsAndEvaluatesIt) {
  const std::string data = loop_sequence();
  const std::string dir = test::make_temp_dir("agvslam-vocab-tool");
  const std::string file = dir + "/voc.bin", json_path = dir + "/train.json";
  std::string out;
  ASSERT_EQ(test::run_command("(" + vocab() + " --datasets " + data + " --out " + file +
                                  " --k 10 --levels 3 --frame-step 2 --threads 2 --description 'tool test' --json " +
                                  json_path + " 2>/dev/null)",
                              &out),
            0)
      << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(^VOCABULARY \S+ k 10 L 3 words (\d+) )"))) << out;
  const place::Vocabulary v = place::Vocabulary::load(file);
  EXPECT_EQ(v.word_count(), std::stoul(m[1].str()));
  EXPECT_GT(v.word_count(), 500u);
  EXPECT_EQ(v.training_images(), 20u);  // 40 frames, every second one
  EXPECT_NE(v.description().find("tool test"), std::string::npos);
  EXPECT_NE(v.description().find("static_s61"), std::string::npos);
  std::ifstream jf(json_path);
  const auto j = nlohmann::json::parse(jf);
  EXPECT_EQ(j["identity"].get<std::string>(), v.identity_hex());
  EXPECT_EQ(j["images"].get<int>(), 20);
  EXPECT_GT(j["timings"]["extract_ms"]["median"].get<double>(), 0.0);

  ASSERT_EQ(test::run_command(vocab() + " --info " + file, &out), 0) << out;
  EXPECT_NE(out.find(v.identity_hex()), std::string::npos) << out;

  // Evaluation: the sequence as its own map (every query's top-1 must be itself: score 1, all correct), and its
  // loop revisits (the end of the lap returns to the start).
  const std::string eval_json = dir + "/eval.json";
  ASSERT_EQ(test::run_command("(" + vocab() + " --evaluate --vocabulary " + file + " --loop " + data + " --map " +
                                  data + " --query " + data + " --min-gap-s 0.5 --json " + eval_json + " 2>/dev/null)",
                              &out),
            0)
      << out;
  EXPECT_NE(out.find("PR voc.bin loop static_s61"), std::string::npos) << out;
  EXPECT_NE(out.find("PR voc.bin relocalisation static_s61"), std::string::npos) << out;
  EXPECT_NE(out.find("TRANSFORM voc.bin"), std::string::npos) << out;
  std::ifstream ef(eval_json);
  const auto e = nlohmann::json::parse(ef);
  ASSERT_EQ(e["evaluations"].size(), 2u);
  const auto& reloc = e["evaluations"][1];
  EXPECT_EQ(reloc["mode"], "relocalisation");
  EXPECT_EQ(reloc["positives"].get<int>(), 40);
  EXPECT_DOUBLE_EQ(reloc["recall_at_precision_1"].get<double>(), 1.0);
  for (const auto& q : reloc["per_query"]) {
    EXPECT_EQ(q["match"].get<long>(), q["query"].get<long>());
    EXPECT_NEAR(q["score"].get<double>(), 1.0, 1e-5);
  }
  const auto& loop = e["evaluations"][0];
  EXPECT_EQ(loop["mode"], "loop");
  EXPECT_GT(loop["positives"].get<int>(), 0);
}

TEST(VocabTool, TrainsOnAnImageFolder) {
  const std::string data = loop_sequence();
  const std::string dir = test::make_temp_dir("agvslam-vocab-tool");
  const std::string file = dir + "/images.bin";
  std::string out;
  ASSERT_EQ(test::run_command(vocab() + " --images " + data + "/image_0," + data + "/image_1 --out " + file +
                                  " --k 6 --levels 2 --frame-step 4 --max-features-per-image 300 2>&1",
                              &out),
            0)
      << out;
  // Settings are echoed at start-up.
  EXPECT_NE(out.find("k=6 L=2"), std::string::npos) << out;
  EXPECT_NE(out.find("max features per image 300"), std::string::npos) << out;
  const place::Vocabulary v = place::Vocabulary::load(file);
  EXPECT_EQ(v.training_images(), 20u);  // 10 of each camera
  EXPECT_EQ(v.training_descriptors(), 20u * 300u);
  EXPECT_LE(v.word_count(), 36u);
}

TEST(VocabTool, BadInputExitsWithTwoAndNamesTheOptionOrFile) {
  const std::string data = loop_sequence();
  const std::string dir = test::make_temp_dir("agvslam-vocab-tool");
  std::string out;
  EXPECT_EQ(test::run_command(vocab() + " --datasets " + dir + "/missing --out " + dir + "/x.bin 2>&1", &out), 2);
  EXPECT_NE(out.find("missing"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(vocab() + " --datasets " + data + " --out " + dir + "/x.bin --k 1 2>&1", &out), 2);
  EXPECT_NE(out.find("branching"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(vocab() + " --out " + dir + "/x.bin 2>&1", &out), 2);
  EXPECT_NE(out.find("--images/--datasets"), std::string::npos) << out;
  const std::string corrupt = dir + "/corrupt.bin";
  std::ofstream(corrupt) << "not a vocabulary at all, but long enough to have a header of 128 bytes ......"
                            "..........................................................................";
  EXPECT_EQ(test::run_command(vocab() + " --info " + corrupt + " 2>&1", &out), 2);
  EXPECT_NE(out.find(corrupt), std::string::npos) << out;
  EXPECT_NE(out.find("magic"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(vocab() + " --evaluate --vocabulary " + corrupt + " --loop " + data + " 2>&1", &out), 2);
  EXPECT_EQ(test::run_command(vocab() + " --evaluate --vocabulary " + corrupt + " 2>&1", &out), 2);
  EXPECT_NE(out.find("--loop"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(vocab() + " --evaluate --vocabulary " + corrupt + " --map " + data + " 2>&1", &out), 2);
}

}  // namespace
}  // namespace agvslam
