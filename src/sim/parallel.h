#pragma once
// Private: a minimal parallel-for over task indices on a fixed number of std::threads.

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace gmm_localization {
namespace sim {

template <typename Fn>
void parallelFor(int tasks, int threads, Fn fn) {
  threads = std::max(1, std::min(threads, tasks));
  if (threads == 1) {
    for (int k = 0; k < tasks; ++k) fn(k);
    return;
  }
  std::atomic<int> next{0};
  auto worker = [&]() {
    for (int k = next++; k < tasks; k = next++) fn(k);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
}

}  // namespace sim
}  // namespace gmm_localization
