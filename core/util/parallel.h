// The one parallel-for every kernel uses (oneTBB underneath), so kernels are written once.
// Work is split into fixed chunks of `grain` indices: results that are reduced per chunk in
// chunk order are identical from run to run at any thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

namespace hdr4d {

// Limits the threads every ParallelFor uses from now on (0 = all cores). Keep the returned
// object alive for as long as the limit should hold.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Threads a ParallelFor may use now.
int MaxThreads();

// Calls fn(begin, end) on disjoint chunks [begin, end) covering [0, n), each at most `grain`
// long, possibly in parallel. Exceptions thrown by fn propagate to the caller.
void ParallelForChunks(std::int64_t n,
                       std::int64_t grain,
                       const std::function<void(std::int64_t, std::int64_t)>& fn);

// Runs `side` (one serial job) as a task beside `main`, which runs on the calling thread, and
// returns when both are done: a serial job that would leave the other threads idle fills a gap
// in main's parallel loops instead. Neither may write what the other reads. With one thread,
// main runs first, then side. Both always run to their end; then an exception from either
// reaches the caller (main's, when both threw).
void RunAlongside(const std::function<void()>& side, const std::function<void()>& main);

// Calls fn(i) for every i in [0, n).
template <typename Fn>
void ParallelFor(std::int64_t n, std::int64_t grain, Fn&& fn) {
  ParallelForChunks(n, grain, [&fn](std::int64_t b, std::int64_t e) {
    for (std::int64_t i = b; i < e; ++i) fn(i);
  });
}

}  // namespace hdr4d
