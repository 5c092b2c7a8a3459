// Checkpoint state of every baseline tone mapper: round trips, and every way a file can be wrong.
#include "baselines/param_tone_mapper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>

#include "baselines/test_util.h"
#include "baselines/tone_mapper_kinds.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "tests/testing.h"

namespace hdr4d::baselines {
namespace {

using hdr4d::testing::ErrorOf;

std::unique_ptr<method::ToneMapper> Make(const std::string& kind, int num_images = 3) {
  method::ToneMapperConfig config;
  config.kind = kind;
  config.num_images = num_images;
  config.seed = 5;
  RegisterToneMappers();
  return method::MakeToneMapper(config);
}

std::string Saved(const method::ToneMapper& mapper) {
  std::ostringstream out;
  mapper.Save(out);
  return out.str();
}

std::string LoadError(method::ToneMapper& mapper, const std::string& bytes) {
  const std::vector<float> before = mapper.params();
  const float* data = mapper.params().data();
  const std::string message = ErrorOf([&] {
    std::istringstream in(bytes);
    mapper.Load(in, "run/tone.bin");
  });
  EXPECT_EQ(mapper.params(), before) << "a failed load changed the mapper";
  EXPECT_EQ(mapper.params().data(), data);
  return message;
}

// Output of the mapper on a small image (MapImage works for every kind).
std::vector<float> Render(method::ToneMapper& mapper) {
  const std::vector<float> log_hdr = testing::Uniform<float>(3 * 12, -3, 3, 4);
  std::vector<float> ldr(log_hdr.size());
  mapper.BeginFrame({0, 1, 0.2f});
  mapper.MapImage(log_hdr.data(), 4, 3, ldr.data());
  return ldr;
}

class ParamToneMapperTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ParamToneMapperTest, SaveLoadRoundTripRestoresTheParametersInPlace) {
  auto a = Make(GetParam());
  for (std::size_t i = 0; i < a->params().size(); ++i) a->params()[i] += 0.01f * float(i % 7 + 1);
  const std::string bytes = Saved(*a);
  auto b = Make(GetParam());
  ASSERT_NE(a->params(), b->params());
  const float* data = b->params().data();
  std::istringstream in(bytes);
  b->Load(in, "mem");
  EXPECT_EQ(b->params(), a->params());
  EXPECT_EQ(b->params().data(), data);  // an optimiser bound to the array stays bound
  EXPECT_EQ(Render(*a), Render(*b));
  EXPECT_EQ(Saved(*b), bytes);
}

TEST_P(ParamToneMapperTest, LoadRejectsCorruptDataNamingTheSource) {
  auto mapper = Make(GetParam());
  const std::string good = Saved(*Make(GetParam()));
  auto expect = [&](const std::string& bytes, const std::string& problem) {
    const std::string message = LoadError(*mapper, bytes);
    EXPECT_NE(message.find("run/tone.bin: "), std::string::npos) << message;
    EXPECT_NE(message.find(problem), std::string::npos) << message;
  };
  expect("", "truncated");
  std::string bad = good;
  bad[0] = 'X';
  expect(bad, "bad magic");
  bad = good;
  bad[8] = 2;
  expect(bad, "version 2 is not supported");
  for (std::size_t size : {std::size_t(9), std::size_t(14), good.size() / 2, good.size() - 1}) {
    expect(good.substr(0, size), "truncated");
  }
  bad = good;
  bad[good.size() - 12] ^= 0x10;  // inside the last parameter
  expect(bad, "checksum mismatch");
  bad = good;
  bad[12] = 0;  // kind length 0
  expect(bad, "kind of length 0");
}

TEST_P(ParamToneMapperTest, LoadRejectsAnotherKindOrSizeAndNonFiniteValues) {
  auto mapper = Make(GetParam());
  const std::string other = GetParam() == "reinhard" ? "durand" : "reinhard";
  EXPECT_NE(LoadError(*mapper, Saved(*Make(other)))
                .find("is for kind '" + other + "', not '" + GetParam() + "'"),
            std::string::npos);
  auto nan = Make(GetParam());
  nan->params().back() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(LoadError(*mapper, Saved(*nan)).find("non-finite parameter at index"),
            std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Baselines,
                         ParamToneMapperTest,
                         ::testing::Values("mlp", "sigmoid", "reinhard", "durand"));

TEST(ParamToneMapper, LoadRejectsAStateOfADifferentConfiguration) {
  auto three = Make("sigmoid", 3);
  auto four = Make("sigmoid", 4);
  EXPECT_NE(LoadError(*four, Saved(*three))
                .find("has 3 parameters, this 'sigmoid' tone mapper has 4 (its configuration "
                      "differs)"),
            std::string::npos);
  // A foreign kind claiming a huge count is rejected before any allocation.
  std::string bytes = Saved(*Make("reinhard"));
  const std::uint64_t huge = std::uint64_t{1} << 40;
  std::memcpy(&bytes[8 + 4 + 4 + 8], &huge, sizeof(huge));
  EXPECT_NE(LoadError(*four, bytes).find("claims 1099511627776 parameters (corrupt)"),
            std::string::npos);
}

TEST(ParamToneMapperDeathTest, BeginFrameChecksTheFrame) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto mapper = Make("sigmoid", 2);
  EXPECT_DEATH(mapper->BeginFrame({0, 2, 0.f}), "internal check failed");
  EXPECT_DEATH(mapper->BeginFrame({0, -2, 0.f}), "internal check failed");
  EXPECT_DEATH(mapper->BeginFrame({0, 0, std::numeric_limits<float>::quiet_NaN()}),
               "internal check failed");
  // Mappers without per-image parameters accept any training image index.
  auto reinhard = Make("reinhard", 0);
  reinhard->BeginFrame({0, 7, 0.f});
}

}  // namespace
}  // namespace hdr4d::baselines
