// Place-recognition benchmarks: loading the shipped vocabulary (params/vocabulary/agvslam_orb_k10l5.bin), the
// transform of one frame's 1200 ORB descriptors (BoW vector + direct index), keyframe-database queries, and
// training speed. The frames are rendered by the simulator (the static loop, seed 1: 10 places around it) and
// their features extracted with the project's extractor, once.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <random>

#include "agvslam/features/orb_extractor.h"
#include "agvslam/place/keyframe_database.h"
#include "agvslam/place/vocabulary.h"
#include "agvslam/sim/simulator.h"

namespace {
namespace fs = std::filesystem;
namespace place = agvslam::place;

std::string shipped_vocabulary_path() {
  return (fs::path(AGVSLAM_SOURCE_DIR) / "params" / "vocabulary" / "agvslam_orb_k10l5.bin").string();
}

const place::Vocabulary* shipped_vocabulary(benchmark::State& state) {
  static std::unique_ptr<place::Vocabulary> v;
  static std::string error;
  if (!v && error.empty()) {
    try {
      v = std::make_unique<place::Vocabulary>(place::Vocabulary::load(shipped_vocabulary_path()));
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  if (!v) state.SkipWithError(error.c_str());
  return v.get();
}

// ORB descriptors (1200 per frame) of 10 frames around the static loop.
const std::vector<cv::Mat>& loop_descriptors() {
  static const std::vector<cv::Mat> frames = [] {
    agvslam::sim::ScenarioOptions o;
    o.name = "static";
    o.seed = 1;
    o.frames = 10;
    const agvslam::sim::Simulator sim(agvslam::sim::SimConfig{}, o);
    agvslam::features::OrbExtractor extractor;
    agvslam::features::KeypointSet kps;
    agvslam::sim::SimFrame f;
    std::vector<cv::Mat> out;
    for (int k = 0; k < 10; ++k) {
      sim.render_frame(k, f, 1);
      extractor.extract(f.left, cv::Mat(), kps);
      out.push_back(kps.descriptors.clone());
    }
    return out;
  }();
  return frames;
}

void BM_PlaceVocabularyLoad(benchmark::State& state) {
  const place::Vocabulary* shipped = shipped_vocabulary(state);
  if (!shipped) return;
  const std::string path = shipped_vocabulary_path();
  for (auto _ : state) {
    place::Vocabulary v = place::Vocabulary::load(path);
    benchmark::DoNotOptimize(v.identity());
  }
  state.counters["bytes"] = double(fs::file_size(path));
  state.counters["words"] = double(shipped->word_count());
}
BENCHMARK(BM_PlaceVocabularyLoad)->Unit(benchmark::kMillisecond);

// BoW vector and direct index (level 2) of one frame.
void BM_PlaceTransform(benchmark::State& state) {
  const place::Vocabulary* v = shipped_vocabulary(state);
  if (!v) return;
  const auto& frames = loop_descriptors();
  place::BowVector bow;
  place::FeatureVector fv;
  std::size_t i = 0;
  for (auto _ : state) {
    v->transform(frames[i++ % frames.size()], bow, fv, 2);
    benchmark::DoNotOptimize(bow.entries.data());
  }
  state.counters["features"] = double(frames[0].rows);
  state.counters["words_per_frame"] = double(bow.size());
}
BENCHMARK(BM_PlaceTransform)->Unit(benchmark::kMicrosecond);

// Top-candidate query against a database of N keyframes. Keyframes: the 10 frames' descriptors with 0..40 random
// bits flipped per descriptor (so words differ as between nearby views), transformed with the shipped vocabulary.
void BM_PlaceDatabaseQuery(benchmark::State& state) {
  const place::Vocabulary* v = shipped_vocabulary(state);
  if (!v) return;
  const auto& frames = loop_descriptors();
  const auto n = std::size_t(state.range(0));
  place::KeyframeDatabase db(v->word_count());
  std::mt19937_64 rng(1);
  place::BowVector bow;
  for (std::size_t k = 0; k < n; ++k) {
    cv::Mat d = frames[k % frames.size()].clone();
    const int flips = int(rng() % 41);
    for (int r = 0; r < d.rows; ++r)
      for (int b = 0; b < flips; ++b) d.at<uint8_t>(r, int(rng() % 32)) ^= uint8_t(1u << (rng() % 8));
    v->transform(d, bow);
    db.add(k, bow);
  }
  std::vector<place::BowVector> queries(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) v->transform(frames[i], queries[i]);
  place::QueryOptions options;
  options.min_common_words_ratio = 0.8f;
  std::vector<place::Candidate> out;
  std::size_t i = 0;
  for (auto _ : state) {
    db.query(queries[i++ % queries.size()], options, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["keyframes"] = double(n);
  state.counters["candidates"] = double(out.size());
}
BENCHMARK(BM_PlaceDatabaseQuery)->Arg(500)->Arg(2000)->Unit(benchmark::kMicrosecond);

// Training on the 10 frames' 12000 descriptors, k = 10, L = 3 (one thread).
void BM_PlaceTrain12kDescriptors(benchmark::State& state) {
  place::DescriptorSet set;
  for (const auto& d : loop_descriptors()) set.add_image(d);
  place::VocabularyTrainingConfig cfg;
  cfg.levels = 3;
  for (auto _ : state) {
    const place::Vocabulary v = place::Vocabulary::train(set, cfg);
    benchmark::DoNotOptimize(v.identity());
  }
  state.counters["descriptors"] = double(set.size());
}
BENCHMARK(BM_PlaceTrain12kDescriptors)->Unit(benchmark::kMillisecond);

}  // namespace
