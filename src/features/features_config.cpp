#include "agvslam/features/features_config.h"

#include "agvslam/core/error.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::features {

void FeaturesConfig::validate(const std::string& source) const {
  orb.validate(source);
  stereo_matching.validate(source);
}

std::vector<std::string> FeaturesConfig::describe() const { return {orb.describe(), stereo_matching.describe()}; }

FeaturesConfig load_features_config(const std::string& path) {
  const stereo::ParamsReader in(path);
  in.check_sections({"orb", "stereo_matching"});
  FeaturesConfig c;

  in.check_keys("orb", {"n_features", "scale_factor", "n_levels", "ini_fast_threshold", "min_fast_threshold",
                        "mask_dilation_px", "cell_size_px", "level_allocation"});
  OrbExtractorConfig& o = c.orb;
  in.read("orb", "n_features", o.n_features, "an integer");
  in.read("orb", "scale_factor", o.scale_factor, "a number");
  in.read("orb", "n_levels", o.n_levels, "an integer");
  in.read("orb", "ini_fast_threshold", o.ini_fast_threshold, "an integer (grey levels)");
  in.read("orb", "min_fast_threshold", o.min_fast_threshold, "an integer (grey levels)");
  in.read("orb", "mask_dilation_px", o.mask_dilation_px, "an integer (px)");
  in.read("orb", "cell_size_px", o.cell_size_px, "an integer (px)");
  std::string allocation = to_string(o.level_allocation);
  in.read("orb", "level_allocation", allocation, "area or side");
  if (!parse_level_allocation(allocation, o.level_allocation)) {
    throw InputError(path, "orb.level_allocation", "expected area or side");
  }

  in.check_keys("stereo_matching", {"method", "min_depth_m", "max_depth_m", "sad_half_window", "sad_search_px",
                                    "max_descriptor_distance", "uniqueness_ratio", "min_curvature",
                                    "outlier_factor"});
  StereoMatcherConfig& s = c.stereo_matching;
  std::string method = to_string(s.method);
  in.read("stereo_matching", "method", method, "block_matching or descriptor");
  if (!parse_stereo_method(method, s.method)) {
    throw InputError(path, "stereo_matching.method", "expected block_matching or descriptor");
  }
  in.read("stereo_matching", "min_depth_m", s.min_depth_m, "a number (m)");
  in.read("stereo_matching", "max_depth_m", s.max_depth_m, "a number (m)");
  in.read("stereo_matching", "sad_half_window", s.sad_half_window, "an integer (px)");
  in.read("stereo_matching", "sad_search_px", s.sad_search_px, "an integer (px)");
  in.read("stereo_matching", "max_descriptor_distance", s.max_descriptor_distance, "an integer (bits)");
  in.read("stereo_matching", "uniqueness_ratio", s.uniqueness_ratio, "a number");
  in.read("stereo_matching", "min_curvature", s.min_curvature, "a number (grey levels)");
  in.read("stereo_matching", "outlier_factor", s.outlier_factor, "a number");
  c.validate(path);
  return c;
}

}  // namespace agvslam::features
