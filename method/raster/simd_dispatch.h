// Which SIMD target the method's Highway kernels run: by default the best one compiled into
// hdr4d that the CPU supports (AVX-512, AVX2 or the scalar baseline); the environment variable
// HDR4D_SIMD_TARGETS limits that choice for the whole process, so that a machine with AVX-512
// can also run (and test) the AVX2 and scalar paths. Every main (the CLI, each test and
// benchmark binary) calls ApplySimdTargetsFromEnvironment once at start-up.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace hdr4d::method {

inline constexpr const char* kSimdTargetsVariable = "HDR4D_SIMD_TARGETS";

// The Highway targets compiled into hdr4d that this CPU supports (a mask of HWY_* bits),
// ignoring any restriction in force.
std::int64_t CpuSimdTargets();

// The mask of Highway targets that `value` names: one name or a comma list, case-insensitive,
// each a compiled target ("avx3" or "avx512", "avx2", and "scalar", "emu128" or "baseline" for
// the baseline). 0 for an empty value (no restriction). Throws hdr4d::Error naming the variable
// and the value for an unknown name (listing the valid ones) and for a target missing from
// `available` (listing those that are there).
std::int64_t ParseSimdTargets(std::string_view value, std::int64_t available);

// Reads HDR4D_SIMD_TARGETS and limits Highway's run-time dispatch to the targets it names (none
// when it is unset or empty: Highway picks the best the CPU has). Throws hdr4d::Error as
// ParseSimdTargets does, leaving the restriction as it was.
void ApplySimdTargetsFromEnvironment();

// For a main: ApplySimdTargetsFromEnvironment, and on a bad value its error on stderr after
// `prefix` (e.g. "hdr4d: error: "); false then, and the main exits with an error.
bool ApplySimdTargetsOrPrintError(const char* prefix);

// The mask ApplySimdTargetsFromEnvironment put in force, 0 when none. Code that changes
// Highway's targets for a while (tests) restores this afterwards.
std::int64_t ProcessSimdTargets();

// The target HWY_DYNAMIC_DISPATCH picks now, as Highway names it ("AVX3", "AVX2", "SCALAR").
std::string ActiveSimdTarget();

// One line for --version and logs: "AVX3", or "AVX2 (HDR4D_SIMD_TARGETS=avx2)" when restricted.
std::string SimdTargetDescription();

}  // namespace hdr4d::method
