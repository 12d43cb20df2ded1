#include "agvslam/sim/simulator.h"
#include "agvslam/sim/wheel_odometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/io/calibration_io.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/sim/cpu_dispatch.h"
#include "agvslam/sim/png_writer.h"
#include "agvslam/sim/random.h"
#include "agvslam/sim/texture.h"

namespace agvslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kExposureBase = 1.12;  // radiance 1 -> 285 DN (saturates): keeps typical surfaces mid-grey

// Smooth 1-D noise in [-1, 1].
double noise_1d(double x, uint32_t seed) {
  const double f = std::floor(x);
  const int32_t i = static_cast<int32_t>(f);
  double t = x - f;
  t = t * t * (3 - 2 * t);
  const double a = unit_from_hash(hash32(static_cast<uint32_t>(i), seed));
  const double b = unit_from_hash(hash32(static_cast<uint32_t>(i + 1), seed));
  return 2.0 * (a + (b - a) * t) - 1.0;
}

// Sensor model of image row v: global gain, vignetting, read noise, 8-bit quantisation.
AGVSLAM_SIM_CLONES void expose_row(const float* rad, uint8_t* px, int width, int v, float gain, float sigma,
                                   float vignetting, float cx, float cy, float r2_corner, uint32_t cam_seed) {
  const float dy = static_cast<float>(v) - cy;
  for (int u = 0; u < width; ++u) {
    const float dx = static_cast<float>(u) - cx;
    const float vig = 1.0f - vignetting * (dx * dx + dy * dy) / r2_corner;
    // Approximately Gaussian noise: sum of four 16-bit uniforms (Irwin-Hall), unit variance.
    const uint32_t pixel = static_cast<uint32_t>(v * width + u);
    const uint32_t h1 = hash32(pixel, cam_seed), h2 = hash32(pixel ^ 0x5bd1e995U, cam_seed + 0x68e31da4U);
    const float sum = static_cast<float>((h1 & 0xffffU) + (h1 >> 16) + (h2 & 0xffffU) + (h2 >> 16)) * (1.0f / 65536.0f);
    const float noise = (sum - 2.0f) * 1.7320508f * sigma;
    const float value = rad[u] * gain * vig + noise;
    px[u] = static_cast<uint8_t>(value <= 0.0f ? 0 : (value >= 254.5f ? 255 : static_cast<int>(value + 0.5f)));
  }
}

// Mean lighting of the floor and of walls facing the four horizontal directions (RenderSettings' model).
float mean_lighting(const RenderSettings& s) {
  float sum = s.ambient + s.sky + s.sun * std::max(0.0f, s.sun_dir.z);
  for (const V3 n : {V3{1, 0, 0}, V3{-1, 0, 0}, V3{0, 1, 0}, V3{0, -1, 0}})
    sum += s.ambient + s.sun * std::max(0.0f, dot(n, s.sun_dir));
  return sum / 5.0f;
}

// The renderer's settings. The hall's lighting varies between warehouses (layout seeds): the key light's
// strength against the ambient light and its direction (35 to 70 degrees above the horizon, any azimuth). The
// lights are then scaled to the default mean lighting, as an auto-exposed camera sees the same mean brightness
// in any hall; brightness varies through the camera's exposure (SimConfig::exposure_spread).
RenderSettings render_settings(const SimConfig& c, uint64_t layout_seed) {
  RenderSettings s;
  s.antialias_edges = c.antialias_edges;
  s.haze_distance_m = static_cast<float>(c.haze_distance_m);
  if (c.lighting_variation > 0) {
    const float nominal = mean_lighting(s);
    Rng light(layout_seed, RngStream::kLighting);
    const float spread = static_cast<float>(c.lighting_variation);
    const float key = 1.0f + spread * static_cast<float>(light.uniform(-1.0, 1.0));
    const float ambient = 1.0f + 0.5f * spread * static_cast<float>(light.uniform(-1.0, 1.0));
    const double azimuth = light.uniform(0.0, 2 * kPi), elevation = light.uniform(35.0, 70.0) * kPi / 180.0;
    s.ambient *= ambient;
    s.sun *= key;
    s.sun_dir = normalized(V3{static_cast<float>(std::cos(azimuth) * std::cos(elevation)),
                              static_cast<float>(std::sin(azimuth) * std::cos(elevation)),
                              static_cast<float>(std::sin(elevation))});
    const float level = nominal / mean_lighting(s);
    s.ambient *= level;
    s.sky *= level;
    s.sun *= level;
  }
  return s;
}

std::string frame_name(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06d.png", frame);
  return buf;
}

}  // namespace

Simulator::Simulator(const SimConfig& config, const ScenarioOptions& options)
    : config_((config.validate("simulator settings"), config)),
      warehouse_(generate_warehouse(options.effective_layout_seed())),
      scenario_(make_scenario(options, warehouse_, config.rate_hz)),
      renderer_(warehouse_, render_settings(config, options.effective_layout_seed())) {
  Rng sensor(options.seed, RngStream::kSensor);
  sensor_seed_ = sensor.next_u64();
  exposure_phase_[0] = sensor.uniform(0.0, 2 * kPi);
  exposure_phase_[1] = sensor.uniform(0.0, 2 * kPi);
  exposure_base_ = 1.0 + config.exposure_spread * sensor.uniform(-1.0, 1.0);
  Rng vehicle(options.seed, RngStream::kVehicle);
  vibration_seed_ = vehicle.next_u32();
  T_w_map_ = T_map_cam(0).inverse();
}

CameraIntrinsics Simulator::intrinsics() const {
  CameraIntrinsics cam;
  cam.fx = config_.fx;
  cam.fy = config_.fy_px();
  cam.cx = config_.cx_px();
  cam.cy = config_.cy_px();
  cam.width = config_.width;
  cam.height = config_.height;
  return cam;
}

int64_t Simulator::timestamp_ns(int frame) const { return s_to_ns(frame / config_.rate_hz); }

Eigen::Isometry3d Simulator::T_map_cam(int frame) const {
  double x, y, yaw, s;
  scenario_.agv.planar_pose(scenario_.scenario_time(frame), x, y, yaw, s);
  // Vehicle frame: x forward, y left, z up. Camera: x right, y down, z forward.
  Eigen::Matrix3d R_v_c;
  R_v_c << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  // Vibration: pitch and roll from floor irregularities along the distance travelled, scaled by the speed
  // (none while the AGV stands, so the first pose is level and a loop ends exactly where it started).
  double speed_ratio = 0;
  if (!scenario_.agv.stationary && scenario_.agv.profile.cruise_mps > 0)
    speed_ratio = scenario_.agv.profile.speed_at(scenario_.scenario_time(frame)) / scenario_.agv.profile.cruise_mps;
  const double amp = config_.vibration_deg * kPi / 180.0 * speed_ratio;
  auto vib = [&](double dist, uint32_t seed) {
    return 0.65 * noise_1d(dist / 0.55, seed) + 0.35 * noise_1d(dist / 0.21, seed + 1U);
  };
  const double pitch = amp * vib(s, vibration_seed_);
  const double roll = 0.6 * amp * vib(s, vibration_seed_ + 7U);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_v_c *
               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()).toRotationMatrix() *
               Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, config_.camera_height_m);
  return T;
}

Trajectory Simulator::ground_truth() const {
  Trajectory traj;
  traj.reserve(static_cast<std::size_t>(frame_count()));
  for (int k = 0; k < frame_count(); ++k) traj.push_back({timestamp_ns(k), T_w_c(k)});
  return traj;
}

double Simulator::exposure_gain(int frame) const {
  const double t = frame / config_.rate_hz;
  const double a = config_.exposure_variation;
  return exposure_base_ * (1.0 + a * (0.6 * std::sin(2 * kPi * t / 9.7 + exposure_phase_[0]) +
                                      0.4 * std::sin(2 * kPi * t / 3.9 + exposure_phase_[1])));
}

std::vector<std::pair<int, int>> Simulator::moving_frames(const Actor& actor) const {
  std::vector<std::pair<int, int>> ranges;
  for (int k = 0; k < frame_count(); ++k) {
    if (!actor_state(actor, scenario_.scenario_time(k)).moving) continue;
    if (!ranges.empty() && ranges.back().second == k - 1)
      ranges.back().second = k;
    else
      ranges.emplace_back(k, k);
  }
  return ranges;
}

void Simulator::pose_objects(int frame, std::vector<DynamicObject>& out) const {
  const double t = scenario_.scenario_time(frame);
  const std::size_t n = scenario_.actors.size();
  std::size_t parts = n;
  for (const Actor& a : scenario_.actors) parts += static_cast<std::size_t>(trailer_count(a));
  out.resize(parts);
  std::size_t next = n;  // trailers after the actors, so out[i] is actor i
  for (std::size_t i = 0; i < n; ++i) {
    const Actor& a = scenario_.actors[i];
    const ActorState st = actor_state(a, t);
    pose_actor(a, st, out[i]);
    for (int k = 0; k < trailer_count(a); ++k) pose_trailer(a, st, k, out[next++]);
  }
}

void Simulator::render_frame(int frame, SimFrame& out, int threads) const {
  out.index = frame;
  out.t_ns = timestamp_ns(frame);
  out.T_w_c = T_w_c(frame);
  out.exposure_gain = exposure_gain(frame);
  pose_objects(frame, out.posed_objects);
  const CameraIntrinsics cam = intrinsics();
  const Eigen::Isometry3d T_m_c0 = T_map_cam(frame);
  Eigen::Isometry3d T_c0_c1 = Eigen::Isometry3d::Identity();
  T_c0_c1.translation() = Eigen::Vector3d(config_.baseline_m, 0, 0);
  renderer_.render(cam, T_m_c0, out.posed_objects, out.left_render, threads);
  renderer_.render(cam, T_m_c0 * T_c0_c1, out.posed_objects, out.right_render, threads);

  // Sensor: global gain (same for both cameras), vignetting, read noise, 8-bit quantisation.
  const int width = cam.width, height = cam.height;
  const float gain = static_cast<float>(255.0 * kExposureBase * out.exposure_gain);
  const float sigma = static_cast<float>(config_.noise_sigma_dn);
  const float vignetting = static_cast<float>(config_.vignetting);
  const float cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  const float r2_corner = cx * cx + cy * cy;
  const uint32_t frame_seed = static_cast<uint32_t>(hash64(sensor_seed_, static_cast<uint64_t>(frame)));
  for (int c = 0; c < 2; ++c) {
    const cv::Mat& radiance = c == 0 ? out.left_render.radiance : out.right_render.radiance;
    cv::Mat& image = c == 0 ? out.left : out.right;
    image.create(height, width, CV_8UC1);
    const uint32_t cam_seed = hash32(frame_seed, static_cast<uint32_t>(c + 1));
    for (int v = 0; v < height; ++v)
      expose_row(radiance.ptr<float>(v), image.ptr<uint8_t>(v), width, v, gain, sigma, vignetting, cx, cy, r2_corner,
                 cam_seed);
  }

  // Ground truth from the left camera.
  const double bf = config_.fx * config_.baseline_m;
  const double max_depth = config_.max_depth_m;
  out.disparity_u16.create(height, width, CV_16UC1);
  out.mask.create(height, width, CV_8UC1);
  out.instances.create(height, width, CV_8UC1);
  int max_id = 0;
  for (const auto& o : out.posed_objects) max_id = std::max(max_id, o.id);
  if (max_id > 255) {
    throw InputError("scenario", "actor id " + std::to_string(max_id),
                     "expected actor ids of at most 255 (instance_0/ holds them in 8-bit PNGs)");
  }
  std::vector<int> moving_by_id(static_cast<std::size_t>(max_id) + 1, 0);
  std::vector<int> slot_by_id(static_cast<std::size_t>(max_id) + 1, -1);
  for (std::size_t i = 0; i < out.posed_objects.size(); ++i) {
    moving_by_id[static_cast<std::size_t>(out.posed_objects[i].id)] = out.posed_objects[i].moving ? 1 : 0;
    slot_by_id[static_cast<std::size_t>(out.posed_objects[i].id)] = static_cast<int>(i);
  }
  std::vector<VisibleObject> boxes(static_cast<std::size_t>(max_id) + 1);
  for (int v = 0; v < height; ++v) {
    const float* depth = out.left_render.depth_m.ptr<float>(v);
    const uint16_t* ids = out.left_render.object_id.ptr<uint16_t>(v);
    uint16_t* disp = out.disparity_u16.ptr<uint16_t>(v);
    uint8_t* mask = out.mask.ptr<uint8_t>(v);
    uint8_t* instance = out.instances.ptr<uint8_t>(v);
    for (int u = 0; u < width; ++u) {
      const double z = depth[u];
      uint16_t d16 = 0;
      if (z > 0 && z <= max_depth) {
        const double scaled = std::round(bf / z * 256.0);
        if (scaled >= 1.0 && scaled <= 65535.0) d16 = static_cast<uint16_t>(scaled);
      }
      disp[u] = d16;
      const int id = ids[u];
      mask[u] = (id > 0 && id <= max_id && moving_by_id[static_cast<std::size_t>(id)]) ? 255 : 0;
      instance[u] = (id > 0 && id <= max_id) ? static_cast<uint8_t>(id) : 0;
      if (id > 0 && id <= max_id) {
        VisibleObject& b = boxes[static_cast<std::size_t>(id)];
        if (b.pixel_count == 0) {
          b.x_min = b.x_max = u;
          b.y_min = b.y_max = v;
        } else {
          b.x_min = std::min(b.x_min, u);
          b.x_max = std::max(b.x_max, u);
          b.y_min = std::min(b.y_min, v);
          b.y_max = std::max(b.y_max, v);
        }
        ++b.pixel_count;
      }
    }
  }
  out.left_render.class_id.copyTo(out.classes);
  out.objects.clear();
  for (int id = 1; id <= max_id; ++id) {
    VisibleObject b = boxes[static_cast<std::size_t>(id)];
    if (b.pixel_count == 0 || slot_by_id[static_cast<std::size_t>(id)] < 0) continue;
    const DynamicObject& o = out.posed_objects[static_cast<std::size_t>(slot_by_id[static_cast<std::size_t>(id)])];
    b.id = id;
    b.cls = o.cls;
    b.moving = o.moving;
    out.objects.push_back(b);
  }
}

// ---- Writing ------------------------------------------------------------------------------------------------

void prepare_output_dir(const std::string& dir, const std::string& option) {
  namespace fs = std::filesystem;
  if (dir.empty()) throw InputError(option, "''", "expected an output folder path");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(option, dir, "expected a folder, but this path is an existing file");
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(option, dir,
                     "could not create the output folder: " + (ec ? ec.message() : std::string("unknown")));
  for (const char* sub : {"image_0", "image_1", "disp_0", "mask_0", "instance_0", "class_0"}) {
    fs::create_directories(fs::path(dir) / sub, ec);
    if (ec) throw InputError(option, (fs::path(dir) / sub).string(), "could not create the folder: " + ec.message());
  }
  const fs::path probe = fs::path(dir) / ".agvslam-sim-write-test";
  {
    std::ofstream f(probe);
    f << "probe\n";
    if (!f.good()) throw InputError(option, dir, "expected a writable folder (cannot create files in it)");
  }
  fs::remove(probe, ec);
}

std::string objects_header() {
  return "# frame id class moving x_min y_min x_max y_max  (class: person|forklift|agv|pallet; moving: 1 = moving at "
         "this frame; bbox of the visible pixels in image_0, inclusive, pixels)";
}

std::string format_objects(int frame, const std::vector<VisibleObject>& objects) {
  std::string s;
  char buf[160];
  for (const auto& o : objects) {
    std::snprintf(buf, sizeof(buf), "%d %d %s %d %d %d %d %d\n", frame, o.id, to_string(o.cls).c_str(),
                  o.moving ? 1 : 0, o.x_min, o.y_min, o.x_max, o.y_max);
    s += buf;
  }
  return s;
}

void write_sequence(const Simulator& sim, const std::string& out_dir, const WriteOptions& options) {
  namespace fs = std::filesystem;
  prepare_output_dir(out_dir);
  const fs::path root(out_dir);
  io::write_kitti_calib((root / "calib.txt").string(), sim.calibration());
  std::vector<int64_t> times;
  for (int k = 0; k < sim.frame_count(); ++k) times.push_back(sim.timestamp_ns(k));
  io::write_kitti_times((root / "times.txt").string(), times);
  const Trajectory gt = sim.ground_truth();
  io::write_kitti_poses((root / "poses.txt").string(), gt);
  // What a differential-drive AGV's wheel encoders would report: the baseline every SLAM result is compared to.
  io::write_tum((root / "odometry.txt").string(),
                simulate_wheel_odometry(gt, WheelOdometryConfig{}, sim.scenario().seed));

  // One fixed PNG row filter per image kind (see png_writer.h).
  PngWriter png(sim.config().png_compression);
  std::string objects = objects_header() + "\n";
  SimFrame frame;
  for (int k = 0; k < sim.frame_count(); ++k) {
    sim.render_frame(k, frame, options.threads);
    const std::string name = frame_name(k);
    png.write((root / "image_0" / name).string(), frame.left, PngFilter::kPaeth);
    png.write((root / "image_1" / name).string(), frame.right, PngFilter::kPaeth);
    png.write((root / "disp_0" / name).string(), frame.disparity_u16, PngFilter::kPaeth);
    png.write((root / "mask_0" / name).string(), frame.mask, PngFilter::kNone);
    png.write((root / "instance_0" / name).string(), frame.instances, PngFilter::kNone);
    png.write((root / "class_0" / name).string(), frame.classes, PngFilter::kNone);
    objects += format_objects(k, frame.objects);
    if (options.progress) options.progress(k + 1, sim.frame_count());
  }
  io::write_file_atomically((root / "objects.txt").string(), objects);
}

}  // namespace agvslam::sim
