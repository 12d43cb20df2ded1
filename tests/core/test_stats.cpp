#include <gtest/gtest.h>

#include "agvslam/core/stats.h"

namespace agvslam {
namespace {

TEST(Stats, QuantileIsTheNearestRankOfTheSortedSample) {
  Series s;
  for (double v : {5.0, 1.0, 4.0, 2.0, 3.0}) s.add(v);
  EXPECT_EQ(s.median(), 3.0);
  EXPECT_EQ(s.quantile(0.0), 1.0);
  EXPECT_EQ(s.quantile(1.0), 5.0);
  EXPECT_EQ(s.quantile(0.95), 5.0);  // round(0.95 * 4) = 4
  EXPECT_EQ(s.quantile(0.6), 3.0);   // round(2.4) = 2
  EXPECT_EQ(s.max(), 5.0);
  EXPECT_DOUBLE_EQ(s.mean(), 3.0);
  EXPECT_EQ(s.values().front(), 5.0);  // the sample keeps its order
}

TEST(Stats, EmptySamplesGiveZero) {
  Series s;
  EXPECT_EQ(s.median(), 0.0);
  EXPECT_EQ(s.max(), 0.0);
  EXPECT_EQ(s.mean(), 0.0);
  RollingSeries r(4);
  EXPECT_EQ(r.quantile(0.99), 0.0);
  EXPECT_EQ(r.max(), 0.0);
}

TEST(Stats, RollingSeriesKeepsTheLastValues) {
  RollingSeries r(3);
  for (double v : {100.0, 1.0, 2.0, 3.0}) r.add(v);
  EXPECT_EQ(r.count(), 3u);
  EXPECT_EQ(r.total(), 4u);
  EXPECT_EQ(r.max(), 3.0);  // 100 has left the window
  EXPECT_EQ(r.quantile(0.5), 2.0);
  EXPECT_EQ(r.quantile(0.0), 1.0);
}

}  // namespace
}  // namespace agvslam
