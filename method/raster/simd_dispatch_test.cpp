#include "method/raster/simd_dispatch.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cstdlib>
#include <string>

#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using hdr4d::testing::ErrorOf;

// Every target this build compiles, as if the CPU had them all: parsing alone.
constexpr std::int64_t kAll = HWY_TARGETS;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// "SCALAR (HDR4D_SIMD_TARGETS=Scalar)"
std::string Described(std::int64_t target, const std::string& value) {
  std::string text = hwy::TargetName(target);
  text += " (HDR4D_SIMD_TARGETS=";
  text += value;
  text += ")";
  return text;
}

TEST(SimdDispatch, NamesAreCaseInsensitiveAndListsCombine) {
  EXPECT_EQ(ParseSimdTargets("avx2", kAll), HWY_AVX2);
  EXPECT_EQ(ParseSimdTargets("AVX2", kAll), HWY_AVX2);
  EXPECT_EQ(ParseSimdTargets("avx3", kAll), HWY_AVX3);
  EXPECT_EQ(ParseSimdTargets("Avx512", kAll), HWY_AVX3);
  EXPECT_EQ(ParseSimdTargets(" avx2 , AVX3 ", kAll), HWY_AVX2 | HWY_AVX3);
  EXPECT_EQ(ParseSimdTargets("avx2,", kAll), HWY_AVX2);
}

TEST(SimdDispatch, ScalarEmu128AndBaselineNameTheBaseline) {
  for (const char* name : {"scalar", "SCALAR", "emu128", "baseline"}) {
    EXPECT_EQ(ParseSimdTargets(name, kAll), HWY_STATIC_TARGET) << name;
  }
}

TEST(SimdDispatch, AnEmptyValueRestrictsNothing) {
  EXPECT_EQ(ParseSimdTargets("", kAll), 0);
  EXPECT_EQ(ParseSimdTargets(" , ", kAll), 0);
}

TEST(SimdDispatch, UnknownNamesFailNamingTheVariableAndTheValidOnes) {
  for (const char* value : {"sse9", "avx2,neon", "sse4"}) {  // sse4: not compiled into hdr4d
    const std::string e = ErrorOf([&] { ParseSimdTargets(value, kAll); });
    EXPECT_TRUE(Contains(e, std::string("HDR4D_SIMD_TARGETS=") + value)) << e;
    EXPECT_TRUE(Contains(e, "avx3 (or avx512), avx2, scalar (or emu128, baseline)")) << e;
  }
}

TEST(SimdDispatch, ATargetTheCpuLacksFailsListingWhatItHas) {
  const std::int64_t avx2_host = HWY_AVX2 | HWY_STATIC_TARGET;
  const std::string e = ErrorOf([&] { ParseSimdTargets("avx2,avx3", avx2_host); });
  EXPECT_TRUE(Contains(e, "HDR4D_SIMD_TARGETS=avx2,avx3")) << e;
  EXPECT_TRUE(Contains(e, "does not support avx3; it supports: avx2, scalar")) << e;
  EXPECT_EQ(ParseSimdTargets("avx2", avx2_host), HWY_AVX2);
}

// The test binaries' main applies the variable: when scripts/test.sh sets it, the process is
// limited to what it names, and the target in use is the best of those.
TEST(SimdDispatch, TheTestMainAppliesTheVariable) {
  const char* value = std::getenv(kSimdTargetsVariable);
  const std::int64_t want = value != nullptr ? ParseSimdTargets(value, CpuSimdTargets()) : 0;
  EXPECT_EQ(ProcessSimdTargets(), want);
  const std::int64_t in_force = want != 0 ? want : CpuSimdTargets();
  EXPECT_EQ(ActiveSimdTarget(), hwy::TargetName(in_force & -in_force));
  EXPECT_EQ(hwy::SupportedTargets() & HWY_TARGETS, in_force);
}

TEST(SimdDispatch, ApplyingLimitsDispatchAndSaysSo) {
  const char* saved = std::getenv(kSimdTargetsVariable);
  const std::string restore = saved != nullptr ? saved : "";
  const std::int64_t cpu = CpuSimdTargets();
  ASSERT_EQ(setenv(kSimdTargetsVariable, "Scalar", 1), 0);
  ApplySimdTargetsFromEnvironment();
  EXPECT_EQ(ProcessSimdTargets(), HWY_STATIC_TARGET);
  EXPECT_EQ(ActiveSimdTarget(), hwy::TargetName(HWY_STATIC_TARGET));
  EXPECT_EQ(SimdTargetDescription(), Described(HWY_STATIC_TARGET, "Scalar"));
  EXPECT_EQ(CpuSimdTargets(), cpu);  // the CPU's own targets are still known while restricted
  ASSERT_EQ(setenv(kSimdTargetsVariable, "nonsense", 1), 0);
  EXPECT_TRUE(
      Contains(ErrorOf([] { ApplySimdTargetsFromEnvironment(); }), "HDR4D_SIMD_TARGETS=nonsense"));
  EXPECT_EQ(ActiveSimdTarget(), hwy::TargetName(HWY_STATIC_TARGET));  // unchanged by the error
  ::testing::internal::CaptureStderr();
  EXPECT_FALSE(ApplySimdTargetsOrPrintError("tool: error: "));
  EXPECT_EQ(::testing::internal::GetCapturedStderr().rfind(
                "tool: error: HDR4D_SIMD_TARGETS=nonsense: 'nonsense' is not", 0),
            0u);
  // Unset: no restriction.
  ASSERT_EQ(unsetenv(kSimdTargetsVariable), 0);
  ApplySimdTargetsFromEnvironment();
  EXPECT_EQ(ProcessSimdTargets(), 0);
  EXPECT_EQ(hwy::SupportedTargets() & HWY_TARGETS, cpu);
  EXPECT_EQ(SimdTargetDescription(), ActiveSimdTarget());
  // Back to the process's own setting for the tests after this one.
  if (saved != nullptr) {
    ASSERT_EQ(setenv(kSimdTargetsVariable, restore.c_str(), 1), 0);
    ApplySimdTargetsFromEnvironment();
  }
}

}  // namespace
}  // namespace hdr4d::method
