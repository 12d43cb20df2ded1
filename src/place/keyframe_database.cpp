#include "agvslam/place/keyframe_database.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace agvslam::place {

KeyframeDatabase::KeyframeDatabase(std::size_t word_count) : word_count_(word_count), postings_(word_count) {}

void KeyframeDatabase::add(KeyframeId id, const BowVector& bow) {
  for (std::size_t i = 0; i < bow.entries.size(); ++i) {
    if (bow.entries[i].word >= word_count_)
      throw std::invalid_argument("KeyframeDatabase::add: word " + std::to_string(bow.entries[i].word) +
                                  " >= word count " + std::to_string(word_count_));
    if (i > 0 && bow.entries[i].word <= bow.entries[i - 1].word)
      throw std::invalid_argument("KeyframeDatabase::add: BoW entries must be sorted by word and unique");
  }
  std::unique_lock lock(mutex_);
  if (auto it = slot_of_.find(id); it != slot_of_.end()) erase_locked(it->second);
  uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = static_cast<uint32_t>(slots_.size());
    slots_.emplace_back();
  }
  Slot& s = slots_[slot];
  s.id = id;
  s.used = true;
  s.bow = bow;
  slot_of_[id] = slot;
  for (const WordWeight& e : bow.entries) postings_[e.word].push_back({slot, e.weight});
}

void KeyframeDatabase::erase_locked(uint32_t slot) {
  Slot& s = slots_[slot];
  for (const WordWeight& e : s.bow.entries) {
    auto& list = postings_[e.word];
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (list[i].slot == slot) {
        list[i] = list.back();  // order within a posting list does not matter
        list.pop_back();
        break;
      }
    }
  }
  slot_of_.erase(s.id);
  s.used = false;
  s.bow.clear();
  free_slots_.push_back(slot);
}

bool KeyframeDatabase::erase(KeyframeId id) {
  std::unique_lock lock(mutex_);
  auto it = slot_of_.find(id);
  if (it == slot_of_.end()) return false;
  erase_locked(it->second);
  return true;
}

void KeyframeDatabase::clear() {
  std::unique_lock lock(mutex_);
  for (auto& list : postings_) list.clear();
  slots_.clear();
  free_slots_.clear();
  slot_of_.clear();
}

std::size_t KeyframeDatabase::size() const {
  std::shared_lock lock(mutex_);
  return slot_of_.size();
}

bool KeyframeDatabase::contains(KeyframeId id) const {
  std::shared_lock lock(mutex_);
  return slot_of_.count(id) != 0;
}

bool KeyframeDatabase::bow(KeyframeId id, BowVector& out) const {
  std::shared_lock lock(mutex_);
  auto it = slot_of_.find(id);
  if (it == slot_of_.end()) return false;
  out = slots_[it->second].bow;
  return true;
}

std::size_t KeyframeDatabase::keyframes_with_word(WordId word) const {
  std::shared_lock lock(mutex_);
  return word < postings_.size() ? postings_[word].size() : 0;
}

std::vector<Candidate> KeyframeDatabase::query(const BowVector& bow, const QueryOptions& options) const {
  std::vector<Candidate> out;
  query(bow, options, out);
  return out;
}

void KeyframeDatabase::query(const BowVector& bow, const QueryOptions& options, std::vector<Candidate>& out) const {
  out.clear();
  // Per-thread accumulators indexed by slot (no allocation per query once grown); `touched` lists the slots in
  // use so only those are reset.
  thread_local std::vector<uint32_t> common;
  thread_local std::vector<float> score;
  thread_local std::vector<uint32_t> touched;
  touched.clear();
  std::vector<KeyframeId> exclude = options.exclude;  // small (covisible neighbours)
  std::sort(exclude.begin(), exclude.end());

  std::shared_lock lock(mutex_);
  if (common.size() < slots_.size()) {
    common.resize(slots_.size(), 0);
    score.resize(slots_.size(), 0.f);
  }
  for (const WordWeight& q : bow.entries) {
    if (q.word >= postings_.size()) continue;
    for (const Posting& p : postings_[q.word]) {
      if (common[p.slot]++ == 0) touched.push_back(p.slot);
      score[p.slot] += std::min(q.weight, p.weight);
    }
  }
  for (uint32_t slot : touched) {
    out.push_back({slots_[slot].id, common[slot], std::min(score[slot], 1.0f)});
    common[slot] = 0;
    score[slot] = 0.f;
  }
  lock.unlock();

  out.erase(std::remove_if(out.begin(), out.end(),
                           [&](const Candidate& c) {
                             return (options.id_below != 0 && c.id >= options.id_below) ||
                                    std::binary_search(exclude.begin(), exclude.end(), c.id) ||
                                    (options.accept && !options.accept(c.id));
                           }),
            out.end());
  uint32_t max_common = 0;
  for (const Candidate& c : out) max_common = std::max(max_common, c.common_words);
  const auto min_common =
      std::max<uint32_t>(options.min_common_words,
                         static_cast<uint32_t>(std::ceil(double(options.min_common_words_ratio) * max_common - 1e-4)));
  out.erase(
      std::remove_if(out.begin(), out.end(),
                     [&](const Candidate& c) { return c.common_words < min_common || c.score < options.min_score; }),
      out.end());
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.id < b.id;
  });
  if (options.max_results > 0 && out.size() > options.max_results) out.resize(options.max_results);
}

std::vector<GroupCandidate> group_candidates(
    const std::vector<Candidate>& candidates,
    const std::function<void(KeyframeId, std::vector<KeyframeId>&)>& neighbours, float min_group_ratio) {
  std::unordered_map<KeyframeId, float> score_of;
  score_of.reserve(candidates.size() * 2);
  for (const Candidate& c : candidates) score_of[c.id] = c.score;
  std::vector<GroupCandidate> groups;
  groups.reserve(candidates.size());
  std::vector<KeyframeId> n;
  float best_group = 0;
  for (const Candidate& c : candidates) {
    GroupCandidate g{c.id, c.score, c.score};
    n.clear();
    if (neighbours) neighbours(c.id, n);
    for (KeyframeId other : n) {
      if (other == c.id) continue;
      auto it = score_of.find(other);
      if (it == score_of.end()) continue;
      g.group_score += it->second;
      if (it->second > g.best_score) {
        g.best_score = it->second;
        g.best_id = other;
      }
    }
    best_group = std::max(best_group, g.group_score);
    groups.push_back(g);
  }
  const float keep_from = min_group_ratio * best_group;
  std::stable_sort(groups.begin(), groups.end(),
                   [](const GroupCandidate& a, const GroupCandidate& b) { return a.group_score > b.group_score; });
  std::vector<GroupCandidate> out;
  for (const GroupCandidate& g : groups) {
    if (g.group_score < keep_from) break;
    if (std::none_of(out.begin(), out.end(), [&](const GroupCandidate& o) { return o.best_id == g.best_id; }))
      out.push_back(g);
  }
  return out;
}

}  // namespace agvslam::place
