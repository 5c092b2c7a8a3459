// Tests only: run a check once per Highway target compiled into hdr4d and supported by this CPU
// (AVX-512, AVX2, the scalar baseline) and allowed by HDR4D_SIMD_TARGETS, with dispatch
// restricted to that target.
#pragma once

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cstdint>

#include "method/raster/simd_dispatch.h"

namespace hdr4d::method {

// Runs `body` once per target, under a SCOPED_TRACE naming it; returns how many ran. Afterwards
// the process's own restriction (HDR4D_SIMD_TARGETS, or none) is in force again.
template <typename Body>
int ForEachCompiledTarget(Body body) {
  const std::int64_t supported = hwy::SupportedTargets();  // within HDR4D_SIMD_TARGETS
  int ran = 0;
  for (std::int64_t target = 1; target != 0 && target <= HWY_TARGETS; target <<= 1) {
    if ((HWY_TARGETS & target) == 0 || (supported & target) == 0) continue;
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    body();
    ++ran;
  }
  hwy::SetSupportedTargetsForTest(ProcessSimdTargets());
  return ran;
}

// The fewest runs ForEachCompiledTarget may make: a vector target and the baseline, or every
// target HDR4D_SIMD_TARGETS names when it names fewer.
inline int MinimumTargetRuns() {
  const std::int64_t process = ProcessSimdTargets();
  return process == 0 ? 2
                      : std::min(2, __builtin_popcountll(static_cast<unsigned long long>(process)));
}

}  // namespace hdr4d::method
