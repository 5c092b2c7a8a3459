// Giving freed heap memory back to the system, and reading how much the process holds.
//
// glibc keeps freed blocks below its mmap threshold in the heap for reuse, and raises that
// threshold to the size of any mmap'ed block freed (up to 32 MB). So after a burst of
// allocations of one size that are then freed (the test split's images after they are checked,
// densification's temporaries) the process keeps them resident although nothing reuses them:
// 0.35 GB of a paper-size scene at 800x800 (issue 15). ReturnFreedMemory releases the free
// pages of every arena (malloc_trim).
#pragma once

#include <cstddef>

namespace hdr4d {

// Releases the free pages of the heap to the system; a no-op where the C library has no
// malloc_trim. Costs a walk over the heap's free blocks (milliseconds at gigabytes).
void ReturnFreedMemory();

// The process's resident memory in bytes (Linux /proc/self/statm), 0 where unknown.
std::size_t ResidentBytes();

// The process's peak resident memory so far in bytes (getrusage), 0 where unknown.
std::size_t PeakResidentBytes();

// The machine's physical memory in bytes (sysconf), 0 where unknown.
std::size_t PhysicalMemoryBytes();

// What this process may still allocate, in bytes: the least of the memory the system has
// available (/proc/meminfo MemAvailable), the address-space limit (RLIMIT_AS) less what the
// process already maps, and its cgroup's limit (v2 memory.max) less what the cgroup uses. 0
// where none of them is known.
std::size_t AvailableMemoryBytes();

}  // namespace hdr4d
