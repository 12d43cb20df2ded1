#include "agvslam/stereo/stereo_config.h"

#include "agvslam/core/param_table.h"

namespace agvslam::stereo {
namespace {

using params::Range;

const params::EnumNames<SgbmMode>& sgbm_mode_names() {
  static const params::EnumNames<SgbmMode> names{
      {"sgbm", SgbmMode::kSgbm}, {"hh", SgbmMode::kHh}, {"sgbm_3way", SgbmMode::kSgbm3Way}, {"hh4", SgbmMode::kHh4}};
  return names;
}

const params::Table<SgbmConfig>& sgbm_params() {
  static const params::Table<SgbmConfig> table =
      params::Table<SgbmConfig>(
          "sgbm",
          {
              {"min_disparity", &SgbmConfig::min_disparity, Range::closed(0, 1024), "px"},
              {"num_disparities", &SgbmConfig::num_disparities, Range::closed(16, 1024).multiple_of(16), "px",
               "OpenCV's StereoSGBM requires a multiple of 16"},
              {"block_size", &SgbmConfig::block_size, Range::closed(1, 11).odd(), "px",
               "a window centred on the pixel"},
              {"p1", &SgbmConfig::p1, Range::any(), "", "<= 0: 8 x channels x block_size^2"},
              {"p2", &SgbmConfig::p2, Range::any(), "", "<= 0: 32 x channels x block_size^2"},
              {"disp12_max_diff", &SgbmConfig::disp12_max_diff, Range::at_most(64), "px", "< 0 disables the check"},
              {"pre_filter_cap", &SgbmConfig::pre_filter_cap, Range::closed(1, 63)},
              {"uniqueness_ratio", &SgbmConfig::uniqueness_ratio, Range::closed(0, 100), "%"},
              {"speckle_window_size", &SgbmConfig::speckle_window_size, Range::at_least(0), "px",
               "0 disables speckle filtering"},
              {"speckle_range", &SgbmConfig::speckle_range, Range::closed(0, 64), "px"},
              {"mode", &SgbmConfig::mode, sgbm_mode_names()},
              {"roi_margin_px", &SgbmConfig::roi_margin_px, Range::closed(0, 256), "px"},
          })
          .check(
              "p2", [](const SgbmConfig& g) { return g.p1 <= 0 || g.p2 <= 0 || g.p2 > g.p1; },
              "p2 > p1 (or <= 0 for the default)")
          .summary([](const SgbmConfig& g) {
            return "P1 " + std::to_string(g.effective_p1(1)) + " P2 " + std::to_string(g.effective_p2(1)) +
                   " on grey images, disparities " + std::to_string(g.min_disparity) + ".." +
                   std::to_string(g.max_disparity()) + " px";
          });
  return table;
}

const params::Table<SparseStereoConfig>& sparse_params() {
  static const params::Table<SparseStereoConfig> table =
      params::Table<SparseStereoConfig>(
          "sparse",
          {
              {"half_window", &SparseStereoConfig::half_window, Range::closed(1, 10), "px"},
              {"min_disparity", &SparseStereoConfig::min_disparity, Range::closed(0, 1024), "px"},
              {"num_disparities", &SparseStereoConfig::num_disparities, Range::closed(4, 1024), "px"},
              {"uniqueness_margin", &SparseStereoConfig::uniqueness_margin, Range::closed(0, 2)},
              {"max_mean_cost", &SparseStereoConfig::max_mean_cost, Range::left_open(0, 255), "grey levels"},
              {"max_cost_ratio", &SparseStereoConfig::max_cost_ratio, Range::left_open(0, 10), "", "of the texture"},
              {"min_texture", &SparseStereoConfig::min_texture, Range::closed(0, 128), "grey levels"},
              {"lr_max_diff_px", &SparseStereoConfig::lr_max_diff_px, Range::at_most(16), "px",
               "< 0 disables the check"},
              {"subpixel", &SparseStereoConfig::subpixel},
          })
          .summary([](const SparseStereoConfig& s) {
            const std::string side = std::to_string(2 * s.half_window + 1);
            return "window " + side + "x" + side + " px, disparities " + std::to_string(s.min_disparity) + ".." +
                   std::to_string(s.max_disparity()) + " px";
          });
  return table;
}

}  // namespace

std::string to_string(SgbmMode mode) { return sgbm_mode_names().name(mode); }

bool parse_sgbm_mode(const std::string& text, SgbmMode& mode) { return sgbm_mode_names().parse(text, mode); }

void SgbmConfig::validate(const std::string& source) const { sgbm_params().validate(source, *this); }
std::string SgbmConfig::describe() const { return sgbm_params().describe(*this); }

void SparseStereoConfig::validate(const std::string& source) const { sparse_params().validate(source, *this); }
std::string SparseStereoConfig::describe() const { return sparse_params().describe(*this); }

void StereoConfig::validate(const std::string& source) const {
  sgbm.validate(source);
  sparse.validate(source);
}

std::vector<std::string> StereoConfig::describe() const { return {sgbm.describe(), sparse.describe()}; }

StereoConfig load_stereo_config(const std::string& path) {
  StereoConfig c;
  params::read_sections(params::File(path), {sgbm_params().reader(c.sgbm), sparse_params().reader(c.sparse)});
  c.validate(path);
  return c;
}

}  // namespace agvslam::stereo
