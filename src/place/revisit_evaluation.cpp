#include "agvslam/place/revisit_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "agvslam/place/keyframe_database.h"

namespace agvslam::place {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

bool is_revisit(const SE3d& a, const SE3d& b, const RevisitCriteria& c, double* distance_m = nullptr,
                double* angle_deg = nullptr) {
  const double d = (a.translation() - b.translation()).norm();
  const double angle = rotation_angle_rad(a.inverse() * b) * kRadToDeg;
  if (distance_m) *distance_m = d;
  if (angle_deg) *angle_deg = angle;
  return d <= c.max_distance_m && angle <= c.max_angle_deg;
}

void finish(RevisitEvaluation& e) {
  std::vector<const QueryOutcome*> answered;
  for (const auto& q : e.queries)
    if (q.match >= 0) answered.push_back(&q);
  std::stable_sort(answered.begin(), answered.end(),
                   [](const QueryOutcome* a, const QueryOutcome* b) { return a->score > b->score; });
  int tp = 0, fp = 0;
  double previous_recall = 0;
  for (std::size_t i = 0; i < answered.size(); ++i) {
    (answered[i]->correct ? tp : fp)++;
    if (i + 1 < answered.size() && answered[i + 1]->score == answered[i]->score) continue;
    PrPoint p;
    p.threshold = answered[i]->score;
    p.true_positives = tp;
    p.false_positives = fp;
    p.precision = double(tp) / double(tp + fp);
    p.recall = e.positives > 0 ? double(tp) / e.positives : 0.0;
    e.average_precision += p.precision * (p.recall - previous_recall);
    previous_recall = p.recall;
    e.curve.push_back(p);
  }
}

}  // namespace

std::string RevisitCriteria::describe() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "revisit: camera within %.2f m and %.1f deg; loop queries >= %.1f s apart",
                max_distance_m, max_angle_deg, min_time_gap_s);
  return buf;
}

double RevisitEvaluation::recall_at_precision(double p, float* threshold) const {
  double best = 0;
  for (const PrPoint& x : curve)
    if (x.precision >= p && x.recall > best) {
      best = x.recall;
      if (threshold) *threshold = x.threshold;
    }
  return best;
}

double RevisitEvaluation::precision_at_recall(double r) const {
  double best = 0;
  for (const PrPoint& x : curve)
    if (x.recall >= r) best = std::max(best, x.precision);
  return best;
}

PrPoint RevisitEvaluation::at_threshold(float threshold) const {
  PrPoint out;
  out.threshold = threshold;
  for (const PrPoint& x : curve) {  // thresholds descending: the last one >= threshold
    if (x.threshold < threshold) break;
    out = x;
    out.threshold = threshold;
  }
  return out;
}

RevisitEvaluation evaluate_loop_revisits(const std::vector<PlaceSample>& sequence, const RevisitCriteria& criteria,
                                         std::size_t word_count) {
  RevisitEvaluation e;
  KeyframeDatabase db(word_count);
  const auto gap_ns = static_cast<int64_t>(criteria.min_time_gap_s * 1e9);
  std::size_t added = 0;
  QueryOptions options;
  options.max_results = 1;
  std::vector<Candidate> top;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    while (added < i && sequence[added].t_ns <= sequence[i].t_ns - gap_ns) {
      db.add(added, sequence[added].bow);
      ++added;
    }
    QueryOutcome q;
    q.query = i;
    for (std::size_t j = 0; j < added && !q.positive; ++j)
      q.positive = is_revisit(sequence[i].T_w_c, sequence[j].T_w_c, criteria);
    db.query(sequence[i].bow, options, top);
    if (!top.empty()) {
      q.match = long(top[0].id);
      q.score = top[0].score;
      q.correct =
          is_revisit(sequence[i].T_w_c, sequence[top[0].id].T_w_c, criteria, &q.match_distance_m, &q.match_angle_deg);
    }
    e.positives += q.positive;
    e.queries.push_back(q);
  }
  finish(e);
  return e;
}

RevisitEvaluation evaluate_relocalisation(const std::vector<PlaceSample>& map, const std::vector<PlaceSample>& queries,
                                          const RevisitCriteria& criteria, std::size_t word_count) {
  RevisitEvaluation e;
  KeyframeDatabase db(word_count);
  for (std::size_t j = 0; j < map.size(); ++j) db.add(j, map[j].bow);
  QueryOptions options;
  options.max_results = 1;
  std::vector<Candidate> top;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    QueryOutcome q;
    q.query = i;
    for (std::size_t j = 0; j < map.size() && !q.positive; ++j)
      q.positive = is_revisit(queries[i].T_w_c, map[j].T_w_c, criteria);
    db.query(queries[i].bow, options, top);
    if (!top.empty()) {
      q.match = long(top[0].id);
      q.score = top[0].score;
      q.correct = is_revisit(queries[i].T_w_c, map[top[0].id].T_w_c, criteria, &q.match_distance_m, &q.match_angle_deg);
    }
    e.positives += q.positive;
    e.queries.push_back(q);
  }
  finish(e);
  return e;
}

}  // namespace agvslam::place
