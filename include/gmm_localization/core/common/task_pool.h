#pragma once
// A small pool of worker threads for the data-parallel loops of a match (the search's headings,
// the refinement's and the labels' points). run(n, fn) calls fn(i) once for each i in [0, n),
// spread over the workers and the calling thread, and returns when every call has returned.
//
// Determinism is the callers' part: they cut the work into a fixed number of pieces that does
// not depend on the thread count and combine the pieces' results in index order, so that a
// match gives bit-identical results on 1 or N threads.
//
// One run at a time: a run() issued while another is in progress (from another thread, or from
// inside fn) executes serially on its caller, which keeps nested and concurrent use safe and
// deadlock-free. An exception thrown by fn is rethrown by run() after every piece has finished
// (the first one thrown; the others are dropped).

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace gmm_localization {

class TaskPool {
 public:
  /// `threads`: threads that work on a run, the caller included (1: no workers, run() is a
  /// plain loop); 0: one per hardware thread (std::thread::hardware_concurrency, at least 1).
  explicit TaskPool(int threads);
  ~TaskPool();
  TaskPool(const TaskPool&) = delete;
  TaskPool& operator=(const TaskPool&) = delete;

  /// Threads that work on a run, the caller included.
  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// What `threads` resolves to: 0 -> the hardware threads (at least 1), otherwise itself,
  /// clamped to [1, kMaxThreads].
  static int resolve(int threads);
  static constexpr int kMaxThreads = 64;

  void run(int n, const std::function<void(int)>& fn);

 private:
  struct Job;
  void workerLoop();
  /// Runs the job's unclaimed pieces; returns how many it ran.
  static int drain(Job& job);

  std::vector<std::thread> workers_;
  std::mutex run_mutex_;  ///< held by the run in progress (try_lock: others go serial)
  std::mutex mutex_;      ///< guards job_; generation_ and stop_ change under it
  std::condition_variable wake_, finished_;
  std::shared_ptr<Job> job_;
  /// Bumped per run. Workers spin on it for a few tens of microseconds before they sleep (the
  /// loops of a match issue runs closer together than a condition variable's wake-up), and
  /// the caller spins likewise for the workers' last pieces.
  std::atomic<uint64_t> generation_{0};
  std::atomic<bool> stop_{false};
};

/// Runs fn(i) for i in [0, n) on `pool`, or serially when `pool` is null.
inline void parallelFor(TaskPool* pool, int n, const std::function<void(int)>& fn) {
  if (pool != nullptr) {
    pool->run(n, fn);
    return;
  }
  for (int i = 0; i < n; ++i) fn(i);
}

}  // namespace gmm_localization
