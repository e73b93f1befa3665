#include "gmm_localization/core/common/task_pool.h"

#include <algorithm>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gmm_localization {

namespace {

/// How long a worker waits for the next run, and the caller for the workers' last pieces,
/// spinning before it sleeps on a condition variable.
constexpr std::chrono::microseconds kSpin(50);

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

/// Spins until `done()` or kSpin has passed; returns done().
template <typename Done>
bool spinUntil(Done done) {
  const auto deadline = std::chrono::steady_clock::now() + kSpin;
  for (int i = 0;; ++i) {
    if (done()) return true;
    cpuRelax();
    if ((i & 63) == 63 && std::chrono::steady_clock::now() > deadline) return done();
  }
}

}  // namespace

struct TaskPool::Job {
  const std::function<void(int)>* fn = nullptr;
  int n = 0;
  std::atomic<int> next{0};  ///< the next piece to claim
  std::atomic<int> done{0};  ///< pieces finished
  std::mutex error_mutex;
  std::exception_ptr error;
};

int TaskPool::resolve(int threads) {
  if (threads <= 0) {
    threads = static_cast<int>(std::thread::hardware_concurrency());
    if (threads <= 0) threads = 1;
  }
  return std::clamp(threads, 1, kMaxThreads);
}

TaskPool::TaskPool(int threads) {
  const int n = resolve(threads);
  workers_.reserve(static_cast<size_t>(n - 1));
  for (int i = 1; i < n; ++i) workers_.emplace_back([this] { workerLoop(); });
}

TaskPool::~TaskPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

int TaskPool::drain(Job& job) {
  int finished = 0;
  for (int i = job.next.fetch_add(1); i < job.n; i = job.next.fetch_add(1)) {
    try {
      (*job.fn)(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(job.error_mutex);
      if (!job.error) job.error = std::current_exception();
    }
    job.done.fetch_add(1);
    ++finished;
  }
  return finished;
}

void TaskPool::workerLoop() {
  uint64_t seen = 0;
  for (;;) {
    spinUntil([&] { return stop_.load() || generation_.load() != seen; });
    std::shared_ptr<Job> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_.load() || generation_.load() != seen; });
      if (stop_) return;
      seen = generation_.load();
      job = job_;
    }
    if (!job || drain(*job) == 0) continue;
    { std::lock_guard<std::mutex> lock(mutex_); }
    finished_.notify_all();
  }
}

void TaskPool::run(int n, const std::function<void(int)>& fn) {
  if (n <= 0) return;
  std::unique_lock<std::mutex> running(run_mutex_, std::try_to_lock);
  if (workers_.empty() || n == 1 || !running.owns_lock()) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  auto job = std::make_shared<Job>();
  job->fn = &fn;
  job->n = n;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = job;
    ++generation_;
  }
  wake_.notify_all();
  drain(*job);
  // Every piece has been claimed; wait for the pieces still running on workers, not for the
  // workers: one woken late (or preempted before it claimed anything) finds no piece left
  // (next >= n) and touches nothing of the caller's, so the run need not wait for it.
  if (!spinUntil([&] { return job->done.load() == n; })) {
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, [&] { return job->done.load() == n; });
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_.reset();
  }
  if (job->error) std::rethrow_exception(job->error);
}

}  // namespace gmm_localization
