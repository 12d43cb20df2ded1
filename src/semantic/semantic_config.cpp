#include "agvslam/semantic/semantic_config.h"

#include <filesystem>
#include <sstream>

#include "agvslam/core/param_table.h"

namespace agvslam::semantic {
namespace {

using params::Range;
using params::Text;

// "5 6 7" -> {5, 6, 7}; false for anything else than 1..32 ids in [0, 255] separated by spaces or commas.
bool parse_ids(const std::string& text, std::vector<int>& ids) {
  std::string spaced = text;
  for (char& ch : spaced) {
    if (ch == ',') ch = ' ';
  }
  std::istringstream in(spaced);
  ids.clear();
  std::string token;
  while (in >> token) {
    std::size_t used = 0;
    int id = -1;
    try {
      id = std::stoi(token, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (used != token.size() || id < 0 || id > 255) return false;
    ids.push_back(id);
  }
  return !ids.empty() && ids.size() <= 32;
}

const params::Table<ModelConfig>& model_params() {
  static const params::Table<ModelConfig> table =
      params::Table<ModelConfig>("model",
                                 {
                                     {"path", &ModelConfig::path, Text::non_empty()},
                                     {"input_width", &ModelConfig::input_width, Range::closed(1, 4096), "px"},
                                     {"input_height", &ModelConfig::input_height, Range::closed(1, 4096), "px"},
                                     {"input_channels", &ModelConfig::input_channels, Range::value(1) | Range::value(3),
                                      "", "1: grey, 3: grey as B, G, R"},
                                     {"mean", &ModelConfig::mean, Range::closed(-255, 255), "grey levels"},
                                     {"scale", &ModelConfig::scale, Range::above(0)},
                                     {"movable_classes", &ModelConfig::movable_classes, Text::non_empty(),
                                      "class ids in [0, 255] separated by spaces"},
                                 })
          .check(
              "movable_classes",
              [](const ModelConfig& m) {
                std::vector<int> ids;
                return parse_ids(m.movable_classes, ids);
              },
              "1 to 32 class ids in [0, 255] separated by spaces, e.g. '5 6 7'");
  return table;
}

const params::Table<KeyframeConfig>& keyframe_params() {
  static const params::Table<KeyframeConfig> table = params::Table<KeyframeConfig>(
      "keyframes", {
                       {"every_n_frames", &KeyframeConfig::every_n_frames, Range::closed(1, 1000), "frames"},
                       {"min_dynamic_points", &KeyframeConfig::min_dynamic_points, Range::at_least(0), "points",
                        "0 turns the rule off"},
                       {"on_new_keyframe", &KeyframeConfig::on_new_keyframe},
                   });
  return table;
}

const params::Table<PropagationConfig>& propagation_params() {
  static const params::Table<PropagationConfig> table = params::Table<PropagationConfig>(
      "propagation",
      {
          {"max_points_per_object", &PropagationConfig::max_points_per_object, Range::closed(1, 1000), "points"},
          {"lk_window_px", &PropagationConfig::lk_window_px, Range::closed(5, 101).odd(), "px"},
          {"lk_levels", &PropagationConfig::lk_levels, Range::closed(1, 8)},
          {"max_fb_error_px", &PropagationConfig::max_fb_error_px, Range::above(0), "px"},
          {"min_object_pixels", &PropagationConfig::min_object_pixels, Range::at_least(1), "px"},
          {"max_late_frames", &PropagationConfig::max_late_frames, Range::closed(0, 100), "frames"},
          {"min_match_iou", &PropagationConfig::min_match_iou, Range::left_open(0, 1)},
      });
  return table;
}

const params::Table<MotionConfig>& motion_params() {
  static const params::Table<MotionConfig> table =
      params::Table<MotionConfig>("motion",
                                  {
                                      {"min_points", &MotionConfig::min_points, Range::at_least(1), "points"},
                                      {"static_sigmas", &MotionConfig::static_sigmas, Range::above(0)},
                                      {"min_offset_px", &MotionConfig::min_offset_px, Range::at_least(0), "px"},
                                      {"moving_fraction", &MotionConfig::moving_fraction, Range::left_open(0, 1)},
                                      {"far_min_offset_px", &MotionConfig::far_min_offset_px, Range::above(0), "px"},
                                      {"decay", &MotionConfig::decay, Range::right_open(0, 1)},
                                      {"enter_evidence", &MotionConfig::enter_evidence, Range::above(0)},
                                      {"exit_evidence", &MotionConfig::exit_evidence, Range::at_least(0)},
                                  })
          .check(
              "exit_evidence", [](const MotionConfig& m) { return m.exit_evidence < m.enter_evidence; },
              "less than enter_evidence (hysteresis)");
  return table;
}

const params::EnumNames<FusionMode>& fusion_mode_names() {
  static const params::EnumNames<FusionMode> names{
      {"union", FusionMode::kUnion}, {"semantic", FusionMode::kSemantic}, {"geometry", FusionMode::kGeometry}};
  return names;
}

const params::Table<FusionConfig>& fusion_params() {
  static const params::Table<FusionConfig> table = params::Table<FusionConfig>(
      "fusion", {
                    {"mode", &FusionConfig::mode, fusion_mode_names()},
                    {"mask_dilation_px", &FusionConfig::mask_dilation_px, Range::closed(0, 50), "px"},
                    {"synchronous", &FusionConfig::synchronous},
                });
  return table;
}

}  // namespace

std::vector<int> ModelConfig::movable_ids() const {
  std::vector<int> ids;
  parse_ids(movable_classes, ids);
  return ids;
}

std::string to_string(FusionMode mode) { return fusion_mode_names().name(mode); }

void ModelConfig::validate(const std::string& source) const { model_params().validate(source, *this); }
std::string ModelConfig::describe() const { return model_params().describe(*this); }
void KeyframeConfig::validate(const std::string& source) const { keyframe_params().validate(source, *this); }
std::string KeyframeConfig::describe() const { return keyframe_params().describe(*this); }
void PropagationConfig::validate(const std::string& source) const { propagation_params().validate(source, *this); }
std::string PropagationConfig::describe() const { return propagation_params().describe(*this); }
void MotionConfig::validate(const std::string& source) const { motion_params().validate(source, *this); }
std::string MotionConfig::describe() const { return motion_params().describe(*this); }
void FusionConfig::validate(const std::string& source) const { fusion_params().validate(source, *this); }
std::string FusionConfig::describe() const { return fusion_params().describe(*this); }

void SemanticConfig::validate(const std::string& source) const {
  model.validate(source);
  keyframes.validate(source);
  propagation.validate(source);
  motion.validate(source);
  fusion.validate(source);
}

std::vector<std::string> SemanticConfig::describe() const {
  return {model.describe(), keyframes.describe(), propagation.describe(), motion.describe(), fusion.describe()};
}

SemanticConfig load_semantic_config(const std::string& path) {
  SemanticConfig c;
  params::read_sections(params::File(path), {model_params().reader(c.model), keyframe_params().reader(c.keyframes),
                                             propagation_params().reader(c.propagation),
                                             motion_params().reader(c.motion), fusion_params().reader(c.fusion)});
  // A relative model path in the file is relative to the file (params/semantic.yaml -> params/models/...), so the
  // daemon and the tools find the model whatever their working directory.
  if (!c.model.path.empty() && std::filesystem::path(c.model.path).is_relative()) {
    c.model.path = (std::filesystem::absolute(path).parent_path() / c.model.path).lexically_normal().string();
  }
  c.validate(path);
  return c;
}

}  // namespace agvslam::semantic
