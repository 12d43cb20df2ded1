#include "agvslam/sim/sim_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "agvslam/core/error.h"

namespace agvslam::sim {
namespace {

std::string fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

template <typename T>
void read_value(const YAML::Node& section, const std::string& section_name, const std::string& key, T& value,
                const std::string& path, const char* expectation) {
  const YAML::Node node = section[key];
  if (!node) return;
  try {
    value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(path, section_name + "." + key, std::string("expected ") + expectation);
  }
}

void check_keys(const YAML::Node& section, const std::string& section_name, const std::set<std::string>& allowed,
                const std::string& path) {
  if (!section.IsMap()) throw InputError(path, section_name, "expected a map of settings");
  for (const auto& kv : section) {
    const std::string key = kv.first.as<std::string>();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw InputError(path, section_name + "." + key, "unknown setting; expected one of: " + list);
    }
  }
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
  auto require = [&](bool ok, const std::string& field, const std::string& expected) {
    if (!ok) throw InputError(source, field, expected);
  };
  require(width >= 16 && width <= 8192, "camera.width", "expected an image width in [16, 8192] pixels");
  require(height >= 16 && height <= 8192, "camera.height", "expected an image height in [16, 8192] pixels");
  require(std::isfinite(fx) && fx > 1.0, "camera.fx", "expected a focal length > 1 pixel");
  require(std::isfinite(fy) && (fy <= 0 || fy > 1.0), "camera.fy", "expected a focal length > 1 pixel (or <= 0: fx)");
  require(std::isfinite(cx) && cx < width, "camera.cx", "expected a principal point inside the image (or < 0)");
  require(std::isfinite(cy) && cy < height, "camera.cy", "expected a principal point inside the image (or < 0)");
  require(std::isfinite(baseline_m) && baseline_m > 0.001 && baseline_m < 2.0, "camera.baseline_m",
          "expected a baseline in (0.001, 2) metres");
  require(std::isfinite(camera_height_m) && camera_height_m > 0.1 && camera_height_m < 3.0,
          "camera.height_above_floor_m", "expected a camera height in (0.1, 3) metres");
  require(std::isfinite(rate_hz) && rate_hz > 0.5 && rate_hz <= 1000.0, "camera.rate_hz",
          "expected a frame rate in (0.5, 1000] Hz");
  require(std::isfinite(noise_sigma_dn) && noise_sigma_dn >= 0 && noise_sigma_dn <= 50, "sensor.noise_sigma_dn",
          "expected a noise sigma in [0, 50] grey levels");
  require(std::isfinite(exposure_variation) && exposure_variation >= 0 && exposure_variation <= 0.5,
          "sensor.exposure_variation", "expected a relative gain variation in [0, 0.5]");
  require(std::isfinite(vignetting) && vignetting >= 0 && vignetting < 1, "sensor.vignetting",
          "expected a relative corner darkening in [0, 1)");
  require(std::isfinite(max_depth_m) && max_depth_m > 1.0, "rendering.max_depth_m", "expected a depth > 1 metre");
  require(std::isfinite(haze_distance_m), "rendering.haze_distance_m", "expected a number (<= 0: no haze)");
  require(png_compression >= 0 && png_compression <= 9, "rendering.png_compression",
          "expected a zlib level in [0, 9]");
  require(std::isfinite(vibration_deg) && vibration_deg >= 0 && vibration_deg <= 5, "vehicle.vibration_deg",
          "expected a vibration amplitude in [0, 5] degrees");
}

std::vector<std::string> SimConfig::describe() const {
  std::vector<std::string> lines;
  lines.push_back("camera: " + std::to_string(width) + "x" + std::to_string(height) + " grey, fx " +
                  fmt("%.2f", fx) + " fy " + fmt("%.2f", fy_px()) + " cx " + fmt("%.2f", cx_px()) + " cy " +
                  fmt("%.2f", cy_px()) + " px, baseline " + fmt("%.4f", baseline_m) + " m, height " +
                  fmt("%.3f", camera_height_m) + " m above the floor, " + fmt("%.2f", rate_hz) + " Hz");
  lines.push_back("sensor: noise sigma " + fmt("%.2f", noise_sigma_dn) + " DN, exposure variation +-" +
                  fmt("%.1f", 100.0 * exposure_variation) + " %, vignetting " + fmt("%.1f", 100.0 * vignetting) +
                  " %");
  lines.push_back("rendering: max depth " + fmt("%.1f", max_depth_m) + " m, edge antialiasing " +
                  (antialias_edges ? "on" : "off") + ", haze distance " + fmt("%.1f", haze_distance_m) +
                  " m, PNG compression " + std::to_string(png_compression));
  lines.push_back("vehicle: vibration " + fmt("%.2f", vibration_deg) + " deg");
  return lines;
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
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "", "expected a readable YAML file (params/sim.yaml)");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "line " + std::to_string(e.mark.line + 1), "expected valid YAML: " + e.msg);
  }
  SimConfig c;
  if (!root || root.IsNull()) return c;
  check_keys(root, "(top level)", {"camera", "sensor", "rendering", "vehicle"}, path);
  if (const YAML::Node cam = root["camera"]) {
    check_keys(cam, "camera", {"width", "height", "fx", "fy", "cx", "cy", "baseline_m", "height_above_floor_m", "rate_hz"},
               path);
    read_value(cam, "camera", "width", c.width, path, "an integer width in pixels");
    read_value(cam, "camera", "height", c.height, path, "an integer height in pixels");
    read_value(cam, "camera", "fx", c.fx, path, "a number (pixels)");
    read_value(cam, "camera", "fy", c.fy, path, "a number (pixels)");
    read_value(cam, "camera", "cx", c.cx, path, "a number (pixels)");
    read_value(cam, "camera", "cy", c.cy, path, "a number (pixels)");
    read_value(cam, "camera", "baseline_m", c.baseline_m, path, "a number (metres)");
    read_value(cam, "camera", "height_above_floor_m", c.camera_height_m, path, "a number (metres)");
    read_value(cam, "camera", "rate_hz", c.rate_hz, path, "a number (Hz)");
  }
  if (const YAML::Node sensor = root["sensor"]) {
    check_keys(sensor, "sensor", {"noise_sigma_dn", "exposure_variation", "vignetting"}, path);
    read_value(sensor, "sensor", "noise_sigma_dn", c.noise_sigma_dn, path, "a number (grey levels)");
    read_value(sensor, "sensor", "exposure_variation", c.exposure_variation, path, "a number (relative gain)");
    read_value(sensor, "sensor", "vignetting", c.vignetting, path, "a number (relative darkening)");
  }
  if (const YAML::Node rendering = root["rendering"]) {
    check_keys(rendering, "rendering", {"max_depth_m", "antialias_edges", "haze_distance_m", "png_compression"}, path);
    read_value(rendering, "rendering", "max_depth_m", c.max_depth_m, path, "a number (metres)");
    read_value(rendering, "rendering", "antialias_edges", c.antialias_edges, path, "true or false");
    read_value(rendering, "rendering", "haze_distance_m", c.haze_distance_m, path, "a number (metres)");
    read_value(rendering, "rendering", "png_compression", c.png_compression, path, "an integer 0..9");
  }
  if (const YAML::Node vehicle = root["vehicle"]) {
    check_keys(vehicle, "vehicle", {"vibration_deg"}, path);
    read_value(vehicle, "vehicle", "vibration_deg", c.vibration_deg, path, "a number (degrees)");
  }
  c.validate(path);
  return c;
}

}  // namespace agvslam::sim
