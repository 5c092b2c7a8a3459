// Tests only: run a check once per Highway target compiled into hdr4d and supported by this CPU
// (AVX-512, AVX2, SSE4, SSSE3, the scalar fallback), with dispatch restricted to that target.
#pragma once

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cstdint>

namespace hdr4d::method {

// Runs `body` once per target, under a SCOPED_TRACE naming it; returns how many ran.
template <typename Body>
int ForEachCompiledTarget(Body body) {
  const std::int64_t supported = hwy::SupportedTargets();
  int ran = 0;
  for (std::int64_t target = 1; target != 0 && target <= HWY_TARGETS; target <<= 1) {
    if ((HWY_TARGETS & target) == 0 || (supported & target) == 0) continue;
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    body();
    ++ran;
  }
  hwy::SetSupportedTargetsForTest(0);
  return ran;
}

}  // namespace hdr4d::method
