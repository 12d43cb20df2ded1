// slam benchmarks: descriptor matching (local map projection, last frame, triangulation search), the Ceres
// motion-only BA and local BA on synthetic stereo data of realistic size, and the whole tracking thread per frame
// (ORB extraction, stereo matching, tracking; System::track_stereo) on the EuRoC excerpt (752x480, 1200 features).
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>

#include "agvslam/io/dataset.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/matcher.h"
#include "agvslam/slam/optimizer.h"
#include "agvslam/slam/system.h"
#include "agvslam/slam/triangulation.h"
#include "slam/synthetic_world.h"

namespace {

namespace fs = std::filesystem;
namespace slam = agvslam::slam;
namespace st = agvslam::slam::test;

slam::StereoIntrinsics intrinsics(const slam::FrameGeometry& g) {
  return {g.camera.fx, g.camera.fy, g.camera.cx, g.camera.cy, g.bf};
}

// A local map of 3000 points seen from frame 0 and a frame 1 to match them into (about 1200 keypoints each).
struct MatchingScene {
  slam::FrameGeometryPtr g = st::test_geometry();
  st::World world = st::make_world(3000, 17, 1.5, 15.0);
  slam::Map map;
  std::vector<slam::MapPointPtr> points;
  slam::Frame f0, f1;
  std::vector<int> p0, p1;
  MatchingScene() {
    st::make_frame(world, st::path_pose(0), g, 0, 0.5, 1, f0, p0);
    st::make_frame(world, st::path_pose(1), g, 1, 0.5, 2, f1, p1);
    for (std::size_t i = 0; i < world.points_w.size(); ++i) {
      auto p = std::make_shared<slam::MapPoint>(i, world.points_w[i], nullptr, 0);
      p->descriptor = world.descriptors[i];
      p->normal_w = (world.points_w[i] - f0.center_w()).normalized();
      p->max_distance_m = static_cast<float>((world.points_w[i] - f0.center_w()).norm());  // seen at level 0 from f0
      p->min_distance_m = p->max_distance_m / 3.6f;
      points.push_back(p);
    }
    for (std::size_t k = 0; k < f0.size(); ++k) f0.map_points[k] = points[static_cast<std::size_t>(p0[k])];
  }
};

void BM_SlamMatchLocalMap(benchmark::State& state) {
  MatchingScene s;
  slam::Matcher matcher;
  std::vector<slam::MapPoint*> local;
  for (const auto& p : s.points) local.push_back(p.get());
  int matches = 0;
  for (auto _ : state) {
    std::fill(s.f1.map_points.begin(), s.f1.map_points.end(), nullptr);
    for (slam::MapPoint* p : local) s.f1.is_in_frustum(*p, 0.5);
    matches = matcher.search_local_points(s.f1, local, 1.0f);
    benchmark::DoNotOptimize(matches);
  }
  state.counters["local_points"] = static_cast<double>(local.size());
  state.counters["keypoints"] = static_cast<double>(s.f1.size());
  state.counters["matches"] = matches;
}
BENCHMARK(BM_SlamMatchLocalMap)->Unit(benchmark::kMillisecond);

void BM_SlamMatchLastFrame(benchmark::State& state) {
  MatchingScene s;
  slam::Matcher matcher;
  int matches = 0;
  for (auto _ : state) {
    std::fill(s.f1.map_points.begin(), s.f1.map_points.end(), nullptr);
    matches = matcher.search_last_frame(s.f1, s.f0, 7.0f, true);
    benchmark::DoNotOptimize(matches);
  }
  state.counters["keypoints"] = static_cast<double>(s.f1.size());
  state.counters["matches"] = matches;
}
BENCHMARK(BM_SlamMatchLastFrame)->Unit(benchmark::kMillisecond);

void BM_SlamTriangulationSearch(benchmark::State& state) {
  const slam::FrameGeometryPtr g = st::test_geometry();
  const st::World world = st::make_world(3000, 18, 1.5, 25.0);
  slam::Frame f1, f2;
  std::vector<int> p1, p2;
  st::make_frame(world, st::path_pose(0), g, 0, 0.3, 1, f1, p1);
  st::make_frame(world, st::path_pose(6), g, 1, 0.3, 2, f2, p2);
  for (std::size_t i = 0; i < f1.size(); i += 3) f1.u_right[i] = f1.depth[i] = -1;  // a third monocular
  slam::KeyFrame kf1(0, f1), kf2(1, f2);
  Eigen::Matrix3d K;
  K << g->camera.fx, 0, g->camera.cx, 0, g->camera.fy, g->camera.cy, 0, 0, 1;
  const Eigen::Matrix3d F12 = slam::fundamental_from_poses(kf1.T_c_w(), kf2.T_c_w(), K);
  slam::Matcher matcher;
  std::vector<std::pair<int, int>> matches;
  for (auto _ : state) {
    matcher.search_for_triangulation(kf1, kf2, F12, matches);
    benchmark::DoNotOptimize(matches.data());
  }
  state.counters["keypoints"] = static_cast<double>(kf1.size());
  state.counters["matches"] = static_cast<double>(matches.size());
}
BENCHMARK(BM_SlamTriangulationSearch)->Unit(benchmark::kMillisecond);

// Motion-only BA: 500 observations (every second one stereo), 10 % gross outliers, 5 cm / 2 degrees off.
void BM_SlamMotionOnlyBa(benchmark::State& state) {
  const slam::FrameGeometryPtr g = st::test_geometry();
  const slam::StereoIntrinsics cam = intrinsics(*g);
  const st::World world = st::make_world(2000, 19);
  const agvslam::SE3d T_true = st::path_pose(3);
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<slam::PoseObservation> obs;
  for (const Eigen::Vector3d& p : world.points_w) {
    if (obs.size() >= 500) break;
    const Eigen::Vector3d p_c = T_true * p;
    if (p_c.z() < 0.5) continue;
    const Eigen::Vector2d uv = g->camera.project(p_c);
    if (!g->in_image(uv.x(), uv.y())) continue;
    slam::PoseObservation o;
    o.p_w = p;
    o.uv_px = uv + Eigen::Vector2d(noise(rng), noise(rng));
    if (unit(rng) < 0.1) o.uv_px += Eigen::Vector2d(30, -20);
    if (obs.size() % 2 == 0) o.u_right_px = o.uv_px.x() - cam.bf / p_c.z();
    obs.push_back(o);
  }
  const agvslam::SE3d T0 =
      agvslam::se3_exp((agvslam::Vector6d() << 0.03, -0.02, 0.03, 0.02, -0.02, 0.01).finished()) * T_true;
  std::vector<uint8_t> outlier;
  slam::MotionOnlyStats stats;
  for (auto _ : state) {
    agvslam::SE3d T = T0;
    stats = slam::optimize_pose(cam, slam::OptimizerConfig{}, obs, outlier, T);
    benchmark::DoNotOptimize(T.data());
  }
  state.counters["observations"] = static_cast<double>(obs.size());
  state.counters["inliers"] = stats.inliers;
  state.counters["iterations"] = stats.iterations;
}
BENCHMARK(BM_SlamMotionOnlyBa)->Unit(benchmark::kMillisecond);

// Local BA: 10 free + 2 fixed keyframes 0.15 m apart, about 2000 points, 3 % gross outliers, 5 + 10 iterations.
// Argument: 1 = DENSE_SCHUR (the default), 0 = SPARSE_SCHUR.
void BM_SlamLocalBa(benchmark::State& state) {
  slam::OptimizerConfig config;
  config.local_ba_dense_schur = state.range(0) != 0;
  const slam::FrameGeometryPtr g = st::test_geometry();
  const slam::StereoIntrinsics cam = intrinsics(*g);
  const st::World world = st::make_world(3000, 20, 1.5, 15.0);
  slam::BaProblem base;
  std::vector<int> index(world.points_w.size(), -1);
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int k = 0; k < 12; ++k) {
    const agvslam::SE3d T = st::path_pose(k);
    base.poses.push_back(
        {k < 2 ? T : agvslam::se3_exp((agvslam::Vector6d() << 0.01, 0, 0.01, 0.002, 0, 0).finished()) * T, k < 2});
    for (std::size_t i = 0; i < world.points_w.size(); ++i) {
      const Eigen::Vector3d p_c = T * world.points_w[i];
      if (p_c.z() < 0.5) continue;
      const Eigen::Vector2d uv = g->camera.project(p_c);
      if (!g->in_image(uv.x(), uv.y()) || unit(rng) < 0.4) continue;  // not every point in every keyframe
      if (index[i] < 0) {
        index[i] = static_cast<int>(base.points_w.size());
        base.points_w.push_back(world.points_w[i] + Eigen::Vector3d(0.02, -0.01, 0.03));
      }
      slam::BaProblem::Observation o;
      o.pose = k;
      o.point = index[i];
      o.uv_px = uv + Eigen::Vector2d(noise(rng), noise(rng));
      if (unit(rng) < 0.03) o.uv_px += Eigen::Vector2d(25, 15);
      if (i % 3 != 0) o.u_right_px = o.uv_px.x() - cam.bf / p_c.z() + noise(rng);
      base.observations.push_back(o);
    }
  }
  slam::BaStats stats;
  for (auto _ : state) {
    slam::BaProblem p = base;
    stats = slam::solve_bundle_adjustment(p, cam, config, 5, 10);
    benchmark::DoNotOptimize(p.points_w.data());
  }
  state.counters["keyframes"] = static_cast<double>(base.poses.size());
  state.counters["points"] = static_cast<double>(base.points_w.size());
  state.counters["observations"] = static_cast<double>(base.observations.size());
  state.counters["iterations"] = stats.iterations;
}
BENCHMARK(BM_SlamLocalBa)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

// The tracking thread on real 752x480 frames: System::track_stereo (ORB, stereo, tracking) with --dynamic off,
// cycling through the EuRoC excerpt (a still camera: no new keyframes; local mapping inline).
void BM_SlamTrackStereoEuroc(benchmark::State& state) {
  const char* env = std::getenv("AGVSLAM_SHARED_DIR");
  const std::string root =
      (fs::path((env && *env) ? env : AGVSLAM_SHARED_DIR_DEFAULT) / "data" / "euroc_v101_f000-094").string();
  if (!fs::exists(root)) {
    state.SkipWithError(("shared data not found: " + root + " (set AGVSLAM_SHARED_DIR)").c_str());
    return;
  }
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::err);
  const agvslam::io::EurocDataset dataset(root);
  spdlog::set_level(level);
  std::vector<agvslam::StereoFrame> frames;
  for (std::size_t i = 0; i < std::min<std::size_t>(dataset.size(), 40); ++i) frames.push_back(dataset.frame(i));
  slam::SystemConfig config;
  config.frame_rate_hz = dataset.rate_hz();
  config.threaded_mapping = false;
  slam::System system(dataset.calibration(), config);
  std::size_t k = 0;
  int64_t t_ns = 0;
  int lost = 0;
  for (auto _ : state) {
    const agvslam::StereoFrame& f = frames[k++ % frames.size()];
    t_ns += 50'000'000;
    const slam::TrackResult r = system.track_stereo(t_ns, f.left, f.right, {});
    lost += r.state == slam::TrackingState::kOk ? 0 : 1;
  }
  state.counters["not_ok_frames"] = lost;
}
BENCHMARK(BM_SlamTrackStereoEuroc)->Unit(benchmark::kMillisecond);

}  // namespace
