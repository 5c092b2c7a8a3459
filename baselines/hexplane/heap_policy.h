// Keep freed memory in the process between training steps instead of handing it back to the
// kernel. Each step of the grid engine allocates its per-sample matrices afresh (their row
// counts change from step to step): tens of MB, above glibc's mmap threshold, so every step
// mapped new pages and unmapped them again, and the first touch of each page was a page fault.
// Measured on datagen lego mini (HDR-HexPlane, 300 iterations x 512 rays, two threads): 8.0
// million minor faults, 69 of 233 CPU-s in the kernel (docs/history/hexplane.md).
#pragma once

namespace hdr4d::baselines::hexplane {

// Makes glibc serve every block from the heap (none mapped on its own) and never trim it, so a
// freed block stays for the next step. The cost is memory: blocks of changing sizes fragment the
// kept heap (peak RSS 3.6 -> 4.9 GB on a 30-step run with a 200 px test render, whose 8192-ray
// chunks dominate it). Process-wide; call once before the threads start. Returns false where the
// C library has no such setting (not glibc), which changes nothing but the speed.
bool KeepFreedHeap();

}  // namespace hdr4d::baselines::hexplane
