// The main of every test binary (GoogleTest's, after applying HDR4D_SIMD_TARGETS): with it set,
// the whole binary runs the method's kernels on the SIMD targets it names, which is how
// scripts/test.sh proves the AVX2 and scalar paths on an AVX-512 machine.
#include <gtest/gtest.h>

#include <cstdio>

#include "method/raster/simd_dispatch.h"

int main(int argc, char** argv) {
  if (!hdr4d::method::ApplySimdTargetsOrPrintError("error: ")) return 2;
  // stderr: CTest reads the test list from stdout.
  if (hdr4d::method::ProcessSimdTargets() != 0)
    std::fprintf(stderr, "SIMD target: %s\n", hdr4d::method::SimdTargetDescription().c_str());
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
