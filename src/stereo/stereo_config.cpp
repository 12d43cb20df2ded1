#include "agvslam/stereo/stereo_config.h"

#include "agvslam/core/error.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::stereo {

void StereoConfig::validate(const std::string& source) const {
  sgbm.validate(source);
  sparse.validate(source);
}

std::vector<std::string> StereoConfig::describe() const { return {sgbm.describe(), sparse.describe()}; }

StereoConfig load_stereo_config(const std::string& path) {
  const ParamsReader in(path);
  in.check_sections({"sgbm", "sparse"});
  StereoConfig c;
  in.check_keys("sgbm", {"min_disparity", "num_disparities", "block_size", "p1", "p2", "disp12_max_diff",
                         "pre_filter_cap", "uniqueness_ratio", "speckle_window_size", "speckle_range", "mode",
                         "roi_margin_px"});
  SgbmConfig& g = c.sgbm;
  in.read("sgbm", "min_disparity", g.min_disparity, "an integer (px)");
  in.read("sgbm", "num_disparities", g.num_disparities, "an integer (a multiple of 16)");
  in.read("sgbm", "block_size", g.block_size, "an odd integer");
  in.read("sgbm", "p1", g.p1, "an integer (<= 0: default)");
  in.read("sgbm", "p2", g.p2, "an integer (<= 0: default)");
  in.read("sgbm", "disp12_max_diff", g.disp12_max_diff, "an integer (px)");
  in.read("sgbm", "pre_filter_cap", g.pre_filter_cap, "an integer");
  in.read("sgbm", "uniqueness_ratio", g.uniqueness_ratio, "an integer (percent)");
  in.read("sgbm", "speckle_window_size", g.speckle_window_size, "an integer (pixels)");
  in.read("sgbm", "speckle_range", g.speckle_range, "an integer (px)");
  std::string mode = to_string(g.mode);
  in.read("sgbm", "mode", mode, "one of sgbm, hh, sgbm_3way, hh4");
  if (!parse_sgbm_mode(mode, g.mode)) throw InputError(path, "sgbm.mode", "expected one of sgbm, hh, sgbm_3way, hh4");
  in.read("sgbm", "roi_margin_px", g.roi_margin_px, "an integer (px)");

  in.check_keys("sparse", {"half_window", "min_disparity", "num_disparities", "uniqueness_margin", "max_mean_cost",
                           "max_cost_ratio", "min_texture", "lr_max_diff_px", "subpixel"});
  SparseStereoConfig& s = c.sparse;
  in.read("sparse", "half_window", s.half_window, "an integer (px)");
  in.read("sparse", "min_disparity", s.min_disparity, "an integer (px)");
  in.read("sparse", "num_disparities", s.num_disparities, "an integer");
  in.read("sparse", "uniqueness_margin", s.uniqueness_margin, "a number");
  in.read("sparse", "max_mean_cost", s.max_mean_cost, "a number (grey levels)");
  in.read("sparse", "max_cost_ratio", s.max_cost_ratio, "a number (fraction of the texture)");
  in.read("sparse", "min_texture", s.min_texture, "a number (grey levels)");
  in.read("sparse", "lr_max_diff_px", s.lr_max_diff_px, "an integer (px)");
  in.read("sparse", "subpixel", s.subpixel, "true or false");
  c.validate(path);
  return c;
}

}  // namespace agvslam::stereo
