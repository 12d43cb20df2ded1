// The segmentation network's loader: the shipped model, models with the node types OpenCV 4.6 rejects (and their
// repairs), and model files that are missing, truncated or of another input shape.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <string>

#include "agvslam/core/error.h"
#include "agvslam/semantic/segmenter.h"
#include "common/test_data.h"

namespace agvslam::semantic {
namespace {

std::string source_path(const std::string& rel) { return std::string(AGVSLAM_SOURCE_DIR) + "/" + rel; }

ModelConfig shipped() {
  ModelConfig c;
  c.path = source_path(c.path);
  return c;
}

// The two-class 8x8 test models of tests/semantic/data (make_rejected_models.py).
ModelConfig tiny(const std::string& file) {
  ModelConfig c;
  c.path = source_path("tests/semantic/data/" + file);
  c.input_width = c.input_height = 8;
  c.movable_classes = "1";
  return c;
}

// Loading `config` throws an InputError naming the model file whose message holds every one of `words`.
void expect_load_error(const ModelConfig& config, const std::vector<std::string>& words) {
  try {
    Segmenter s(config);
    ADD_FAILURE() << config.path << " loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), config.path) << e.what();
    for (const std::string& w : words)
      EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << w << ": " << e.what();
  }
}

TEST(Segmenter, ShippedModelLoadsAndLabelsEveryPixel) {
  Segmenter s(shipped());
  EXPECT_EQ(s.class_count(), 8);
  cv::Mat grey(480, 752, CV_8UC1);
  cv::randu(grey, 0, 255);
  const cv::Mat labels = s.segment(grey);
  ASSERT_EQ(labels.size(), grey.size());
  ASSERT_EQ(labels.type(), CV_8UC1);
  double max_id = 0;
  cv::minMaxLoc(labels, nullptr, &max_id);
  EXPECT_LT(max_id, 8);
}

TEST(Segmenter, IdentityOnAnInitialiserNamesTheNode) {
  expect_load_error(tiny("rejected_identity.onnx"), {"weights_identity", "Identity"});
}

TEST(Segmenter, ThreeInputClipNamesTheNode) { expect_load_error(tiny("rejected_clip.onnx"), {"relu6_clip", "Clip"}); }

TEST(Segmenter, RepairedModelsLoad) {
  for (const char* file : {"repaired_identity.onnx", "repaired_clip.onnx"}) {
    Segmenter s(tiny(file));
    EXPECT_EQ(s.class_count(), 2) << file;
    const cv::Mat labels = s.segment(cv::Mat(20, 30, CV_8UC1, cv::Scalar(90)));
    EXPECT_EQ(labels.size(), cv::Size(30, 20)) << file;
  }
}

TEST(Segmenter, MissingModelFile) {
  ModelConfig c = shipped();
  c.path = source_path("params/models/no_such_model.onnx");
  expect_load_error(c, {"no_such_model.onnx", "model.path"});
}

TEST(Segmenter, TruncatedModelFile) {
  const std::string dir = test::make_temp_dir("agvslam-semantic-model");
  ModelConfig c = shipped();
  std::ifstream in(c.path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  c.path = dir + "/truncated.onnx";
  std::ofstream(c.path, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  expect_load_error(c, {"truncated.onnx"});
}

TEST(Segmenter, InputShapeOtherThanTheModels) {
  ModelConfig c = shipped();
  c.input_channels = 3;  // the shipped network takes one grey channel
  expect_load_error(c, {"model input", "1x3x192x288"});
  c = shipped();
  c.input_width = 200;  // the pyramid's pooling windows are fixed for 288 x 192
  expect_load_error(c, {"model input"});
}

TEST(Segmenter, MovableClassTheNetworkDoesNotHave) {
  ModelConfig c = shipped();
  c.movable_classes = "5 11";
  expect_load_error(c, {"model output", "11"});
}

}  // namespace
}  // namespace agvslam::semantic
