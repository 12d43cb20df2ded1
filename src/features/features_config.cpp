#include "agvslam/features/features_config.h"

#include "agvslam/core/param_table.h"

namespace agvslam::features {
namespace {

using params::Range;

const params::EnumNames<LevelAllocation>& level_allocation_names() {
  static const params::EnumNames<LevelAllocation> names{{"area", LevelAllocation::kArea},
                                                        {"side", LevelAllocation::kSide}};
  return names;
}

const params::EnumNames<StereoMethod>& stereo_method_names() {
  static const params::EnumNames<StereoMethod> names{{"block_matching", StereoMethod::kBlockMatching},
                                                     {"descriptor", StereoMethod::kDescriptor}};
  return names;
}

const params::Table<OrbExtractorConfig>& orb_params() {
  static const params::Table<OrbExtractorConfig> table =
      params::Table<OrbExtractorConfig>(
          "orb",
          {
              {"n_features", &OrbExtractorConfig::n_features, Range::closed(8, 20000), "per image"},
              {"scale_factor", &OrbExtractorConfig::scale_factor, Range::left_open(1, 2)},
              {"n_levels", &OrbExtractorConfig::n_levels, Range::closed(1, 16)},
              {"ini_fast_threshold", &OrbExtractorConfig::ini_fast_threshold, Range::closed(1, 254), "grey levels"},
              {"min_fast_threshold", &OrbExtractorConfig::min_fast_threshold, Range::at_least(1), "grey levels"},
              {"mask_dilation_px", &OrbExtractorConfig::mask_dilation_px, Range::closed(0, 100), "px"},
              {"cell_size_px", &OrbExtractorConfig::cell_size_px, Range::closed(8, 256), "px"},
              {"level_allocation", &OrbExtractorConfig::level_allocation, level_allocation_names()},
          })
          .check(
              "min_fast_threshold",
              [](const OrbExtractorConfig& o) { return o.min_fast_threshold <= o.ini_fast_threshold; },
              "at most ini_fast_threshold (the retry lowers the threshold)")
          .summary([](const OrbExtractorConfig& o) {
            std::string per_level;
            for (int n : o.features_per_level()) per_level += (per_level.empty() ? "" : " ") + std::to_string(n);
            return "features per level: " + per_level;
          });
  return table;
}

const params::Table<StereoMatcherConfig>& stereo_matching_params() {
  static const params::Table<StereoMatcherConfig> table =
      params::Table<StereoMatcherConfig>(
          "stereo_matching",
          {
              {"method", &StereoMatcherConfig::method, stereo_method_names()},
              {"min_depth_m", &StereoMatcherConfig::min_depth_m, Range::left_open(0, 100), "m"},
              {"max_depth_m", &StereoMatcherConfig::max_depth_m, Range::at_most(10000), "m"},
              {"sad_half_window", &StereoMatcherConfig::sad_half_window, Range::closed(1, 7), "px"},
              {"sad_search_px", &StereoMatcherConfig::sad_search_px, Range::closed(1, 20), "px"},
              {"max_descriptor_distance", &StereoMatcherConfig::max_descriptor_distance, Range::closed(0, 256), "bits",
               "of a 256-bit descriptor"},
              {"uniqueness_ratio", &StereoMatcherConfig::uniqueness_ratio, Range::left_open(0, 1)},
              {"min_curvature", &StereoMatcherConfig::min_curvature, Range::closed(0, 50), "grey levels"},
              {"outlier_factor", &StereoMatcherConfig::outlier_factor, Range::closed(1, 100), "x median SAD",
               "1 already rejects half the matches"},
          })
          .check(
              "max_depth_m", [](const StereoMatcherConfig& s) { return s.max_depth_m > s.min_depth_m; },
              "more than min_depth_m");
  return table;
}

}  // namespace

const char* to_string(LevelAllocation allocation) { return level_allocation_names().name(allocation); }
bool parse_level_allocation(const std::string& text, LevelAllocation& out) {
  return level_allocation_names().parse(text, out);
}

const char* to_string(StereoMethod method) { return stereo_method_names().name(method); }
bool parse_stereo_method(const std::string& text, StereoMethod& out) { return stereo_method_names().parse(text, out); }

void OrbExtractorConfig::validate(const std::string& source) const { orb_params().validate(source, *this); }
std::string OrbExtractorConfig::describe() const { return orb_params().describe(*this); }

void StereoMatcherConfig::validate(const std::string& source) const {
  stereo_matching_params().validate(source, *this);
}
std::string StereoMatcherConfig::describe() const { return stereo_matching_params().describe(*this); }

void FeaturesConfig::validate(const std::string& source) const {
  orb.validate(source);
  stereo_matching.validate(source);
}

std::vector<std::string> FeaturesConfig::describe() const { return {orb.describe(), stereo_matching.describe()}; }

FeaturesConfig load_features_config(const std::string& path) {
  FeaturesConfig c;
  params::read_sections(params::File(path),
                        {orb_params().reader(c.orb), stereo_matching_params().reader(c.stereo_matching)});
  c.validate(path);
  return c;
}

}  // namespace agvslam::features
