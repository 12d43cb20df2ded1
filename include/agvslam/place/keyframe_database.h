#pragma once
// Keyframe database: the inverse index (word -> keyframes that contain it, with the word's weight in each) over
// which relocalisation and loop detection find candidate keyframes (DBoW2's Database, ORB-SLAM2's
// KeyFrameDatabase without the SLAM's own types).
//
// Keyframes are plain integer ids chosen by the caller (the SLAM's keyframe ids); the database stores each
// keyframe's BoW vector, nothing else. Scores are DBoW2's L1 score, computed exactly from the inverse index:
// for L1-normalised vectors 1 - |q - v|_1 / 2 = sum over common words of min(q_w, v_w), so a query visits only
// the postings of its own words.
//
// Threads: every method may be called from any thread. add(), erase() and clear() take an exclusive lock;
// query(), contains(), size() and bow() a shared one, so the tracking thread (relocalisation) and the loop
// closer query concurrently while the local mapper adds and culls keyframes. A query holds the lock only while
// it walks the posting lists; QueryOptions' filters run after it is released (accept may call anything).
//
// ORB-SLAM2's candidate selection is built from these primitives (see also group_candidates below):
//   DetectRelocalizationCandidates: query(bow, {.min_common_words_ratio = 0.8}), group_candidates(..., 0.75).
//   DetectLoopCandidates: the same with exclude = the keyframe's covisible neighbours (and itself) and
//   min_score = the lowest score between the keyframe and those neighbours.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "agvslam/place/bow_vector.h"

namespace agvslam::place {

using KeyframeId = uint64_t;

struct Candidate {
  KeyframeId id = 0;
  uint32_t common_words = 0;  // words shared with the query
  float score = 0;            // L1 score with the query, (0, 1]
};

struct QueryOptions {
  std::size_t max_results = 0;    // 0: every candidate that passes
  float min_score = 0;            // keep candidates with score >= this
  uint32_t min_common_words = 1;  // keep candidates sharing at least this many words
  // Keep candidates sharing at least this fraction of the largest number of common words among the candidates
  // that pass the filters below (ORB-SLAM2: 0.8). 0: off.
  float min_common_words_ratio = 0;
  std::vector<KeyframeId> exclude;  // never returned (e.g. the query keyframe and its covisible neighbours)
  // Only keyframes with id < this (e.g. older than some time, when ids grow with time). 0: no limit.
  KeyframeId id_below = 0;
  // Extra filter: keep a candidate only where it returns true (called without the database's lock held).
  std::function<bool(KeyframeId)> accept;
};

class KeyframeDatabase {
 public:
  // word_count: the vocabulary's word count (words of added vectors must be below it).
  explicit KeyframeDatabase(std::size_t word_count);
  KeyframeDatabase(const KeyframeDatabase&) = delete;
  KeyframeDatabase& operator=(const KeyframeDatabase&) = delete;

  std::size_t word_count() const { return word_count_; }

  // Adds (or replaces) a keyframe. Throws std::invalid_argument for a word id >= word_count or entries that are
  // not sorted and unique.
  void add(KeyframeId id, const BowVector& bow);
  // Removes a keyframe; false when it was not there.
  bool erase(KeyframeId id);
  void clear();

  std::size_t size() const;
  bool contains(KeyframeId id) const;
  // The stored BoW vector of a keyframe; false when it is not there.
  bool bow(KeyframeId id, BowVector& out) const;
  // Number of keyframes that contain a word (the length of its posting list).
  std::size_t keyframes_with_word(WordId word) const;

  // Candidates sharing words with `bow` that pass `options`, best score first (ties: smaller id first).
  std::vector<Candidate> query(const BowVector& bow, const QueryOptions& options = {}) const;
  // The same into `out` (reuses its storage).
  void query(const BowVector& bow, const QueryOptions& options, std::vector<Candidate>& out) const;

 private:
  struct Posting {
    uint32_t slot;
    float weight;
  };
  struct Slot {
    KeyframeId id = 0;
    bool used = false;
    BowVector bow;
  };
  void erase_locked(uint32_t slot);

  std::size_t word_count_;
  mutable std::shared_mutex mutex_;
  std::vector<std::vector<Posting>> postings_;  // word -> keyframes (slots) containing it
  std::vector<Slot> slots_;
  std::vector<uint32_t> free_slots_;
  std::unordered_map<KeyframeId, uint32_t> slot_of_;
};

// ORB-SLAM2's covisibility-group scoring. For each candidate c: its group is c plus those of neighbours(c)
// (the SLAM's best covisible keyframes of c) that are candidates too; the group score is the sum of their
// scores, and the group is represented by its best-scoring member. Returns the groups whose score is at least
// min_group_ratio x the best group score (ORB-SLAM2: 0.75), one entry per distinct representative, best group
// score first. neighbours(id, out) fills `out` (cleared before each call).
struct GroupCandidate {
  KeyframeId best_id = 0;  // best-scoring keyframe of the group
  float best_score = 0;
  float group_score = 0;  // accumulated score of the group
};
std::vector<GroupCandidate> group_candidates(
    const std::vector<Candidate>& candidates,
    const std::function<void(KeyframeId, std::vector<KeyframeId>&)>& neighbours, float min_group_ratio = 0.75f);

}  // namespace agvslam::place
