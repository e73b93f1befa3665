#include "gmm_localization/core/common/task_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace gmm_localization {
namespace {

TEST(TaskPool, ResolvesTheThreadCount) {
  EXPECT_EQ(TaskPool::resolve(1), 1);
  EXPECT_EQ(TaskPool::resolve(3), 3);
  EXPECT_GE(TaskPool::resolve(0), 1);
  EXPECT_EQ(TaskPool::resolve(1000), TaskPool::kMaxThreads);
  EXPECT_EQ(TaskPool(1).threads(), 1);
  EXPECT_EQ(TaskPool(4).threads(), 4);
}

TEST(TaskPool, CallsEveryIndexExactlyOnce) {
  for (int threads : {1, 2, 4}) {
    TaskPool pool(threads);
    for (int n : {0, 1, 2, 7, 1000}) {
      std::vector<std::atomic<int>> calls(static_cast<size_t>(n));
      for (int round = 0; round < 20; ++round) {
        pool.run(n, [&](int i) { calls[static_cast<size_t>(i)].fetch_add(1); });
      }
      for (int i = 0; i < n; ++i) EXPECT_EQ(calls[static_cast<size_t>(i)].load(), 20) << i;
    }
  }
}

TEST(TaskPool, UsesTheWorkersForLongPieces) {
  TaskPool pool(2);
  std::mutex m;
  std::set<std::thread::id> ids;
  for (int round = 0; round < 50 && ids.size() < 2; ++round) {
    pool.run(4, [&](int) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    });
  }
  EXPECT_EQ(ids.size(), 2u);  // a worker took part (pieces of 2 ms, 50 tries)
}

TEST(TaskPool, NestedAndConcurrentRunsGoSerialAndFinish) {
  TaskPool pool(2);
  std::atomic<int> inner{0};
  pool.run(4, [&](int) { pool.run(3, [&](int) { inner.fetch_add(1); }); });
  EXPECT_EQ(inner.load(), 12);
  std::atomic<int> total{0};
  std::thread other([&] {
    for (int k = 0; k < 200; ++k) pool.run(5, [&](int) { total.fetch_add(1); });
  });
  for (int k = 0; k < 200; ++k) pool.run(5, [&](int) { total.fetch_add(1); });
  other.join();
  EXPECT_EQ(total.load(), 2000);
}

TEST(TaskPool, RethrowsAfterEveryPieceFinished) {
  TaskPool pool(2);
  std::atomic<int> done{0};
  EXPECT_THROW(pool.run(50,
                        [&](int i) {
                          if (i == 3) throw std::runtime_error("piece 3");
                          done.fetch_add(1);
                        }),
               std::runtime_error);
  EXPECT_EQ(done.load(), 49);
  pool.run(10, [&](int) { done.fetch_add(1); });  // still usable
  EXPECT_EQ(done.load(), 59);
}

TEST(TaskPool, ParallelForWithoutAPoolIsALoop) {
  std::vector<int> order;
  parallelFor(nullptr, 5, [&](int i) { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
}

}  // namespace
}  // namespace gmm_localization
