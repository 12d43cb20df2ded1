#include "agvslam/place/bow_vector.h"

#include <algorithm>

namespace agvslam::place {

double l1_score(const BowVector& a, const BowVector& b) {
  // 1 - |a - b|_1 / 2 = sum over common words of min(a_w, b_w) when both sum to 1 (DBoW2's L1Scoring).
  double score = 0;
  auto i = a.entries.begin(), j = b.entries.begin();
  while (i != a.entries.end() && j != b.entries.end()) {
    if (i->word < j->word) {
      ++i;
    } else if (j->word < i->word) {
      ++j;
    } else {
      score += std::min(i->weight, j->weight);
      ++i;
      ++j;
    }
  }
  return std::clamp(score, 0.0, 1.0);
}

std::size_t common_words(const BowVector& a, const BowVector& b) {
  std::size_t n = 0;
  auto i = a.entries.begin(), j = b.entries.begin();
  while (i != a.entries.end() && j != b.entries.end()) {
    if (i->word < j->word) {
      ++i;
    } else if (j->word < i->word) {
      ++j;
    } else {
      ++n;
      ++i;
      ++j;
    }
  }
  return n;
}

}  // namespace agvslam::place
