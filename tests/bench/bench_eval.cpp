// Evaluation cost on long trajectories (a 30-minute run at 20 Hz is 36,000 poses).
#include <benchmark/benchmark.h>

#include <cmath>

#include "agvslam/eval/metrics.h"

namespace {

using namespace agvslam;

eval::PosePairs make_pairs(int n) {
  eval::PosePairs pairs;
  double yaw = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const SE3d T = make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())), p);
    SE3d T_est = T;
    T_est.translation() += Eigen::Vector3d(0.01 * std::sin(i), 0, 0.01 * std::cos(i));
    pairs.t_ns.push_back(static_cast<int64_t>(i) * 50'000'000);
    pairs.T_w_c_gt.push_back(T);
    pairs.T_w_c_est.push_back(T_est);
    yaw += 0.002 * std::sin(i * 0.01);
    p += 0.05 * Eigen::Vector3d(std::sin(yaw), 0, std::cos(yaw));
  }
  return pairs;
}

void BM_Eval_Ate(benchmark::State& state) {
  const eval::PosePairs pairs = make_pairs(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(eval::compute_ate(pairs, eval::AlignMode::kSE3).translation_m.rmse);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Eval_Ate)->Arg(36000)->Unit(benchmark::kMillisecond);

void BM_Eval_KittiSegments(benchmark::State& state) {
  const eval::PosePairs pairs = make_pairs(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(eval::compute_kitti_relative(pairs));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_Eval_KittiSegments)->Arg(36000)->Unit(benchmark::kMillisecond);

}  // namespace
