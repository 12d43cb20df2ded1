// Pose output benchmarks: CAN frame encoding, ROS 2 message filling, and the DDS publish cost on the caller's
// thread (publish(): queue hand-over; write_now(): serialise and write the three topics). DDS cases run pinned
// to lo in a domain of their own. The publish -> receive latency between two processes is measured by
// tests/drivers/dds_latency.sh (agvslam-pose-replay -> agvslam-echo under unshare -n).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <memory>

#include "agvslam/drivers/can/pose_frames.h"
#include "agvslam/drivers/dds/publisher.h"
#include "agvslam/drivers/pose_sample.h"

namespace {

namespace drv = agvslam::drivers;

void BM_DriversCanEncodeClassic(benchmark::State& state) {
  const drv::PoseSample s = drv::synthetic_pose_sample(17, 1700000000000000000LL);
  std::array<drv::can::CanFrameBytes, drv::can::kMaxClassicFrames> frames;
  uint8_t counter = 0;
  for (auto _ : state) {
    const std::size_t n =
        drv::can::encode_classic_frames(s, counter++, drv::can::FrameLayout{}, true, true, true, frames);
    benchmark::DoNotOptimize(n);
    benchmark::DoNotOptimize(frames.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("5 frames per pose");
}
BENCHMARK(BM_DriversCanEncodeClassic);

void BM_DriversCanEncodeFd(benchmark::State& state) {
  const drv::PoseSample s = drv::synthetic_pose_sample(17, 1700000000000000000LL);
  uint8_t counter = 0;
  for (auto _ : state) {
    auto f = drv::can::encode_fd_frame(s, counter++, drv::can::FrameLayout{});
    benchmark::DoNotOptimize(f);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DriversCanEncodeFd);

void BM_DriversDdsFillMessages(benchmark::State& state) {
  const drv::PoseSample s = drv::synthetic_pose_sample(17, 1700000000000000000LL);
  const drv::dds::FrameIds frames;
  drv::dds::PoseMsg p{};
  drv::dds::OdomMsg o{};
  drv::dds::StatusMsg st{};
  for (auto _ : state) {
    drv::dds::fill_pose_msg(s, frames, p);
    drv::dds::fill_odom_msg(s, frames, o);
    drv::dds::fill_status_msg(s, frames, st);
    benchmark::DoNotOptimize(&p);
    benchmark::DoNotOptimize(&o);
    benchmark::DoNotOptimize(&st);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DriversDdsFillMessages);

drv::dds::DdsConfig bench_dds_config(int offset) {
  drv::dds::DdsConfig cfg;
  cfg.domain_id = 20 + static_cast<int>((getpid() + offset) % 200);
  cfg.network_interface = "lo";
  cfg.topic_namespace = "agvslam_bench";
  return cfg;
}

// Serialise and write pose, odom and status (no subscriber: the cost the publisher thread pays per pose).
void BM_DriversDdsWriteNow(benchmark::State& state) {
  std::unique_ptr<drv::dds::DdsPosePublisher> pub;
  try {
    pub = std::make_unique<drv::dds::DdsPosePublisher>(bench_dds_config(0), false);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  drv::PoseSample s = drv::synthetic_pose_sample(17, 1700000000000000000LL);
  for (auto _ : state) {
    s.t_ns += 50000000;
    benchmark::DoNotOptimize(pub->write_now(s));
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("3 topics");
}
BENCHMARK(BM_DriversDdsWriteNow);

// What the tracker's thread pays: copy into the bounded queue and wake the publisher thread.
void BM_DriversDdsPublishEnqueue(benchmark::State& state) {
  std::unique_ptr<drv::dds::DdsPosePublisher> pub;
  try {
    pub = std::make_unique<drv::dds::DdsPosePublisher>(bench_dds_config(1), true);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  drv::PoseSample s = drv::synthetic_pose_sample(17, 1700000000000000000LL);
  for (auto _ : state) {
    s.t_ns += 50000000;
    benchmark::DoNotOptimize(pub->publish(s));
  }
  const auto st = pub->stats();
  state.counters["dropped_fraction"] =
      st.submitted > 0 ? static_cast<double>(st.dropped_queue_full) / static_cast<double>(st.submitted) : 0.0;
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DriversDdsPublishEnqueue);

}  // namespace
