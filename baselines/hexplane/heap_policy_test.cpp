// KeepFreedHeap: a large block freed and allocated again is served from the kept heap, so
// touching it again costs (almost) no page faults; without the policy glibc maps it afresh.
#include "baselines/hexplane/heap_policy.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdlib>
#include <cstring>

namespace hdr4d::baselines::hexplane {
namespace {

long MinorFaults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

// Allocates, touches every page and frees `bytes`; returns the minor faults that took.
long FaultsOfTouch(std::size_t bytes) {
  const long before = MinorFaults();
  char* p = static_cast<char*>(std::malloc(bytes));
  if (!p) return -1;
  std::memset(p, 1, bytes);
  volatile char keep = p[bytes / 2];
  (void)keep;
  std::free(p);
  return MinorFaults() - before;
}

TEST(HeapPolicy, FreedBlockIsReusedWithoutFaults) {
#if defined(__GLIBC__)
  constexpr std::size_t kBytes = 48u << 20;  // 48 MB: above glibc's largest default mmap threshold
  const long pages = long(kBytes / 4096);
  // The default policy maps such a block each time: one fault per page, every time (fewer
  // where transparent huge pages back it: then there is nothing to measure).
  if (FaultsOfTouch(kBytes) < pages / 2) GTEST_SKIP() << "huge pages: too few faults to compare";
  ASSERT_TRUE(KeepFreedHeap());
  FaultsOfTouch(kBytes);  // the heap grows once
  EXPECT_LT(FaultsOfTouch(kBytes), pages / 10);
#else
  EXPECT_FALSE(KeepFreedHeap());
#endif
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
