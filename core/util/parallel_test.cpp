#include "core/util/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "core/util/progress.h"

namespace hdr4d {
namespace {

TEST(Parallel, EveryIndexOnceInFixedChunks) {
  std::vector<std::atomic<int>> hits(1003);
  std::atomic<int> bad_chunks{0};
  ParallelForChunks(1003, 100, [&](std::int64_t b, std::int64_t e) {
    // Chunk boundaries are multiples of the grain whatever the scheduling.
    if (b % 100 != 0 || e - b > 100 || (e != 1003 && e % 100 != 0)) ++bad_chunks;
    for (std::int64_t i = b; i < e; ++i) ++hits[i];
  });
  EXPECT_EQ(bad_chunks.load(), 0);
  for (const auto& h : hits) ASSERT_EQ(h.load(), 1);
}

TEST(Parallel, EmptyAndTinyRanges) {
  int calls = 0;
  ParallelFor(0, 10, [&](std::int64_t) { ++calls; });
  EXPECT_EQ(calls, 0);
  ParallelFor(1, 0, [&](std::int64_t) { ++calls; });  // grain 0 is treated as 1
  EXPECT_EQ(calls, 1);
}

TEST(Parallel, ExceptionsReachTheCaller) {
  EXPECT_THROW(ParallelFor(1000, 1,
                           [](std::int64_t i) {
                             if (i == 517) throw std::runtime_error("boom");
                           }),
               std::runtime_error);
}

TEST(Parallel, ThreadLimitHoldsWhileAlive) {
  const int all = MaxThreads();
  {
    ThreadLimit one(1);
    EXPECT_EQ(MaxThreads(), 1);
  }
  EXPECT_EQ(MaxThreads(), all);
}

TEST(Parallel, RunAlongsideRunsBothAndWaitsForTheSideJob) {
  for (const int threads : {1, 2}) {
    ThreadLimit limit(threads);
    std::atomic<bool> side_done{false};
    long long main_sum = 0;
    RunAlongside([&] { side_done = true; },
                 [&] {
                   std::vector<long long> parts(64, 0);
                   ParallelFor(64, 1, [&](std::int64_t i) { parts[i] = i; });
                   main_sum = std::accumulate(parts.begin(), parts.end(), 0LL);
                 });
    EXPECT_TRUE(side_done.load()) << threads;
    EXPECT_EQ(main_sum, 63 * 64 / 2) << threads;
  }
}

TEST(Parallel, RunAlongsideRethrowsOnlyAfterTheSideJobHasFinished) {
  for (const int threads : {1, 2}) {
    ThreadLimit limit(threads);
    // main throws at once; the side job (which would read main's buffers) is over by the time
    // the caller sees the exception.
    std::atomic<int> side_steps{0};
    const auto slow_side = [&] {
      for (int i = 0; i < 1000; ++i) side_steps.fetch_add(1);
    };
    EXPECT_THROW(RunAlongside(slow_side, [] { throw std::runtime_error("main"); }),
                 std::runtime_error);
    EXPECT_EQ(side_steps.load(), 1000) << threads;
    // An exception from the side job reaches the caller after main has run.
    bool main_ran = false;
    EXPECT_THROW(RunAlongside([] { throw std::logic_error("side"); }, [&] { main_ran = true; }),
                 std::logic_error);
    EXPECT_TRUE(main_ran) << threads;
  }
}

TEST(Progress, LogLinesAtMostOnePerTenthAndOneFinal) {
  // stderr is not a terminal under ctest, so plain lines are written: capture them.
  ::testing::internal::CaptureStderr();
  {
    Progress progress("work", 100);
    for (int i = 0; i < 100; ++i) progress.Advance(1, "loss 0.5");
    progress.Finish();
    progress.Finish();  // idempotent
  }
  const std::string log = ::testing::internal::GetCapturedStderr();
  const auto lines = std::count(log.begin(), log.end(), '\n');
  EXPECT_GE(lines, 10);
  EXPECT_LE(lines, 11);
  EXPECT_NE(log.find("work 100/100 (100%)"), std::string::npos) << log;
  EXPECT_NE(log.find("loss 0.5"), std::string::npos) << log;
}

TEST(Progress, DisabledPrintsNothing) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("quiet", 10, false);
    progress.Advance(10);
  }
  EXPECT_TRUE(::testing::internal::GetCapturedStderr().empty());
}

}  // namespace
}  // namespace hdr4d
