#include "method/raster/simd_dispatch.h"

#include <hwy/targets.h>

#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/util/error.h"

namespace hdr4d::method {

namespace {

// The mask in force (0: none). Written once at start-up, read by tests that restore it.
std::atomic<std::int64_t> process_targets{0};

// Other spellings a user may reach for: AVX-512 is Highway's AVX3, and the baseline is
// whichever of SCALAR and EMU128 this build compiles (HWY_STATIC_TARGET).
struct Alias {
  const char* name;
  std::int64_t target;
};
constexpr Alias kAliases[] = {{"avx512", HWY_AVX3},
                              {"scalar", HWY_STATIC_TARGET},
                              {"emu128", HWY_STATIC_TARGET},
                              {"baseline", HWY_STATIC_TARGET}};

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string Name(std::int64_t target) { return Lower(hwy::TargetName(target)); }

// The single targets in `mask`, best first (Highway gives better targets lower bits).
std::vector<std::int64_t> Targets(std::int64_t mask) {
  std::vector<std::int64_t> out;
  for (; mask != 0; mask &= mask - 1) out.push_back(mask & -mask);
  return out;
}

// "avx3 (or avx512), avx2, scalar (or emu128, baseline)" for the targets in `mask`.
std::string Describe(std::int64_t mask, bool with_aliases) {
  std::string text;
  for (std::int64_t target : Targets(mask)) {
    if (!text.empty()) text += ", ";
    const std::string name = Name(target);
    text += name;
    std::string others;
    for (const Alias& alias : kAliases) {
      if (!with_aliases || alias.target != target || name == alias.name) continue;
      others += (others.empty() ? "" : ", ") + std::string(alias.name);
    }
    if (!others.empty()) text += " (or " + others + ")";
  }
  return text;
}

// The compiled target `name` (lower case) stands for, 0 when none.
std::int64_t Lookup(const std::string& name) {
  for (std::int64_t target : Targets(HWY_TARGETS)) {
    if (Name(target) == name) return target;
  }
  for (const Alias& alias : kAliases) {
    if (name == alias.name && (HWY_TARGETS & alias.target) != 0) return alias.target;
  }
  return 0;
}

}  // namespace

std::int64_t CpuSimdTargets() {
  const std::int64_t mock = process_targets.load();
  if (mock != 0) hwy::SetSupportedTargetsForTest(0);
  const std::int64_t cpu = hwy::SupportedTargets() & HWY_TARGETS;
  if (mock != 0) hwy::SetSupportedTargetsForTest(mock);
  return cpu;
}

std::int64_t ParseSimdTargets(std::string_view value, std::int64_t available) {
  std::int64_t mask = 0;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    std::size_t end = value.find(',', begin);
    if (end == std::string_view::npos) end = value.size();
    std::string name = Lower(value.substr(begin, end - begin));
    begin = end + 1;
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) continue;
    const std::int64_t target = Lookup(name);
    if (target == 0) {
      Fail(
          "{}={}: '{}' is not a SIMD target of this build; valid (case-insensitive, "
          "comma-separated): {}",
          kSimdTargetsVariable, value, name, Describe(HWY_TARGETS, true));
    }
    if ((available & target) == 0) {
      Fail("{}={}: this CPU does not support {}; it supports: {}", kSimdTargetsVariable, value,
           name, Describe(available, false));
    }
    mask |= target;
  }
  return mask;
}

void ApplySimdTargetsFromEnvironment() {
  const char* value = std::getenv(kSimdTargetsVariable);
  const std::int64_t mask = value != nullptr ? ParseSimdTargets(value, CpuSimdTargets()) : 0;
  process_targets.store(mask);
  hwy::SetSupportedTargetsForTest(mask);  // 0 (unset or empty): Highway's own choice
}

bool ApplySimdTargetsOrPrintError(const char* prefix) {
  try {
    ApplySimdTargetsFromEnvironment();
  } catch (const Error& e) {
    std::fprintf(stderr, "%s%s\n", prefix, e.what());
    return false;
  }
  return true;
}

std::int64_t ProcessSimdTargets() { return process_targets.load(); }

std::string ActiveSimdTarget() {
  const std::vector<std::int64_t> targets = Targets(hwy::SupportedTargets() & HWY_TARGETS);
  return hwy::TargetName(targets.empty() ? HWY_STATIC_TARGET : targets.front());
}

std::string SimdTargetDescription() {
  std::string text = ActiveSimdTarget();
  const char* value = std::getenv(kSimdTargetsVariable);
  if (ProcessSimdTargets() != 0 && value != nullptr) {
    text += std::string(" (") + kSimdTargetsVariable + "=" + value + ")";
  }
  return text;
}

}  // namespace hdr4d::method
