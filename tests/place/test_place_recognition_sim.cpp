// Place recognition with the shipped vocabulary on simulator sequences rendered at test time, in warehouses the
// vocabulary never saw (training used seeds 900-960): relocalisation in a saved warehouse with other people and
// another start, and loop revisits at the end of a lap. One test (each ctest test is its own process, and the
// rendering is the slow part).
#include <gtest/gtest.h>

#include "agvslam/features/orb_extractor.h"
#include "agvslam/place/place_config.h"
#include "agvslam/place/revisit_evaluation.h"
#include "agvslam/place/vocabulary.h"
#include "agvslam/sim/simulator.h"

namespace agvslam::place {
namespace {

// Left-camera samples of a scenario (poses in the warehouse's map frame, so two runs of one layout compare).
std::vector<PlaceSample> render_samples(const Vocabulary& v, const std::string& scenario, uint64_t seed,
                                        uint64_t layout_seed, double start_offset_m, int frames) {
  sim::ScenarioOptions o;
  o.name = scenario;
  o.seed = seed;
  o.layout_seed = layout_seed;
  o.start_offset_m = start_offset_m;
  o.squeeze_to_frames = frames;  // the whole route over `frames` frames
  const sim::Simulator sim(sim::SimConfig{}, o);
  features::OrbExtractor extractor;
  features::KeypointSet kps;
  sim::SimFrame f;
  FeatureVector fv;
  std::vector<PlaceSample> out(static_cast<std::size_t>(frames));
  for (int k = 0; k < frames; ++k) {
    sim.render_frame(k, f, 2);
    extractor.extract(f.left, cv::Mat(), kps);
    auto& s = out[static_cast<std::size_t>(k)];
    v.transform(kps.descriptors, s.bow, fv, 2);
    s.T_w_c = sim.T_map_cam(k);
    s.t_ns = f.t_ns;
  }
  return out;
}

TEST(PlaceRecognitionSim, RelocalisationAndLoopRevisitsWithTheShippedVocabulary) {
  const PlaceConfig config = load_place_config(std::string(AGVSLAM_SOURCE_DIR) + "/params/place.yaml");
  const Vocabulary vocabulary = Vocabulary::load(config.vocabulary_file);
  // The map run: the whole static loop (28.7 m) over 100 frames, ~0.29 m apart.
  const auto map = render_samples(vocabulary, "static", 51, 51, 0.0, 100);
  // The second run through the same warehouse: other people (scene5: one walks ahead all the way), starting 5 m
  // further along the loop; 50 frames over the whole lap.
  const auto query = render_samples(vocabulary, "scene5", 52, 51, 5.0, 50);

  {
    SCOPED_TRACE("relocalisation");
    const RevisitCriteria criteria;  // 1 m, 20 degrees
    const RevisitEvaluation e = evaluate_relocalisation(map, query, criteria, vocabulary.word_count());
    // Nearly every query has a map frame within 1 m and 20 degrees (the corners turn faster than the sampling).
    EXPECT_GE(e.positives, 40);
    float t = 0;
    const double recall = e.recall_at_precision(0.95, &t);
    std::size_t correct = 0;
    for (const auto& q : e.queries) correct += q.correct;
    RecordProperty("relocalisation_recall_at_precision_0_95", std::to_string(recall));
    RecordProperty("relocalisation_top1_correct", std::to_string(correct) + " of " + std::to_string(e.positives));
    EXPECT_GE(recall, 0.9) << "threshold " << t << ", AP " << e.average_precision;
    EXPECT_GE(double(correct), 0.9 * e.positives) << "top-1 correct for " << correct << " of " << e.positives;
  }
  {
    SCOPED_TRACE("loop revisits");
    // The lap lasts 5 s: the database holds frames at least 2.5 s older than the query.
    RevisitCriteria criteria;
    criteria.min_time_gap_s = 2.5;
    const RevisitEvaluation e = evaluate_loop_revisits(map, criteria, vocabulary.word_count());
    EXPECT_GE(e.positives, 3);
    RecordProperty("loop_positives", std::to_string(e.positives));
    RecordProperty("loop_recall_at_precision_1", std::to_string(e.recall_at_precision(1.0)));
    // A revisit at the end of the lap is found before any false answer (precision 1 at some recall).
    EXPECT_GT(e.recall_at_precision(1.0), 0.0) << "AP " << e.average_precision;
  }
}

}  // namespace
}  // namespace agvslam::place
