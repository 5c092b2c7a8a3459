#include "baselines/tone_mapper_factory.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace hdr4d::baselines {
namespace {

using hdr4d::testing::ErrorOf;

TEST(ToneMapperFactory, BuildsEveryKind) {
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

TEST(ToneMapperFactory, UnknownKindListsTheValidOnes) {
  method::ToneMapperConfig config;
  config.kind = "drago";
  EXPECT_EQ(ErrorOf([&] { MakeToneMapper(config); }),
            "unknown tone mapper kind 'drago' (valid kinds: dtm, mlp, sigmoid, reinhard, durand)");
}

TEST(ToneMapperFactory, InvalidConfigurationNamesTheField) {
  method::ToneMapperConfig config;
  config.kind = "sigmoid";
  config.num_images = -1;
  const std::string message = ErrorOf([&] { MakeToneMapper(config); });
  EXPECT_NE(message.find("invalid tone mapper configuration"), std::string::npos) << message;
  EXPECT_NE(message.find("num_images"), std::string::npos) << message;
}

}  // namespace
}  // namespace hdr4d::baselines
