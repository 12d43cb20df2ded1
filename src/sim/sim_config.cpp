#include "agvslam/sim/sim_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "agvslam/core/param_table.h"

namespace agvslam::sim {
namespace {

using params::Range;

std::string fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

const params::Table<SimConfig>& camera_params() {
  using S = SimConfig;
  static const params::Table<S> table =
      params::Table<S>("camera",
                       {
                           {"width", &S::width, Range::closed(16, 8192), "px"},
                           {"height", &S::height, Range::closed(16, 8192), "px"},
                           {"fx", &S::fx, Range::above(1), "px"},
                           {"fy", &S::fy, Range::above(1) | Range::at_most(0), "px", "<= 0: fx"},
                           {"cx", &S::cx, Range::finite(), "px", "< 0: the image centre"},
                           {"cy", &S::cy, Range::finite(), "px", "< 0: the image centre"},
                           {"baseline_m", &S::baseline_m, Range::open(0.001, 2), "m"},
                           {"height_above_floor_m", &S::camera_height_m, Range::open(0.1, 3), "m"},
                           {"rate_hz", &S::rate_hz, Range::left_open(0.5, 1000), "Hz"},
                       })
          .check(
              "cx", [](const S& c) { return c.cx < c.width; }, "a principal point inside the image (or < 0)")
          .check(
              "cy", [](const S& c) { return c.cy < c.height; }, "a principal point inside the image (or < 0)")
          .summary([](const S& c) {
            return "fy " + fmt("%.2f", c.fy_px()) + ", cx " + fmt("%.2f", c.cx_px()) + ", cy " +
                   fmt("%.2f", c.cy_px()) + " px";
          });
  return table;
}

const params::Table<SimConfig>& sensor_params() {
  using S = SimConfig;
  static const params::Table<S> table(
      "sensor",
      {
          {"noise_sigma_dn", &S::noise_sigma_dn, Range::closed(0, 50), "grey levels"},
          {"exposure_variation", &S::exposure_variation, Range::closed(0, 0.5), "", "relative gain, 0.04 = +-4 %"},
          {"exposure_spread", &S::exposure_spread, Range::closed(0, 0.5), "", "relative gain between sequences"},
          {"vignetting", &S::vignetting, Range::right_open(0, 1), "", "relative darkening of the corners"},
      });
  return table;
}

const params::Table<SimConfig>& rendering_params() {
  using S = SimConfig;
  static const params::Table<S> table(
      "rendering",
      {
          {"max_depth_m", &S::max_depth_m, Range::above(1), "m"},
          {"antialias_edges", &S::antialias_edges},
          {"haze_distance_m", &S::haze_distance_m, Range::finite(), "m", "<= 0: no haze"},
          {"png_compression", &S::png_compression, Range::closed(0, 9), "", "a zlib level"},
          {"lighting_variation", &S::lighting_variation, Range::closed(0, 0.5), "", "relative, between warehouses"},
      });
  return table;
}

const params::Table<SimConfig>& vehicle_params() {
  static const params::Table<SimConfig> table(
      "vehicle", {
                     {"vibration_deg", &SimConfig::vibration_deg, Range::closed(0, 5), "deg"},
                 });
  return table;
}

}  // namespace

StereoCalibration SimConfig::calibration() const {
  StereoCalibration calib;
  calib.left.fx = fx;
  calib.left.fy = fy_px();
  calib.left.cx = cx_px();
  calib.left.cy = cy_px();
  calib.left.width = width;
  calib.left.height = height;
  calib.baseline_m = baseline_m;
  return calib;
}

void SimConfig::validate(const std::string& source) const {
  camera_params().validate(source, *this);
  sensor_params().validate(source, *this);
  rendering_params().validate(source, *this);
  vehicle_params().validate(source, *this);
}

std::vector<std::string> SimConfig::describe() const {
  return {camera_params().describe(*this), sensor_params().describe(*this), rendering_params().describe(*this),
          vehicle_params().describe(*this)};
}

SimConfig SimConfig::scaled(double factor) const {
  SimConfig c = *this;
  c.width = std::max(16, static_cast<int>(std::lround(width * factor)));
  c.height = std::max(16, static_cast<int>(std::lround(height * factor)));
  c.fx = fx * factor;
  c.fy = fy > 0 ? fy * factor : -1.0;
  c.cx = cx >= 0 ? (cx + 0.5) * factor - 0.5 : -1.0;
  c.cy = cy >= 0 ? (cy + 0.5) * factor - 0.5 : -1.0;
  return c;
}

SimConfig load_sim_config(const std::string& path) {
  SimConfig c;
  params::read_sections(params::File(path), {camera_params().reader(c), sensor_params().reader(c),
                                             rendering_params().reader(c), vehicle_params().reader(c)});
  c.validate(path);
  return c;
}

}  // namespace agvslam::sim
