// KeyframeWorker: refuse-new and drop-oldest queues, inline processing in order, the thread processing every
// queued keyframe, idle() false while a keyframe is in progress, wait_until_idle() returning only once the last
// one is done, stop() leaving the rest queued, clear(). The threaded cases are meant to be repeated
// (--gtest_repeat) to catch races.
#include "agvslam/slam/keyframe_worker.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "agvslam/slam/frame.h"

namespace agvslam::slam {
namespace {

using namespace std::chrono_literals;

KeyFramePtr keyframe(uint64_t id) { return std::make_shared<KeyFrame>(id, Frame{}); }

// Records the ids processed, in order.
struct Recorder {
  std::mutex mutex;
  std::vector<uint64_t> ids;
  void operator()(const KeyFramePtr& kf) {
    std::lock_guard<std::mutex> lock(mutex);
    ids.push_back(kf->id);
  }
  std::vector<uint64_t> get() {
    std::lock_guard<std::mutex> lock(mutex);
    return ids;
  }
};

// A work function that blocks in the worker until released, so a test can look at the worker meanwhile.
struct Gate {
  std::mutex mutex;
  std::condition_variable cv;
  bool started = false, released = false;
  void block() {
    std::unique_lock<std::mutex> lock(mutex);
    started = true;
    cv.notify_all();
    cv.wait(lock, [&] { return released; });
  }
  bool wait_started() {
    std::unique_lock<std::mutex> lock(mutex);
    return cv.wait_for(lock, 10s, [&] { return started; });
  }
  void release() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      released = true;
    }
    cv.notify_all();
  }
};

TEST(KeyframeWorker, RefuseNewKeepsTheQueuedOnesAndProcessesThemInlineInOrder) {
  Recorder rec;
  KeyframeWorker w(2, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr& kf) { rec(kf); });
  EXPECT_EQ(w.push(keyframe(1)), KeyframeWorker::Pushed::kQueued);
  EXPECT_EQ(w.push(keyframe(2)), KeyframeWorker::Pushed::kQueued);
  EXPECT_EQ(w.push(keyframe(3)), KeyframeWorker::Pushed::kRefused);
  EXPECT_EQ(w.size(), 2U);
  EXPECT_FALSE(w.idle());
  w.process_pending();
  EXPECT_EQ(rec.get(), (std::vector<uint64_t>{1, 2}));
  EXPECT_TRUE(w.idle());
  EXPECT_TRUE(w.empty());
}

TEST(KeyframeWorker, DropOldestKeepsTheNewest) {
  Recorder rec;
  KeyframeWorker w(2, KeyframeWorker::WhenFull::kDropOldest, [&](const KeyFramePtr& kf) { rec(kf); });
  w.push(keyframe(1));
  w.push(keyframe(2));
  EXPECT_EQ(w.push(keyframe(3)), KeyframeWorker::Pushed::kQueuedDroppedOldest);
  EXPECT_EQ(w.size(), 2U);
  w.wait_until_idle();  // no thread: processes them here
  EXPECT_EQ(rec.get(), (std::vector<uint64_t>{2, 3}));
  EXPECT_TRUE(w.idle());
}

TEST(KeyframeWorker, ZeroCapacityIsRejected) {
  EXPECT_THROW(KeyframeWorker(0, KeyframeWorker::WhenFull::kRefuseNew, [](const KeyFramePtr&) {}),
               std::invalid_argument);
}

TEST(KeyframeWorker, ClearDropsTheQueuedOnes) {
  Recorder rec;
  KeyframeWorker w(4, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr& kf) { rec(kf); });
  w.push(keyframe(1));
  w.push(keyframe(2));
  const std::vector<KeyFramePtr> dropped = w.clear();
  ASSERT_EQ(dropped.size(), 2U);  // handed back: their points may still be in a map
  EXPECT_EQ(dropped[0]->id, 1U);
  EXPECT_EQ(dropped[1]->id, 2U);
  EXPECT_TRUE(w.idle());
  w.process_pending();
  EXPECT_TRUE(rec.get().empty());
}

TEST(KeyframeWorker, WaitForRoomReturnsWhenTheThreadTakesAKeyframe) {
  std::atomic<bool> release{false};
  KeyframeWorker w(1, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr&) {
    while (!release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  w.start();
  w.push(keyframe(1));  // taken by the thread, which then blocks
  while (!w.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_TRUE(w.wait_for_room(1000));  // the queue itself is empty
  EXPECT_EQ(w.push(keyframe(2)), KeyframeWorker::Pushed::kQueued);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(w.wait_for_room(50));  // full while the thread is busy: gives up after the timeout
  const double waited_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(waited_ms, 45.0);
  std::thread releaser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    release = true;
  });
  EXPECT_TRUE(w.wait_for_room(5000));  // keyframe 2 taken off the queue
  releaser.join();
  w.wait_until_idle();
  w.stop();
}

TEST(KeyframeWorker, TheThreadProcessesEveryKeyframeAndWaitUntilIdleWaitsForTheLast) {
  std::atomic<int> in_work{0};
  std::atomic<bool> overlapped{false};
  Recorder rec;
  KeyframeWorker w(1000, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr& kf) {
    if (++in_work > 1) overlapped = true;
    rec(kf);
    --in_work;
  });
  w.start();
  EXPECT_TRUE(w.running());
  for (int round = 0; round < 20; ++round) {
    for (uint64_t k = 0; k < 10; ++k)
      ASSERT_EQ(w.push(keyframe(static_cast<uint64_t>(round) * 10 + k)), KeyframeWorker::Pushed::kQueued);
    w.wait_until_idle();
    EXPECT_TRUE(w.idle());
    ASSERT_EQ(rec.get().size(), static_cast<std::size_t>(round + 1) * 10) << "round " << round;
  }
  w.stop();
  EXPECT_FALSE(overlapped.load());
  const std::vector<uint64_t> ids = rec.get();
  for (std::size_t k = 0; k < ids.size(); ++k) EXPECT_EQ(ids[k], k);
}

TEST(KeyframeWorker, NotIdleWhileAKeyframeIsInProgress) {
  Gate gate;
  KeyframeWorker w(2, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr&) { gate.block(); });
  w.start();
  w.push(keyframe(1));
  ASSERT_TRUE(gate.wait_started());
  EXPECT_TRUE(w.empty());  // taken off the queue ...
  EXPECT_FALSE(w.idle());  // ... but not done
  std::atomic<bool> waited{false};
  std::thread waiter([&] {
    w.wait_until_idle();
    waited = true;
  });
  std::this_thread::sleep_for(20ms);
  EXPECT_FALSE(waited.load());
  gate.release();
  waiter.join();
  EXPECT_TRUE(w.idle());
}

TEST(KeyframeWorker, StopFinishesTheKeyframeInProgressAndLeavesTheRestQueued) {
  Gate gate;
  Recorder rec;
  KeyframeWorker w(4, KeyframeWorker::WhenFull::kRefuseNew, [&](const KeyFramePtr& kf) {
    rec(kf);
    gate.block();
  });
  w.start();
  w.push(keyframe(1));
  ASSERT_TRUE(gate.wait_started());
  w.push(keyframe(2));
  w.push(keyframe(3));
  std::thread stopper([&] { w.stop(); });
  std::this_thread::sleep_for(20ms);
  gate.release();
  stopper.join();
  EXPECT_FALSE(w.running());
  EXPECT_EQ(rec.get(), (std::vector<uint64_t>{1}));
  EXPECT_EQ(w.size(), 2U);
  w.process_pending();  // without the thread, in the caller's
  EXPECT_EQ(rec.get(), (std::vector<uint64_t>{1, 2, 3}));
}

TEST(KeyframeWorker, AnIdleThreadStopsPromptly) {
  KeyframeWorker w(2, KeyframeWorker::WhenFull::kRefuseNew, [](const KeyFramePtr&) {});
  w.start();
  std::this_thread::sleep_for(5ms);
  const auto t0 = std::chrono::steady_clock::now();
  w.stop();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
  w.start();  // and starts again
  w.push(keyframe(1));
  w.wait_until_idle();
  EXPECT_TRUE(w.idle());
}

}  // namespace
}  // namespace agvslam::slam
