// The queue between threads: newest wins drops the oldest and counts it; refuse new refuses and counts; lossless
// waits for room and loses nothing, also with several producers and consumers; close() wakes a waiting producer
// and consumer; pop() returns within its time-out; pop_unless() returns once its stop condition holds, leaving
// the items queued. The threaded cases are meant to be repeated (--gtest_repeat) to catch races.
#include "agvslam/core/bounded_queue.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace agvslam {
namespace {

using namespace std::chrono_literals;

TEST(BoundedQueue, NewestWinsDropsTheOldestAndCountsIt) {
  BoundedQueue<int> q(2, QueuePolicy::kNewestWins);
  EXPECT_EQ(q.push(1), PushResult::kQueued);
  EXPECT_EQ(q.push(2), PushResult::kQueued);
  EXPECT_EQ(q.push(3), PushResult::kQueuedDroppedOldest);  // 1 dropped
  EXPECT_EQ(q.push(4), PushResult::kQueuedDroppedOldest);  // 2 dropped
  EXPECT_EQ(q.dropped(), 2U);
  EXPECT_EQ(q.pushed(), 4U);
  EXPECT_EQ(q.pop(0ms), 3);
  EXPECT_EQ(q.pop(0ms), 4);
  EXPECT_FALSE(q.pop(0ms).has_value());
}

TEST(BoundedQueue, RefuseNewKeepsWhatIsQueuedAndCountsTheRefused) {
  BoundedQueue<int> q(2, QueuePolicy::kRefuseNew);
  EXPECT_EQ(q.push(1), PushResult::kQueued);
  EXPECT_EQ(q.push(2), PushResult::kQueued);
  EXPECT_EQ(q.push(3), PushResult::kRefused);
  EXPECT_EQ(q.dropped(), 1U);
  EXPECT_EQ(q.pushed(), 2U);
  EXPECT_EQ(q.try_pop(), 1);
  EXPECT_EQ(q.push(4), PushResult::kQueued);
  EXPECT_EQ(q.try_pop(), 2);
  EXPECT_EQ(q.try_pop(), 4);
  EXPECT_FALSE(q.try_pop().has_value());
}

TEST(BoundedQueue, ClearDiscardsWithoutCountingAndMakesRoom) {
  BoundedQueue<int> q(2, QueuePolicy::kRefuseNew);
  q.push(1);
  q.push(2);
  EXPECT_EQ(q.clear(), 2U);
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.push(3), PushResult::kQueued);
}

TEST(BoundedQueue, ZeroCapacityIsRejected) {
  EXPECT_THROW(BoundedQueue<int>(0, QueuePolicy::kLossless), std::invalid_argument);
}

TEST(BoundedQueue, LosslessWaitsForRoomAndLosesNothing) {
  BoundedQueue<int> q(1, QueuePolicy::kLossless);
  std::thread producer([&] {
    for (int i = 0; i < 50; ++i) q.push(i);
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

TEST(BoundedQueue, LosslessWithSeveralProducersAndConsumersDeliversEveryItemOnce) {
  constexpr int kProducers = 3, kConsumers = 3, kPerProducer = 2000;
  BoundedQueue<int> q(2, QueuePolicy::kLossless);
  std::atomic<int> producers_left{kProducers};
  std::vector<std::thread> threads;
  for (int p = 0; p < kProducers; ++p) {
    threads.emplace_back([&, p] {
      for (int i = 0; i < kPerProducer; ++i) EXPECT_EQ(q.push(p * kPerProducer + i), PushResult::kQueued);
      if (--producers_left == 0) q.close();
    });
  }
  std::vector<std::vector<int>> got(kConsumers);
  for (int c = 0; c < kConsumers; ++c) {
    threads.emplace_back([&, c] {
      while (!q.drained()) {
        if (auto v = q.pop(10ms)) got[static_cast<std::size_t>(c)].push_back(*v);
      }
    });
  }
  for (auto& t : threads) t.join();
  std::vector<int> all;
  for (const auto& g : got) {
    // Each consumer sees every producer's items in the order they were pushed.
    for (std::size_t k = 1; k < g.size(); ++k) {
      if (g[k] / kPerProducer == g[k - 1] / kPerProducer) {
        EXPECT_LT(g[k - 1], g[k]);
      }
    }
    all.insert(all.end(), g.begin(), g.end());
  }
  std::sort(all.begin(), all.end());
  ASSERT_EQ(all.size(), static_cast<std::size_t>(kProducers * kPerProducer));
  for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k], static_cast<int>(k));
  EXPECT_EQ(q.dropped(), 0U);
  EXPECT_EQ(q.pushed(), static_cast<uint64_t>(kProducers * kPerProducer));
}

TEST(BoundedQueue, NewestWinsUnderConcurrencyAccountsForEveryItem) {
  constexpr int kItems = 5000;
  BoundedQueue<int> q(3, QueuePolicy::kNewestWins);
  std::thread producer([&] {
    for (int i = 0; i < kItems; ++i) q.push(i);
    q.close();
  });
  std::vector<int> got;
  while (!q.drained()) {
    if (auto v = q.pop(10ms)) got.push_back(*v);
  }
  producer.join();
  EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
  EXPECT_EQ(std::adjacent_find(got.begin(), got.end()), got.end());  // no item twice
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back(), kItems - 1);  // the newest is never the one dropped
  EXPECT_EQ(got.size() + q.dropped(), static_cast<std::size_t>(kItems));
}

TEST(BoundedQueue, CloseWakesAWaitingProducerAndConsumer) {
  BoundedQueue<int> full(1, QueuePolicy::kLossless);
  full.push(1);
  std::atomic<bool> returned{false};
  std::thread producer([&] {
    EXPECT_EQ(full.push(2), PushResult::kClosed);  // waits for room until closed, then refuses
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
  EXPECT_EQ(full.push(3), PushResult::kClosed);
}

TEST(BoundedQueue, PopReturnsNothingAfterItsTimeout) {
  BoundedQueue<int> q(4, QueuePolicy::kNewestWins);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(q.pop(20ms).has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 20ms);
  EXPECT_FALSE(q.drained());
}

TEST(BoundedQueue, PopUnlessReturnsWhenStoppedAndLeavesTheItemsQueued) {
  BoundedQueue<int> q(4, QueuePolicy::kRefuseNew);
  std::atomic<bool> stop{false};
  std::vector<int> got;
  std::thread consumer([&] {
    while (auto v = q.pop_unless([&] { return stop.load(); })) got.push_back(*v);
  });
  q.push(1);
  q.push(2);
  while (q.size() > 0) std::this_thread::yield();
  stop = true;
  q.wake();
  consumer.join();
  q.push(3);
  EXPECT_EQ(got, (std::vector<int>{1, 2}));
  EXPECT_FALSE(q.pop_unless([] { return true; }).has_value());
  EXPECT_EQ(q.size(), 1U);  // still there for the next consumer
  EXPECT_EQ(q.try_pop(), 3);
}

}  // namespace
}  // namespace agvslam
