// agvslam-dynamic --semantic end to end: a model that is missing or truncated leaves the geometric detector alone
// (a logged warning, the same masks, exit 0); the shipped model adds to the detector's masks (union), never removes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "common/test_data.h"

namespace agvslam {
namespace {
namespace fs = std::filesystem;

const std::string& sequence() {
  static const std::string dir = [] {
    const std::string d = test::make_temp_dir("agvslam-semantic-tool") + "/scene1";
    std::string out;
    // Frames 110-117 of scene1: the person walks in front of the stationary AGV.
    const int rc = test::run_command(
        test::tool_path("agvslam-sim") + " --scenario scene1 --seed 1 --frames 118 " + "--threads 2 --out " + d, &out);
    EXPECT_EQ(rc, 0) << out;
    return d;
  }();
  return dir;
}

// agvslam-dynamic on frames 110-117 into <sequence>/../<name>; stdout+stderr in `log`. Returns the exit status.
int run_dynamic(const std::string& name, const std::string& options, std::string& log) {
  const std::string out = fs::path(sequence()).parent_path().string() + "/" + name;
  return test::run_command(test::tool_path("agvslam-dynamic") + " --dataset " + sequence() + " --out " + out +
                               " --frames 110:117 --overlay-every 0 " + options + " 2>&1",
                           &log);
}

cv::Mat mask(const std::string& name, int frame) {
  char file[32];
  std::snprintf(file, sizeof(file), "%06d.png", frame);
  return cv::imread((fs::path(sequence()).parent_path() / name / "mask" / file).string(), cv::IMREAD_GRAYSCALE);
}

std::string source_path(const std::string& rel) { return std::string(AGVSLAM_SOURCE_DIR) + "/" + rel; }

TEST(SemanticTool, BadModelFallsBackToGeometryAlone) {
  std::string log;
  ASSERT_EQ(run_dynamic("geometry", "", log), 0) << log;
  const std::string truncated = fs::path(sequence()).parent_path().string() + "/truncated.onnx";
  {
    std::ifstream in(source_path("params/models/pspnet_mnv2.onnx"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  }
  for (const std::string& model : {std::string("/no/such/model.onnx"), truncated}) {
    ASSERT_EQ(run_dynamic("fallback", "--semantic " + model, log), 0) << log;
    EXPECT_NE(log.find("continuing with the geometric detector alone"), std::string::npos) << log;
    EXPECT_NE(log.find(model), std::string::npos) << log;
    for (int i = 110; i <= 117; ++i) {
      const cv::Mat a = mask("geometry", i), b = mask("fallback", i);
      ASSERT_FALSE(a.empty());
      ASSERT_FALSE(b.empty());
      EXPECT_EQ(cv::countNonZero(a != b), 0) << model << " frame " << i;
    }
  }
}

TEST(SemanticTool, ShippedModelAddsToTheDetectorsMask) {
  std::string log;
  ASSERT_EQ(run_dynamic("geometry", "", log), 0) << log;
  ASSERT_EQ(run_dynamic("semantic",
                        "--semantic " + source_path("params/models/pspnet_mnv2.onnx") + " --params-semantic " +
                            source_path("params/semantic.yaml"),
                        log),
            0)
      << log;
  EXPECT_NE(log.find("semantic settings"), std::string::npos) << log;
  EXPECT_EQ(log.find("geometric detector alone"), std::string::npos) << log;
  for (int i = 110; i <= 117; ++i) {
    const cv::Mat a = mask("geometry", i), b = mask("semantic", i);
    ASSERT_FALSE(b.empty());
    EXPECT_EQ(cv::countNonZero(a & ~b), 0) << "union mode removed detector pixels in frame " << i;
  }
}

}  // namespace
}  // namespace agvslam
