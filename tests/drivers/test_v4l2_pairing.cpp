// Pairing of left/right frames by V4L2 time stamp, drop counting from sequence numbers, side-by-side split.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "agvslam/drivers/v4l2/pairing.h"
#include "agvslam/io/dataset.h"
#include "common/test_data.h"

namespace v4l2 = agvslam::drivers::v4l2;
using v4l2::EyeFrame;
using v4l2::TimestampPairer;

namespace {
constexpr int64_t kMs = 1000000;

std::vector<v4l2::PairedFrames> drain(TimestampPairer& p, std::deque<int>& released) {
  std::vector<v4l2::PairedFrames> out;
  while (auto q = p.pop(released)) out.push_back(*q);
  return out;
}
}  // namespace

TEST(SequenceTracker, CountsGapsAndResetsOnRestart) {
  v4l2::SequenceTracker t;
  EXPECT_EQ(t.observe(5), 0u);  // first frame: nothing to compare with
  EXPECT_EQ(t.observe(6), 0u);
  EXPECT_EQ(t.observe(9), 2u);  // 7 and 8 lost
  EXPECT_EQ(t.observe(0), 0u);  // device restarted its count: not a loss
  EXPECT_EQ(t.observe(1), 0u);
  EXPECT_EQ(t.observe(1), 0u);  // a driver that does not number frames (constant): no loss
  EXPECT_EQ(t.dropped(), 2u);
}

TEST(TimestampPairer, PairsSynchronisedStreamsInOrder) {
  TimestampPairer p(5 * kMs, 4);
  std::deque<int> rel;
  std::vector<v4l2::PairedFrames> got;
  for (int i = 0; i < 20; ++i) {
    const int64_t t = 1000 * kMs + i * 50 * kMs;
    p.push_left({t + (i % 3) * kMs, static_cast<uint32_t>(i), i}, rel);  // up to 2 ms skew
    p.push_right({t, static_cast<uint32_t>(i), 100 + i}, rel);
    for (auto& q : drain(p, rel)) got.push_back(q);
  }
  ASSERT_EQ(got.size(), 20u);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(got[static_cast<std::size_t>(i)].left.slot, i);
    EXPECT_EQ(got[static_cast<std::size_t>(i)].right.slot, 100 + i);
  }
  EXPECT_EQ(p.unpaired_left(), 0u);
  EXPECT_EQ(p.unpaired_right(), 0u);
  EXPECT_TRUE(rel.empty());
}

TEST(TimestampPairer, FrameMissingOnOneSideLeavesItsPartnerUnpaired) {
  TimestampPairer p(5 * kMs, 4);
  std::deque<int> rel;
  std::vector<v4l2::PairedFrames> got;
  for (int i = 0; i < 10; ++i) {
    const int64_t t = i * 50 * kMs;
    p.push_left({t, 0, i}, rel);
    if (i != 4) p.push_right({t + kMs, 0, 100 + i}, rel);  // right frame 4 lost
    for (auto& q : drain(p, rel)) got.push_back(q);
  }
  ASSERT_EQ(got.size(), 9u);
  for (const auto& q : got) EXPECT_EQ(q.right.slot, 100 + q.left.slot);  // never a frame with its neighbour
  EXPECT_EQ(p.unpaired_left(), 1u);
  EXPECT_EQ(p.unpaired_right(), 0u);
  ASSERT_EQ(rel.size(), 1u);
  EXPECT_EQ(rel.front(), 4);  // the caller gets left frame 4's slot back
}

TEST(TimestampPairer, ToleranceIsInclusiveAndSideAheadIsBounded) {
  TimestampPairer p(5 * kMs, 3);
  std::deque<int> rel;
  p.push_left({100 * kMs, 0, 1}, rel);
  p.push_right({105 * kMs, 0, 2}, rel);
  auto q = p.pop(rel);
  ASSERT_TRUE(q.has_value());  // exactly at the tolerance
  p.push_left({200 * kMs, 0, 3}, rel);
  p.push_right({205 * kMs + 1, 0, 4}, rel);  // 1 ns beyond: left 3 can never pair
  EXPECT_FALSE(p.pop(rel).has_value());
  EXPECT_EQ(p.unpaired_left(), 1u);
  // The right camera stops: left frames pile up to max_pending, the oldest are dropped.
  for (int i = 0; i < 6; ++i) p.push_left({300 * kMs + i * 50 * kMs, 0, 10 + i}, rel);
  EXPECT_LE(p.pending_left(), 3u);
  EXPECT_EQ(p.unpaired_left(), 1u + 3u + 0u);  // 3 pushed out by the bound (right 4 is older than all of them)
  // Out-of-order stamp on one side is refused.
  const auto before = p.unpaired_left();
  p.push_left({1 * kMs, 0, 99}, rel);
  EXPECT_EQ(p.unpaired_left(), before + 1);
  EXPECT_EQ(rel.back(), 99);
}

TEST(TimestampPairer, RightSideAheadIsBoundedToo) {
  TimestampPairer p(5 * kMs, 3);
  std::deque<int> rel;
  // The left camera has not started: right frames pile up to max_pending, the oldest are dropped and released.
  for (int i = 0; i < 6; ++i) p.push_right({100 * kMs + i * 50 * kMs, 0, 20 + i}, rel);
  EXPECT_EQ(p.pending_right(), 3u);
  EXPECT_EQ(p.pending_left(), 0u);
  EXPECT_EQ(p.unpaired_right(), 3u);
  ASSERT_EQ(rel.size(), 3u);
  EXPECT_EQ(rel.front(), 20);
  // The left camera starts next to the newest right frame: they pair, the two older right frames go.
  p.push_left({350 * kMs + 2 * kMs, 0, 7}, rel);
  auto q = p.pop(rel);
  ASSERT_TRUE(q.has_value());
  EXPECT_EQ(q->right.slot, 25);
  EXPECT_EQ(p.pending_right(), 0u);
  EXPECT_EQ(p.unpaired_right(), 5u);
}

// Free-running cameras: independent jitter (+-3 ms), random drops on both sides; every frame whose partner
// exists must pair with it, every other frame must be counted as unpaired, nothing else.
TEST(TimestampPairer, RandomDropsAndJitter) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> jitter_us(-3000, 3000);
  std::bernoulli_distribution drop(0.05);
  TimestampPairer p(8 * kMs, 4);
  std::deque<int> rel;
  std::set<int> left_only, right_only;
  std::vector<v4l2::PairedFrames> got;
  int both = 0;
  for (int i = 0; i < 2000; ++i) {
    const int64_t t = i * 50 * kMs;
    const bool dl = drop(rng), dr = drop(rng);
    if (!dl) p.push_left({t + jitter_us(rng) * 1000LL, 0, i}, rel);
    if (!dr) p.push_right({t + jitter_us(rng) * 1000LL, 0, i}, rel);
    if (!dl && dr) left_only.insert(i);
    if (dl && !dr) right_only.insert(i);
    if (!dl && !dr) ++both;
    for (auto& q : drain(p, rel)) got.push_back(q);
  }
  for (const auto& q : got) ASSERT_EQ(q.left.slot, q.right.slot);
  // The last frame may still wait for its partner.
  EXPECT_GE(static_cast<int>(got.size()), both - 1);
  EXPECT_LE(static_cast<int>(got.size()), both);
  EXPECT_NEAR(static_cast<double>(p.unpaired_left()), static_cast<double>(left_only.size()), 1.0);
  EXPECT_NEAR(static_cast<double>(p.unpaired_right()), static_cast<double>(right_only.size()), 1.0);
  EXPECT_GT(left_only.size(), 50u);
}

// Real time stamps: EuRoC V1_01's cam0 and cam1 CSVs (hardware-triggered, identical stamps; cam1 lists four
// frames without an image). Pairing the stamps of the images that exist finds exactly the dataset reader's pairs.
TEST(TimestampPairer, EurocStampsPairLikeTheDatasetReader) {
  AGVSLAM_REQUIRE_SHARED(root, "data/euroc_v101_f000-094");
  auto stamps = [&](const std::string& cam) {
    std::vector<int64_t> t;
    std::ifstream in(root + "/mav0/" + cam + "/data.csv");
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      const std::string name = line.substr(line.find(',') + 1);
      std::string trimmed = name;
      trimmed.erase(std::remove_if(trimmed.begin(), trimmed.end(), ::isspace), trimmed.end());
      if (std::filesystem::exists(root + "/mav0/" + cam + "/data/" + trimmed))
        t.push_back(std::stoll(line.substr(0, line.find(','))));
    }
    return t;
  };
  const auto tl = stamps("cam0"), tr = stamps("cam1");
  ASSERT_GT(tl.size(), 90u);
  TimestampPairer p(10 * kMs, 4);
  std::deque<int> rel;
  std::vector<int64_t> paired;
  std::size_t i = 0, j = 0;
  while (i < tl.size() || j < tr.size()) {  // deliver in time order, as two devices would
    if (j >= tr.size() || (i < tl.size() && tl[i] <= tr[j])) {
      p.push_left({tl[i], 0, static_cast<int>(i)}, rel);
      ++i;
    } else {
      p.push_right({tr[j], 0, static_cast<int>(j)}, rel);
      ++j;
    }
    while (auto q = p.pop(rel)) {
      EXPECT_EQ(q->left.t_ns, q->right.t_ns);
      paired.push_back(q->left.t_ns);
    }
  }
  const auto ds = agvslam::io::open_dataset(root);
  ASSERT_EQ(paired.size(), ds->size());
  for (std::size_t k = 0; k < paired.size(); ++k) EXPECT_EQ(paired[k], ds->timestamp_ns(k));
}

TEST(SplitSideBySide, CopiesHalvesIntoContinuousImages) {
  cv::Mat sbs(37, 2 * 51, CV_8UC1);
  for (int y = 0; y < sbs.rows; ++y)
    for (int x = 0; x < sbs.cols; ++x) sbs.at<uint8_t>(y, x) = static_cast<uint8_t>((x < 51 ? 0 : 128) + (x % 51) + y);
  cv::Mat l, r;
  v4l2::split_side_by_side(sbs, l, r);
  ASSERT_EQ(l.size(), cv::Size(51, 37));
  ASSERT_EQ(r.size(), cv::Size(51, 37));
  EXPECT_TRUE(l.isContinuous() && r.isContinuous());
  EXPECT_EQ(cv::norm(l, sbs(cv::Rect(0, 0, 51, 37)), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(r, sbs(cv::Rect(51, 0, 51, 37)), cv::NORM_INF), 0.0);
  const uint8_t* before = l.data;
  v4l2::split_side_by_side(sbs, l, r);
  EXPECT_EQ(l.data, before);  // no allocation once the size is right
  cv::Mat odd(4, 7, CV_8UC1), colour(4, 8, CV_8UC3);
  EXPECT_THROW(v4l2::split_side_by_side(odd, l, r), std::invalid_argument);
  EXPECT_THROW(v4l2::split_side_by_side(colour, l, r), std::invalid_argument);
}
