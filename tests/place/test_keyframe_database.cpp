// Keyframe database: inverse-index scores equal the L1 score, filters, add/erase/replace, concurrent use, and
// ORB-SLAM2's covisibility-group scoring.
#include "agvslam/place/keyframe_database.h"

#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <random>
#include <thread>

namespace agvslam::place {
namespace {

// A random L1-normalised vector of `n` distinct words below `words`.
BowVector random_bow(std::mt19937_64& rng, std::size_t n, uint32_t words) {
  std::map<WordId, float> m;
  while (m.size() < n) m[WordId(rng() % words)] = 0.1f + float(rng() % 1000) / 1000.f;
  double total = 0;
  for (auto& [w, x] : m) total += x;
  BowVector b;
  for (auto& [w, x] : m) b.entries.push_back({w, float(x / total)});
  return b;
}

TEST(KeyframeDatabase, ScoresAndCommonWordsEqualTheDirectComputation) {
  std::mt19937_64 rng(1);
  KeyframeDatabase db(500);
  std::vector<BowVector> kfs;
  for (int i = 0; i < 60; ++i) {
    kfs.push_back(random_bow(rng, 40, 500));
    db.add(KeyframeId(1000 + i), kfs.back());
  }
  EXPECT_EQ(db.size(), 60u);
  const BowVector q = random_bow(rng, 60, 500);
  const auto cands = db.query(q);
  std::size_t sharing = 0;
  for (const auto& k : kfs) sharing += common_words(q, k) > 0;
  ASSERT_EQ(cands.size(), sharing);
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const auto& k = kfs[cands[i].id - 1000];
    EXPECT_NEAR(cands[i].score, l1_score(q, k), 1e-5);
    EXPECT_EQ(cands[i].common_words, common_words(q, k));
    if (i > 0) {
      EXPECT_GE(cands[i - 1].score, cands[i].score);
    }
  }
  // A stored keyframe queried with its own vector is the best candidate with score 1.
  const auto self = db.query(kfs[17], {});
  ASSERT_FALSE(self.empty());
  EXPECT_EQ(self[0].id, 1017u);
  EXPECT_NEAR(self[0].score, 1.0, 1e-5);
  EXPECT_EQ(self[0].common_words, 40u);
}

TEST(KeyframeDatabase, FiltersAndLimits) {
  std::mt19937_64 rng(2);
  KeyframeDatabase db(300);
  std::vector<BowVector> kfs;
  for (int i = 0; i < 50; ++i) {
    kfs.push_back(random_bow(rng, 30, 300));
    db.add(KeyframeId(i), kfs.back());
  }
  const BowVector q = random_bow(rng, 50, 300);
  const auto all = db.query(q);
  ASSERT_GT(all.size(), 10u);

  QueryOptions o;
  o.max_results = 3;
  auto r = db.query(q, o);
  ASSERT_EQ(r.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r[std::size_t(i)].id, all[std::size_t(i)].id);

  o = {};
  o.exclude = {all[0].id, all[2].id};
  o.id_below = 40;
  o.accept = [](KeyframeId id) { return id % 7 != 3; };
  r = db.query(q, o);
  for (const auto& c : r) {
    EXPECT_NE(c.id, all[0].id);
    EXPECT_NE(c.id, all[2].id);
    EXPECT_LT(c.id, 40u);
    EXPECT_NE(c.id % 7, 3u);
  }
  std::size_t expected = 0;
  for (const auto& c : all) expected += c.id != all[0].id && c.id != all[2].id && c.id < 40 && c.id % 7 != 3;
  EXPECT_EQ(r.size(), expected);

  o = {};
  o.min_score = all[4].score;
  r = db.query(q, o);
  for (const auto& c : r) EXPECT_GE(c.score, all[4].score);
  EXPECT_GE(r.size(), 5u);

  // ORB-SLAM2's rule: at least 0.8 x the largest number of common words among the candidates.
  uint32_t max_common = 0;
  for (const auto& c : all) max_common = std::max(max_common, c.common_words);
  o = {};
  o.min_common_words_ratio = 0.8f;
  r = db.query(q, o);
  ASSERT_FALSE(r.empty());
  for (const auto& c : r) EXPECT_GE(double(c.common_words), 0.8 * max_common - 1e-9);
  std::size_t n_ok = 0;
  for (const auto& c : all) n_ok += double(c.common_words) >= 0.8 * max_common - 1e-9;
  EXPECT_EQ(r.size(), n_ok);
}

TEST(KeyframeDatabase, EraseReplaceAndClear) {
  KeyframeDatabase db(10);
  BowVector a, b;
  a.entries = {{1, 0.5f}, {2, 0.5f}};
  b.entries = {{2, 0.5f}, {3, 0.5f}};
  db.add(7, a);
  db.add(8, b);
  EXPECT_EQ(db.keyframes_with_word(2), 2u);
  EXPECT_EQ(db.query(a).size(), 2u);
  EXPECT_TRUE(db.erase(7));
  EXPECT_FALSE(db.erase(7));
  EXPECT_FALSE(db.contains(7));
  EXPECT_EQ(db.keyframes_with_word(1), 0u);
  auto r = db.query(a);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 8u);
  EXPECT_NEAR(r[0].score, 0.5, 1e-6);
  db.add(8, a);  // replaces 8's vector
  EXPECT_EQ(db.size(), 1u);
  EXPECT_EQ(db.keyframes_with_word(3), 0u);
  r = db.query(a);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].score, 1.0, 1e-6);
  BowVector stored;
  EXPECT_TRUE(db.bow(8, stored));
  EXPECT_EQ(stored.entries.size(), 2u);
  db.add(9, b);  // reuses the freed slot
  EXPECT_EQ(db.size(), 2u);
  db.clear();
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.query(a).empty());
  BowVector bad;
  bad.entries = {{10, 1.f}};
  EXPECT_THROW(db.add(1, bad), std::invalid_argument);
  bad.entries = {{3, 0.5f}, {2, 0.5f}};
  EXPECT_THROW(db.add(1, bad), std::invalid_argument);
}

TEST(KeyframeDatabase, ConcurrentQueriesWhileKeyframesAreAddedAndErased) {
  // Two readers (tracking, loop closing) and one writer (local mapping): every answer must be consistent, i.e.
  // each candidate's score equals the L1 score with the vector stored for it.
  std::mt19937_64 rng(3);
  std::vector<BowVector> kfs;
  for (int i = 0; i < 400; ++i) kfs.push_back(random_bow(rng, 50, 2000));
  KeyframeDatabase db(2000);
  for (int i = 0; i < 100; ++i) db.add(KeyframeId(i), kfs[std::size_t(i)]);
  std::atomic<bool> stop{false};
  std::atomic<int> bad{0}, queries{0};
  auto reader = [&](uint64_t seed) {
    std::mt19937_64 r(seed);
    std::vector<Candidate> out;
    while (!stop) {
      const BowVector& q = kfs[r() % kfs.size()];
      db.query(q, {}, out);
      for (const auto& c : out)
        if (std::abs(c.score - l1_score(q, kfs[c.id])) > 1e-4) ++bad;
      ++queries;
    }
  };
  std::thread t1(reader, 10), t2(reader, 11);
  for (int i = 100; i < 400; ++i) {
    db.add(KeyframeId(i), kfs[std::size_t(i)]);
    if (i % 3 == 0) db.erase(KeyframeId(i - 50));
  }
  while (queries < 200) std::this_thread::yield();
  stop = true;
  t1.join();
  t2.join();
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(db.size(), 400u - 100u);
}

TEST(GroupCandidates, AccumulatesCovisibleCandidatesAsOrbSlam2) {
  // Candidates 1, 2, 3 are covisible with each other; 10 stands alone; 20's neighbour 21 is not a candidate.
  const std::vector<Candidate> cands = {
      {1, 20, 0.30f}, {2, 20, 0.20f}, {3, 18, 0.10f}, {10, 20, 0.35f}, {20, 19, 0.25f}};
  auto neighbours = [](KeyframeId id, std::vector<KeyframeId>& out) {
    if (id <= 3) out = {1, 2, 3};
    if (id == 20) out = {21};
  };
  const auto groups = group_candidates(cands, neighbours, 0.75f);
  // Groups of 1, 2, 3: 0.6, best 1; of 10: 0.35; of 20: 0.25. Kept: >= 0.45 -> one entry for keyframe 1.
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].best_id, 1u);
  EXPECT_NEAR(groups[0].group_score, 0.6f, 1e-6);
  EXPECT_NEAR(groups[0].best_score, 0.3f, 1e-6);
  const auto loose = group_candidates(cands, neighbours, 0.4f);  // >= 0.24
  ASSERT_EQ(loose.size(), 3u);
  EXPECT_EQ(loose[1].best_id, 10u);
  EXPECT_EQ(loose[2].best_id, 20u);
  EXPECT_TRUE(group_candidates({}, neighbours).empty());
}

}  // namespace
}  // namespace agvslam::place
