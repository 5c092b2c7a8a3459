// The main of every Google Benchmark binary (the library's, after applying HDR4D_SIMD_TARGETS):
// `HDR4D_SIMD_TARGETS=avx2 build/benchmark/runtime/bench_raster` times the AVX2 kernels on an
// AVX-512 machine. The target in use is in the report's context ("simd_target").
#include <benchmark/benchmark.h>

#include "method/raster/simd_dispatch.h"

int main(int argc, char** argv) {
  if (!hdr4d::method::ApplySimdTargetsOrPrintError("error: ")) return 2;
  benchmark::AddCustomContext("simd_target", hdr4d::method::SimdTargetDescription());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
