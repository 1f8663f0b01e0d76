// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/thread_pool.h"

#include <atomic>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(ThreadPool, RunsEveryIndexOnceOverManyLoops) {
  for (int threads : {1, 2, 4}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.size(), threads);
    for (int loop = 0; loop < 200; ++loop) {
      const int n = loop % 7;  // includes empty and single-index loops
      std::vector<std::atomic<int>> hits(n);
      pool.ParallelFor(n, [&](int i) { hits[i].fetch_add(1); });
      for (int i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << threads << " " << loop;
    }
  }
}

TEST(ThreadPool, UsesSeveralThreads) {
  ThreadPool pool(2);
  std::mutex mutex;
  std::set<std::thread::id> ids;
  std::atomic<int> waiting{0};
  // Two indices that each wait for the other: they can only finish on two threads.
  pool.ParallelFor(2, [&](int) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      ids.insert(std::this_thread::get_id());
    }
    waiting.fetch_add(1);
    while (waiting.load() < 2) std::this_thread::yield();
  });
  EXPECT_EQ(ids.size(), 2u);
}

TEST(ThreadPool, RethrowsTheFirstErrorAndStaysUsable) {
  ThreadPool pool(3);
  std::atomic<int> ran{0};
  EXPECT_THROW(pool.ParallelFor(10,
                                [&](int i) {
                                  ran.fetch_add(1);
                                  if (i == 3) throw std::runtime_error("index 3");
                                }),
               std::runtime_error);
  EXPECT_EQ(ran.load(), 10);
  int sum = 0;
  std::mutex mutex;
  pool.ParallelFor(5, [&](int i) {
    std::lock_guard<std::mutex> lock(mutex);
    sum += i;
  });
  EXPECT_EQ(sum, 10);
  EXPECT_THROW(ThreadPool(-1), Error);
}

}  // namespace
}  // namespace unseen
