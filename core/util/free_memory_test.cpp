#include "core/util/free_memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

namespace hdr4d {
namespace {

// Blocks freed in the middle of the heap stay resident until ReturnFreedMemory gives them back.
TEST(ReturnFreedMemory, GivesBackFreedBlocksTheHeapKept) {
#if !defined(__GLIBC__) || !defined(__linux__)
  GTEST_SKIP() << "malloc_trim and /proc are glibc / Linux";
#else
  ASSERT_GT(ResidentBytes(), 0u);
  constexpr std::size_t kBlock = 64 * 1024;  // below glibc's mmap threshold: heap blocks
  constexpr int kBlocks = 2000;              // 128 MB
  std::vector<std::unique_ptr<char[]>> blocks;
  for (int i = 0; i < kBlocks; ++i) {
    blocks.emplace_back(new char[kBlock]);
    std::memset(blocks.back().get(), 1, kBlock);  // resident
  }
  std::unique_ptr<char[]> pin(new char[kBlock]);  // above them: the heap's top cannot shrink
  std::memset(pin.get(), 1, kBlock);
  // Kept observable: an optimiser may drop an allocation nothing reads (clang 14 at -O1 did).
  static char* volatile pinned;
  pinned = pin.get();
  blocks.clear();
  const std::size_t freed = ResidentBytes();
  ReturnFreedMemory();
  const std::size_t returned = ResidentBytes();
  EXPECT_LT(returned + 100 * 1024 * 1024, freed) << "freed " << freed << ", after " << returned;
#endif
}

TEST(PhysicalMemoryBytes, HoldsWhatTheProcessHolds) {
#if defined(__linux__)
  EXPECT_GT(PhysicalMemoryBytes(), ResidentBytes());
  // The peak is at least what the process holds now, up to the kernel's per-thread counters,
  // which reach the two readings at different times (up to 64 pages a thread; 4 MiB allowed).
  EXPECT_GE(PeakResidentBytes() + 4 * 1024 * 1024, ResidentBytes());
  EXPECT_GT(PhysicalMemoryBytes(), PeakResidentBytes());
#else
  GTEST_SKIP() << "Linux";
#endif
}

}  // namespace
}  // namespace hdr4d
