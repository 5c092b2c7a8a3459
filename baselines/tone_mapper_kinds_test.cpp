#include "baselines/tone_mapper_kinds.h"

#include <gtest/gtest.h>

#include "method/tonemap/tone_mapper_registry.h"
#include "tests/testing.h"

namespace hdr4d::baselines {
namespace {

using hdr4d::testing::ErrorOf;
using method::MakeToneMapper;
using method::ToneMapperKinds;

class ToneMapperKindsTest : public ::testing::Test {
 protected:
  void SetUp() override { RegisterToneMappers(); }
};

TEST_F(ToneMapperKindsTest, BuildsEveryKind) {
  EXPECT_EQ(ToneMapperKinds(),
            (std::vector<std::string>{"dtm", "mlp", "sigmoid", "reinhard", "durand"}));
  for (const std::string& kind : ToneMapperKinds()) {
    method::ToneMapperConfig config;
    config.kind = kind;
    config.num_images = 4;
    config.num_times = 3;
    const auto mapper = MakeToneMapper(config);
    ASSERT_NE(mapper, nullptr) << kind;
    EXPECT_EQ(mapper->config().kind, kind);
    EXPECT_EQ(mapper->pointwise(), kind != "durand") << kind;
    EXPECT_EQ(mapper->params().size(), mapper->grads().size()) << kind;
    EXPECT_GT(mapper->learning_rate(), 0.f) << kind;
  }
}

TEST_F(ToneMapperKindsTest, UnknownKindListsTheValidOnes) {
  method::ToneMapperConfig config;
  config.kind = "drago";
  EXPECT_EQ(
      ErrorOf([&] { MakeToneMapper(config); }),
      "unknown tone mapper kind 'drago' (valid kinds: dtm, mlp, sigmoid, reinhard, durand; the "
      "baselines' kinds mlp, sigmoid, reinhard and durand are added by "
      "baselines::RegisterToneMappers)");
}

TEST_F(ToneMapperKindsTest, InvalidConfigurationNamesTheField) {
  method::ToneMapperConfig config;
  config.kind = "sigmoid";
  config.num_images = -1;
  const std::string message = ErrorOf([&] { MakeToneMapper(config); });
  EXPECT_NE(message.find("invalid tone mapper configuration"), std::string::npos) << message;
  EXPECT_NE(message.find("num_images"), std::string::npos) << message;
}

TEST_F(ToneMapperKindsTest, RegisteringTwiceChangesNothing) {
  RegisterToneMappers();
  EXPECT_EQ(ToneMapperKinds(),
            (std::vector<std::string>{"dtm", "mlp", "sigmoid", "reinhard", "durand"}));
}

}  // namespace
}  // namespace hdr4d::baselines
