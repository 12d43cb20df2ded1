// The queues between agvslamd's threads: newest wins drops the oldest and counts it; lossless waits for room;
// close() wakes a waiting producer and consumer; pop() returns within its time-out.
#include "agvslam/daemon/bounded_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace agvslam::daemon {
namespace {

using namespace std::chrono_literals;

TEST(BoundedQueue, NewestWinsDropsTheOldestAndCountsIt) {
  BoundedQueue<int> q(2, QueuePolicy::kNewestWins);
  EXPECT_TRUE(q.push(1));
  EXPECT_TRUE(q.push(2));
  EXPECT_FALSE(q.push(3));  // 1 dropped
  EXPECT_FALSE(q.push(4));  // 2 dropped
  EXPECT_EQ(q.dropped(), 2U);
  EXPECT_EQ(q.pushed(), 4U);
  EXPECT_EQ(q.pop(0ms), 3);
  EXPECT_EQ(q.pop(0ms), 4);
  EXPECT_FALSE(q.pop(0ms).has_value());
}

TEST(BoundedQueue, LosslessWaitsForRoomAndLosesNothing) {
  BoundedQueue<int> q(1, QueuePolicy::kLossless);
  std::atomic<int> pushed{0};
  std::thread producer([&] {
    for (int i = 0; i < 50; ++i) {
      q.push(i);
      ++pushed;
    }
    q.close();
  });
  std::vector<int> got;
  for (;;) {
    auto v = q.pop(1000ms);
    if (!v) {
      if (q.drained()) break;
      continue;
    }
    got.push_back(*v);
    EXPECT_LE(q.size(), 1U);
  }
  producer.join();
  ASSERT_EQ(got.size(), 50U);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(got[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(q.dropped(), 0U);
}

TEST(BoundedQueue, CloseWakesAWaitingProducerAndConsumer) {
  BoundedQueue<int> full(1, QueuePolicy::kLossless);
  full.push(1);
  std::atomic<bool> returned{false};
  std::thread producer([&] {
    EXPECT_FALSE(full.push(2));  // waits for room until closed, then refuses
    returned = true;
  });
  BoundedQueue<int> empty(1, QueuePolicy::kNewestWins);
  std::thread consumer([&] { EXPECT_FALSE(empty.pop(60s).has_value()); });
  std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(returned.load());
  full.close();
  empty.close();
  producer.join();
  consumer.join();
  EXPECT_TRUE(returned.load());
  // What was queued before close() is still delivered, then nothing.
  EXPECT_EQ(full.pop(0ms), 1);
  EXPECT_TRUE(full.drained());
  EXPECT_FALSE(full.push(3));
}

TEST(BoundedQueue, PopReturnsNothingAfterItsTimeout) {
  BoundedQueue<int> q(4, QueuePolicy::kNewestWins);
  EXPECT_FALSE(q.pop(20ms).has_value());
  EXPECT_FALSE(q.drained());
}

}  // namespace
}  // namespace agvslam::daemon
