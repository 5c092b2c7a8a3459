#include "baselines/hexplane/heap_policy.h"

#include <cstdlib>  // defines __GLIBC__ where it is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hdr4d::baselines::hexplane {

bool KeepFreedHeap() {
#if defined(__GLIBC__)
  // No block is mapped on its own (glibc caps M_MMAP_THRESHOLD at 32 MiB, below a step's
  // largest matrices at 4096 rays), and the heap's top is never trimmed: a freed block stays for
  // the next step. mallopt returns 1 on success.
  return mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, 0x7fffffff) == 1;
#else
  return false;
#endif
}

}  // namespace hdr4d::baselines::hexplane
