#pragma once
// Place recognition for the SLAM (ORB-SLAM2's KeyFrameDatabase on the place module): the bag-of-words vocabulary
// and the inverse index of the map's keyframes, with ORB-SLAM2's candidate selection for relocalisation and loop
// detection. Keyframes carry their BoW vector and direct index (KeyFrame::bow); frames compute theirs on demand.
//
//   on_keyframe_inserted   local-mapping thread, map mutex held, when a keyframe enters the map: computes kf.bow
//                          (when tracking has not already) and adds it to the inverse index.
//   on_keyframe_erased     map mutex held, just before a keyframe leaves the map (culling).
//   relocalisation_candidates   tracking thread, map mutex held: keyframes that may show the frame's place, best
//                          group first (ORB-SLAM2's DetectRelocalizationCandidates: keyframes sharing >= 80 % of
//                          the most shared words, grouped with their 10 best covisible keyframes, groups scoring
//                          >= 75 % of the best one, the best keyframe of each).
//   loop_candidates        loop-closing thread, map mutex held: the same for a keyframe, excluding every keyframe
//                          connected to it and keeping scores >= min_score (ORB-SLAM2's DetectLoopCandidates).
//
// The database has its own lock (place::KeyframeDatabase), so queries and insertions may come from any thread.

#include <cstdint>
#include <memory>
#include <vector>

#include "agvslam/place/keyframe_database.h"
#include "agvslam/place/vocabulary.h"
#include "agvslam/slam/frame.h"
#include "agvslam/slam/key_frame.h"

namespace agvslam::slam {

class Map;

class PlaceRecognition {
 public:
  // vocabulary: non-empty; direct_index_level: depth of the direct index's nodes (1 .. vocabulary levels).
  // Throws std::invalid_argument otherwise.
  PlaceRecognition(std::shared_ptr<const place::Vocabulary> vocabulary, int direct_index_level);

  const place::Vocabulary& vocabulary() const { return *vocabulary_; }
  const std::shared_ptr<const place::Vocabulary>& vocabulary_ptr() const { return vocabulary_; }
  uint64_t vocabulary_id() const { return vocabulary_->identity(); }
  int direct_index_level() const { return level_; }

  void compute(Frame& frame) const { frame.compute_bow(*vocabulary_, level_); }
  void compute(KeyFrame& kf) const { kf.compute_bow(*vocabulary_, level_); }

  void on_keyframe_inserted(KeyFrame& kf);
  void on_keyframe_erased(KeyFrame& kf);
  void clear() { database_.clear(); }
  std::size_t size() const { return database_.size(); }

  // Map mutex held. Computes the frame's BoW when needed. At most max_results (0: all).
  std::vector<KeyFrame*> relocalisation_candidates(Frame& frame, const Map& map, std::size_t max_results = 0);
  // Map mutex held; kf.bow must be computed.
  std::vector<KeyFrame*> loop_candidates(const KeyFrame& kf, float min_score, const Map& map);

  // DBoW2's L1 score of two keyframes' BoW vectors.
  static double score(const KeyFrame& a, const KeyFrame& b) { return place::l1_score(a.bow.words, b.bow.words); }

 private:
  std::vector<KeyFrame*> best_of_groups(const std::vector<place::Candidate>& candidates, const Map& map) const;

  std::shared_ptr<const place::Vocabulary> vocabulary_;
  int level_;
  place::KeyframeDatabase database_;
};

}  // namespace agvslam::slam
