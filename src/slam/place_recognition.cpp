#include "agvslam/slam/place_recognition.h"

#include <stdexcept>
#include <string>

#include "agvslam/slam/map.h"

namespace agvslam::slam {

namespace {

const place::Vocabulary& checked(const std::shared_ptr<const place::Vocabulary>& v, int level) {
  if (!v || v->empty()) throw std::invalid_argument("PlaceRecognition: expected a non-empty vocabulary");
  if (level < 1 || level > v->levels()) {
    throw std::invalid_argument("PlaceRecognition: direct_index_level must be in 1.." + std::to_string(v->levels()));
  }
  return *v;
}

}  // namespace

PlaceRecognition::PlaceRecognition(std::shared_ptr<const place::Vocabulary> vocabulary, int direct_index_level)
    : vocabulary_(std::move(vocabulary)),
      level_(direct_index_level),
      database_(checked(vocabulary_, direct_index_level).word_count()) {}

void PlaceRecognition::on_keyframe_inserted(KeyFrame& kf) {
  compute(kf);
  database_.add(kf.id, kf.bow.words);
}

void PlaceRecognition::on_keyframe_erased(KeyFrame& kf) { database_.erase(kf.id); }

std::vector<KeyFrame*> PlaceRecognition::best_of_groups(const std::vector<place::Candidate>& candidates,
                                                        const Map& map) const {
  std::vector<KeyFrame*> out;
  if (candidates.empty()) return out;
  const auto neighbours = [&](place::KeyframeId id, std::vector<place::KeyframeId>& n) {
    const KeyFramePtr kf = map.keyframe(id);
    if (!kf) return;
    for (const KeyFrame* c : kf->best_covisibles(10)) n.push_back(c->id);
  };
  for (const place::GroupCandidate& g : place::group_candidates(candidates, neighbours, 0.75f)) {
    const KeyFramePtr kf = map.keyframe(g.best_id);
    if (kf && !kf->bad()) out.push_back(kf.get());
  }
  return out;
}

std::vector<KeyFrame*> PlaceRecognition::relocalisation_candidates(Frame& frame, const Map& map,
                                                                   std::size_t max_results) {
  compute(frame);
  place::QueryOptions q;
  q.min_common_words_ratio = 0.8f;
  // Keyframes the database still holds but the map no longer has (erased between the two) are left out.
  q.accept = [&](place::KeyframeId id) {
    const KeyFramePtr kf = map.keyframe(id);
    return kf && !kf->bad();
  };
  std::vector<KeyFrame*> out = best_of_groups(database_.query(frame.bow, q), map);
  if (max_results > 0 && out.size() > max_results) out.resize(max_results);
  return out;
}

std::vector<KeyFrame*> PlaceRecognition::loop_candidates(const KeyFrame& kf, float min_score, const Map& map) {
  place::QueryOptions q;
  q.min_common_words_ratio = 0.8f;
  q.min_score = min_score;
  q.exclude.push_back(kf.id);
  for (const auto& [other, weight] : kf.connections()) q.exclude.push_back(other->id);
  q.accept = [&](place::KeyframeId id) {
    const KeyFramePtr c = map.keyframe(id);
    return c && !c->bad();
  };
  return best_of_groups(database_.query(kf.bow.words, q), map);
}

}  // namespace agvslam::slam
