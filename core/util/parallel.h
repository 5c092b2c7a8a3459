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

// Calls fn(i) for every i in [0, n).
template <typename Fn>
void ParallelFor(std::int64_t n, std::int64_t grain, Fn&& fn) {
  ParallelForChunks(n, grain, [&fn](std::int64_t b, std::int64_t e) {
    for (std::int64_t i = b; i < e; ++i) fn(i);
  });
}

}  // namespace hdr4d
