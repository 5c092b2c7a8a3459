#include "core/util/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <exception>

namespace hdr4d {

struct ThreadLimit::Impl {
  std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int threads) : impl_(std::make_unique<Impl>()) {
  if (threads > 0) {
    impl_->control = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  }
}

ThreadLimit::~ThreadLimit() = default;

int MaxThreads() {
  return static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

void ParallelForChunks(std::int64_t n,
                       std::int64_t grain,
                       const std::function<void(std::int64_t, std::int64_t)>& fn) {
  if (n <= 0) return;
  grain = std::max<std::int64_t>(grain, 1);
  if (n <= grain || MaxThreads() == 1) {
    for (std::int64_t b = 0; b < n; b += grain) fn(b, std::min(n, b + grain));
    return;
  }
  // Fixed chunk boundaries (multiples of grain), so chunk-level results do not depend on
  // how TBB schedules them.
  const std::int64_t chunks = (n + grain - 1) / grain;
  tbb::parallel_for(
      tbb::blocked_range<std::int64_t>(0, chunks, 1),
      [&](const tbb::blocked_range<std::int64_t>& r) {
        for (std::int64_t c = r.begin(); c < r.end(); ++c)
          fn(c * grain, std::min(n, (c + 1) * grain));
      },
      tbb::simple_partitioner());
}

void RunAlongside(const std::function<void()>& side, const std::function<void()>& main) {
  std::exception_ptr failure;
  const auto keep = [&failure](const std::function<void()>& job) {
    try {
      job();
    } catch (...) {
      if (!failure) failure = std::current_exception();
    }
  };
  if (MaxThreads() == 1) {
    keep(main);
    keep(side);
  } else {
    tbb::task_group group;
    group.run(side);
    keep(main);
    // side reads buffers the caller owns: it must be done before anything unwinds.
    keep([&group] { group.wait(); });
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace hdr4d
