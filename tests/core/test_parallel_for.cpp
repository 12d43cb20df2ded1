// parallel_for: every index is visited exactly once whatever the thread count and block size; worker numbers
// stay below the thread count; workers really run at the same time; per-worker integer partial sums give the
// same total for any thread count; the first exception reaches the caller and stops the handing out of blocks.
// Meant to be repeated (--gtest_repeat) to catch races.
#include "agvslam/core/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

namespace agvslam {
namespace {

TEST(ParallelFor, VisitsEveryIndexOnceForAnyThreadCountAndGrain) {
  for (int threads : {1, 2, 3, 8}) {
    for (std::size_t n : {std::size_t(1), std::size_t(7), std::size_t(1000)}) {
      for (std::size_t grain : {std::size_t(0), std::size_t(1), std::size_t(4), std::size_t(333), std::size_t(5000)}) {
        std::vector<std::atomic<int>> visits(n);
        std::atomic<bool> bad_worker{false};
        parallel_for(threads, n, grain, [&](std::size_t begin, std::size_t end, int worker) {
          if (worker < 0 || worker >= threads || begin >= end || end > n) bad_worker = true;
          for (std::size_t i = begin; i < end; ++i) ++visits[i];
        });
        EXPECT_FALSE(bad_worker.load()) << threads << " threads, n " << n << ", grain " << grain;
        for (std::size_t i = 0; i < n; ++i) {
          ASSERT_EQ(visits[i].load(), 1) << "index " << i << ", " << threads << " threads, n " << n << ", grain "
                                         << grain;
        }
      }
    }
  }
}

TEST(ParallelFor, NothingToDoCallsNothing) {
  bool called = false;
  parallel_for(4, 0, 1, [&](std::size_t, std::size_t, int) { called = true; });
  EXPECT_FALSE(called);
}

TEST(ParallelFor, OneWorkerRunsOnceOverTheWholeRangeInTheCallersThread) {
  int calls = 0;
  std::size_t begin = 99, end = 0;
  std::thread::id id;
  parallel_for(1, 50, 4, [&](std::size_t b, std::size_t e, int) {
    ++calls;
    begin = b;
    end = e;
    id = std::this_thread::get_id();
  });
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(begin, 0U);
  EXPECT_EQ(end, 50U);
  EXPECT_EQ(id, std::this_thread::get_id());
}

TEST(ParallelFor, WorkersRunAtTheSameTime) {
  // Each of the two blocks waits until both have started: only two concurrent workers get through quickly.
  std::mutex m;
  std::condition_variable cv;
  int entered = 0;
  bool both = true;
  parallel_for(2, 2, 1, [&](std::size_t, std::size_t, int) {
    std::unique_lock<std::mutex> lock(m);
    ++entered;
    cv.notify_all();
    if (!cv.wait_for(lock, std::chrono::seconds(10), [&] { return entered >= 2; })) both = false;
  });
  EXPECT_TRUE(both);
}

TEST(ParallelFor, PerWorkerIntegerSumsDoNotDependOnTheThreadCount) {
  constexpr std::size_t kN = 100000;
  std::vector<uint64_t> values(kN);
  for (std::size_t i = 0; i < kN; ++i) values[i] = (i * 2654435761U) % 1000;
  const uint64_t expected = std::accumulate(values.begin(), values.end(), uint64_t{0});
  for (int threads : {1, 2, 4, 7}) {
    std::vector<uint64_t> partial(static_cast<std::size_t>(threads), 0);
    parallel_for(threads, kN, 1000, [&](std::size_t begin, std::size_t end, int worker) {
      for (std::size_t i = begin; i < end; ++i) partial[static_cast<std::size_t>(worker)] += values[i];
    });
    EXPECT_EQ(std::accumulate(partial.begin(), partial.end(), uint64_t{0}), expected) << threads << " threads";
  }
}

TEST(ParallelFor, TheFirstExceptionReachesTheCallerAndStopsTheWork) {
  std::atomic<int> blocks_run{0};
  try {
    parallel_for(3, 10000, 1, [&](std::size_t begin, std::size_t, int) {
      ++blocks_run;
      if (begin == 5) throw std::runtime_error("block 5");
    });
    FAIL() << "expected the exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "block 5");
  }
  // Blocks already handed out finish; no new ones start once the failure is seen.
  EXPECT_LT(blocks_run.load(), 10000);
  EXPECT_THROW(parallel_for(1, 3, 1, [](std::size_t, std::size_t, int) { throw std::logic_error("inline"); }),
               std::logic_error);
}

}  // namespace
}  // namespace agvslam
