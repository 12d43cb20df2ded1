#pragma once
// Place-recognition precision/recall on sequences with ground-truth poses (the vocabulary's quality figure).
//
// Two frames show the same place ("revisit") when their cameras are within max_distance_m of each other and
// their orientations within max_angle_deg (angle of the relative rotation). Each query frame asks a
// KeyframeDatabase for its top-1 candidate; a query is *positive* when the database holds at least one revisit
// of it, and its answer is *correct* when the top-1 candidate is one. At a score threshold t the answers with
// score >= t are accepted: precision = correct accepted / accepted, recall = correct accepted / positive queries.
//
//   loop revisits (loop closing): one sequence; frame i queries the frames at least min_time_gap_s older.
//   relocalisation: the frames of a map sequence are the database, every frame of another sequence through the
//     same place (poses in the same frame) is a query.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "agvslam/core/se3.h"
#include "agvslam/place/bow_vector.h"

namespace agvslam::place {

struct RevisitCriteria {
  double max_distance_m = 1.0;
  double max_angle_deg = 20.0;
  double min_time_gap_s = 10.0;  // loop revisits only: how much older than the query a database frame must be

  std::string describe() const;
};

struct PlaceSample {
  BowVector bow;
  SE3d T_w_c = SE3d::Identity();  // camera pose (all samples compared must share the world frame)
  int64_t t_ns = 0;
};

struct QueryOutcome {
  std::size_t query = 0;
  long match = -1;              // database index of the top-1 candidate; -1: no frame shares a word
  float score = 0;              // its L1 score
  bool positive = false;        // the database holds a revisit of the query
  bool correct = false;         // the top-1 candidate is a revisit
  double match_distance_m = 0;  // camera distance and relative rotation to the top-1 candidate
  double match_angle_deg = 0;
};

struct PrPoint {
  float threshold = 0;  // scores >= threshold accepted
  int true_positives = 0, false_positives = 0;
  double precision = 1, recall = 0;
};

struct RevisitEvaluation {
  std::vector<QueryOutcome> queries;
  int positives = 0;             // positive queries
  std::vector<PrPoint> curve;    // one point per distinct score, thresholds descending
  double average_precision = 0;  // area under the curve (sum of precision x recall step)

  // Largest recall reached at precision >= p (0 when none), and the threshold where it is reached.
  double recall_at_precision(double p, float* threshold = nullptr) const;
  // Largest precision among thresholds whose recall is >= r (0 when the recall is never reached).
  double precision_at_recall(double r) const;
  // The curve at a given threshold.
  PrPoint at_threshold(float threshold) const;
};

// word_count: the vocabulary's (for the database).
RevisitEvaluation evaluate_loop_revisits(const std::vector<PlaceSample>& sequence, const RevisitCriteria& criteria,
                                         std::size_t word_count);
RevisitEvaluation evaluate_relocalisation(const std::vector<PlaceSample>& map, const std::vector<PlaceSample>& queries,
                                          const RevisitCriteria& criteria, std::size_t word_count);

}  // namespace agvslam::place
