// The pipeline as agvslam-run drives it (PipelineOptions): a dataset played losslessly hands every frame, in
// order, to the frame hook, with the ground-truth mask as the tracking mask when asked (and no mask otherwise), no
// detector times without a detector, and ends by itself once the source ended (finished, nothing failed).
#include "agvslam/daemon/pipeline.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <mutex>
#include <vector>

#include "agvslam/features/features_config.h"
#include "daemon_test_util.h"

namespace agvslam::daemon {
namespace {

// What the hook saw of one frame.
struct Seen {
  int64_t source_index;
  int lap;
  int64_t t_ns;
  int mask_pixels;  // -1: no mask
  double detector_ms;
};

// A dataset played as fast as the pipeline takes it, without detector, threads for mapping or DDS: deterministic.
DaemonConfig lossless_dataset_config(const std::string& dir) {
  DaemonConfig c;
  c.path = "test.yaml";
  c.source.type = SourceType::kDataset;
  c.source.dataset = dir;
  c.source.rate = 0;
  c.pipeline.dynamic = DynamicMode::kOff;
  c.pipeline.mapping = MappingMode::kInline;
  c.system.threaded_mapping = false;
  c.outputs.dds_enabled = false;
  return c;
}

std::vector<Seen> play(const std::string& dir, bool ground_truth_masks) {
  const DaemonConfig c = lossless_dataset_config(dir);
  const SourceSetup setup = prepare_source(c);
  DatasetPlayback playback;
  playback.laps = 2;
  playback.ground_truth_masks = true;
  std::vector<Seen> seen;
  PipelineOptions options;
  options.ground_truth_masks = ground_truth_masks;
  options.settle_mapping = true;
  options.on_tracked = [&](const TrackedFrame& f) {
    seen.push_back({f.captured.source_index, f.captured.lap, f.captured.frame.t_ns,
                    f.mask.empty() ? -1 : cv::countNonZero(f.mask), f.times.detector_ms});
  };
  Pipeline pipeline(c, setup, std::make_unique<DatasetSource>(setup, c.source, playback), std::move(options));
  pipeline.start();
  pipeline.wait();
  EXPECT_TRUE(pipeline.finished());
  EXPECT_FALSE(pipeline.failed()) << pipeline.error();
  EXPECT_EQ(pipeline.stats().processed, seen.size());
  return seen;
}

TEST(Pipeline, PlaysEveryFrameInOrderThroughTheHookWithTheGroundTruthMaskWhenAsked) {
  const std::string dir = test::tiny_dataset(4, /*with_masks=*/true);
  for (bool ground_truth_masks : {true, false}) {
    const std::vector<Seen> seen = play(dir, ground_truth_masks);
    ASSERT_EQ(seen.size(), 8U);
    for (std::size_t k = 0; k < seen.size(); ++k) {
      EXPECT_EQ(seen[k].source_index, static_cast<int64_t>(k % 4)) << k;
      EXPECT_EQ(seen[k].lap, static_cast<int>(k / 4)) << k;
      EXPECT_EQ(seen[k].t_ns, static_cast<int64_t>(k) * 50000000) << k;  // laps continue the stamps
      EXPECT_EQ(seen[k].mask_pixels, ground_truth_masks ? 48 : -1) << k;
      EXPECT_LT(seen[k].detector_ms, 0.0) << k;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Pipeline, ALongLossStartsANewMapAndTheSamplesCarryItsId) {
  // KITTI 06 with frames 10..25 covered: relocalisation cannot reach the old map 17 m back, and after
  // slam.tracking.new_map_after_lost_s of real views a new map starts (tests/slam). The outputs' samples (the DDS
  // status, the JSON log) carry map_id 0 before, 1 from the new map on.
  AGVSLAM_REQUIRE_SHARED(data, "data/kitti06_f000-050");
  const std::string dir = test::make_temp_dir("agvslamd-newmap");
  DaemonConfig c = lossless_dataset_config(data);
  const features::FeaturesConfig f = features::load_features_config(AGVSLAM_SOURCE_DIR "/params/features_kitti.yaml");
  c.system.orb = f.orb;
  c.system.stereo = f.stereo_matching;
  c.log.pose_log = dir + "/samples.jsonl";
  const SourceSetup setup = prepare_source(c);
  DatasetPlayback playback;
  playback.blank = std::make_pair(std::size_t{10}, std::size_t{25});
  std::vector<uint32_t> map_ids;
  PipelineOptions options;
  options.settle_mapping = true;
  options.on_tracked = [&](const TrackedFrame& t) { map_ids.push_back(t.result.map_id); };
  Pipeline pipeline(c, setup, std::make_unique<DatasetSource>(setup, c.source, playback), std::move(options));
  pipeline.start();
  pipeline.wait();
  ASSERT_FALSE(pipeline.failed()) << pipeline.error();
  ASSERT_FALSE(map_ids.empty());
  ASSERT_EQ(map_ids.back(), 1u) << "no new map after the loss";
  std::size_t samples = 0, in_new_map = 0;
  uint32_t previous = 0;
  for (const nlohmann::json& line : test::read_json_lines(c.log.pose_log)) {
    if (line.at("heartbeat").get<bool>()) continue;
    const uint32_t id = line.at("sample").at("map_id").get<uint32_t>();
    const int64_t index = line.at("source_index").get<int64_t>();
    ASSERT_GE(index, 0);
    EXPECT_EQ(id, map_ids.at(static_cast<std::size_t>(index))) << "frame " << index;
    EXPECT_GE(id, previous) << "frame " << index;
    if (index <= 25) {
      EXPECT_EQ(id, 0u) << "frame " << index;
    }
    previous = id;
    ++samples;
    if (id == 1) ++in_new_map;
  }
  EXPECT_GT(samples, 40u);
  EXPECT_GT(in_new_map, 0u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace agvslam::daemon
