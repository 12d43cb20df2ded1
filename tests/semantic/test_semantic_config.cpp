// params/semantic.yaml loading: the shipped file, overrides, and errors that name the file and the field.
#include <gtest/gtest.h>

#include "agvslam/semantic/semantic_config.h"
#include "common/config_test.h"

namespace agvslam::semantic {
namespace {

void expect_error(const std::string& text, const std::string& field) {
  test::expect_input_error([](const std::string& path) { load_semantic_config(path); }, text, field);
}

TEST(SemanticConfig, ShippedParamsFileLoadsAndMatchesTheDefaults) {
  const SemanticConfig c = load_semantic_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/semantic.yaml");
  const SemanticConfig d;
  EXPECT_EQ(c.model.path, std::string(AGVSLAM_SOURCE_DIR) + "/" + d.model.path);  // relative to params/
  EXPECT_EQ(c.model.input_width, d.model.input_width);
  EXPECT_EQ(c.model.input_height, d.model.input_height);
  EXPECT_DOUBLE_EQ(c.model.scale, d.model.scale);
  EXPECT_EQ(c.model.movable_ids(), (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(c.keyframes.every_n_frames, 5);
  EXPECT_EQ(c.propagation.max_late_frames, d.propagation.max_late_frames);
  EXPECT_DOUBLE_EQ(c.motion.enter_evidence, d.motion.enter_evidence);
  EXPECT_EQ(c.fusion.mode, FusionMode::kUnion);
  EXPECT_EQ(c.describe().size(), 5u);
}

TEST(SemanticConfig, OverridesOnlyTheGivenKeys) {
  test::TempYaml f("model:\n  movable_classes: \"11, 12 13\"\n  input_channels: 3\nfusion:\n  mode: semantic\n");
  const SemanticConfig c = load_semantic_config(f.path());
  EXPECT_EQ(c.model.movable_ids(), (std::vector<int>{11, 12, 13}));
  EXPECT_EQ(c.model.input_channels, 3);
  EXPECT_EQ(c.fusion.mode, FusionMode::kSemantic);
  EXPECT_EQ(c.model.input_width, ModelConfig{}.input_width);
}

TEST(SemanticConfig, BadValuesNameTheField) {
  expect_error("model:\n  movable_classes: \"person\"\n", "model.movable_classes");
  expect_error("model:\n  movable_classes: \"5 300\"\n", "model.movable_classes");
  expect_error("model:\n  input_channels: 2\n", "model.input_channels");
  expect_error("model:\n  path: \"\"\n", "model.path");
  expect_error("keyframes:\n  every_n_frames: 0\n", "keyframes.every_n_frames");
  expect_error("propagation:\n  lk_window_px: 20\n", "propagation.lk_window_px");
  expect_error("motion:\n  exit_evidence: 2.0\n", "motion.exit_evidence");
  expect_error("fusion:\n  mode: intersection\n", "fusion.mode");
  expect_error("fusion:\n  colour: red\n", "fusion.colour");
}

}  // namespace
}  // namespace agvslam::semantic
