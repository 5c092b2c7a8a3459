#include "method/tonemap/tone_mapper.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using testing::ErrorOf;

std::string FromJsonError(const nlohmann::json& json) {
  return ErrorOf([&] { ToneMapperConfig::FromJson(json, "run/config.json"); });
}

TEST(ToneMapperConfig, DefaultsAreValidAndTheReferenceSettings) {
  const ToneMapperConfig c;
  EXPECT_EQ(c.Validate(), "");
  EXPECT_EQ(c.kind, "dtm");
  EXPECT_EQ(c.context_learner, "gru");
  EXPECT_EQ(c.context_window, 20);
  EXPECT_EQ(c.context_size, 2);
  EXPECT_EQ(c.curve_hidden, 64);
}

TEST(ToneMapperConfig, ValidateNamesTheBadField) {
  struct Case {
    void (*mutate)(ToneMapperConfig&);
    const char* field;
  };
  const Case cases[] = {
      {[](ToneMapperConfig& c) { c.kind = "magic"; }, "kind"},
      {[](ToneMapperConfig& c) { c.context_learner = "mamba"; }, "context_learner"},
      {[](ToneMapperConfig& c) { c.num_times = 0; }, "num_times"},
      {[](ToneMapperConfig& c) { c.num_images = -1; }, "num_images"},
      {[](ToneMapperConfig& c) { c.context_window = 0; }, "context_window"},
      {[](ToneMapperConfig& c) { c.context_window = 100000; }, "context_window"},
      {[](ToneMapperConfig& c) { c.context_size = 0; }, "context_size"},
      {[](ToneMapperConfig& c) { c.curve_hidden = 0; }, "curve_hidden"},
      {[](ToneMapperConfig& c) { c.curve_hidden = 5000; }, "curve_hidden"},
      {[](ToneMapperConfig& c) { c.table_nodes = 1; }, "table_nodes"},
      {[](ToneMapperConfig& c) { c.unseen_rows = "guess"; }, "unseen_rows"},
  };
  for (const Case& k : cases) {
    ToneMapperConfig c;
    k.mutate(c);
    const std::string problem = c.Validate();
    EXPECT_NE(problem.find(k.field), std::string::npos) << k.field << ": " << problem;
  }
  for (const char* kind : {"dtm", "mlp", "sigmoid", "reinhard", "durand"}) {
    ToneMapperConfig c;
    c.kind = kind;
    EXPECT_EQ(c.Validate(), "") << kind;
  }
  for (const char* learner : {"gru", "rnn", "lstm", "transformer"}) {
    ToneMapperConfig c;
    c.context_learner = learner;
    EXPECT_EQ(c.Validate(), "") << learner;
  }
}

TEST(ToneMapperConfig, JsonRoundTripKeepsEveryKey) {
  ToneMapperConfig c;
  c.kind = "mlp";
  c.num_times = 17;
  c.num_images = 240;
  c.context_learner = "lstm";
  c.context_window = 7;
  c.context_size = 3;
  c.curve_hidden = 32;
  c.tabulated = false;
  c.table_nodes = 333;
  c.seed = std::numeric_limits<std::uint64_t>::max();
  c.monotone_curves = true;
  c.unseen_rows = "zero";
  const nlohmann::json json = c.ToJson();
  EXPECT_EQ(json.size(), 13u);  // monotone_form only with monotone curves
  // Through text, as config.json is read back.
  const ToneMapperConfig r = ToneMapperConfig::FromJson(nlohmann::json::parse(json.dump()), "x");
  EXPECT_EQ(r.kind, c.kind);
  EXPECT_EQ(r.num_times, c.num_times);
  EXPECT_EQ(r.num_images, c.num_images);
  EXPECT_EQ(r.context_learner, c.context_learner);
  EXPECT_EQ(r.context_window, c.context_window);
  EXPECT_EQ(r.context_size, c.context_size);
  EXPECT_EQ(r.curve_hidden, c.curve_hidden);
  EXPECT_EQ(r.tabulated, c.tabulated);
  EXPECT_EQ(r.table_nodes, c.table_nodes);
  EXPECT_EQ(r.seed, c.seed);
  EXPECT_EQ(r.monotone_curves, c.monotone_curves);
  EXPECT_EQ(r.unseen_rows, c.unseen_rows);
  EXPECT_EQ(r.ToJson(), json);
  // Unwritten bank rows interpolate by default; a config.json without the key read them as zeros.
  EXPECT_EQ(ToneMapperConfig().unseen_rows, "interpolate");
  nlohmann::json before = ToneMapperConfig().ToJson();
  before.erase("unseen_rows");
  EXPECT_EQ(ToneMapperConfig::FromJson(before, "x").unseen_rows, "zero");
  // Free curves (the reference's) are the default, and what a config.json without the key had.
  EXPECT_FALSE(ToneMapperConfig().monotone_curves);
  nlohmann::json old = c.ToJson();
  old.erase("monotone_curves");
  EXPECT_FALSE(ToneMapperConfig::FromJson(old, "x").monotone_curves);
  // A run with the earlier all-positive monotone curves (no form) cannot load as the new ones.
  nlohmann::json convex = c.ToJson();
  convex.erase("monotone_form");
  const std::string e = FromJsonError(convex);
  EXPECT_NE(e.find("monotone_form"), std::string::npos) << e;
  EXPECT_NE(e.find("retrain"), std::string::npos) << e;
}

TEST(ToneMapperConfig, FromJsonNamesSourceAndKey) {
  const nlohmann::json good = ToneMapperConfig().ToJson();
  for (const auto& item : good.items()) {
    if (item.key() == "monotone_curves" || item.key() == "unseen_rows") continue;  // optional
    nlohmann::json j = good;
    j.erase(item.key());
    const std::string e = FromJsonError(j);
    EXPECT_NE(e.find("run/config.json"), std::string::npos) << e;
    EXPECT_NE(e.find("missing key '" + item.key() + "'"), std::string::npos) << e;
  }
  struct Bad {
    const char* key;
    nlohmann::json value;
  };
  const Bad bads[] = {
      {"kind", 3},
      {"kind", "fancy"},
      {"num_times", "many"},
      {"num_times", 1.5},
      {"num_times", 0},
      {"num_times", 1e12},
      {"num_images", -3},
      {"context_learner", true},
      {"context_learner", "mamba"},
      {"context_window", nullptr},
      {"context_window", std::int64_t{1} << 40},
      {"context_size", -1},
      {"curve_hidden", "64"},
      {"tabulated", 1},
      {"monotone_curves", "yes"},
      {"unseen_rows", "guess"},
      {"unseen_rows", 0},
      {"table_nodes", 1},
      {"seed", -1},
      {"seed", 0.5},
      {"seed", "7"},
  };
  for (const Bad& b : bads) {
    nlohmann::json j = good;
    j[b.key] = b.value;
    const std::string e = FromJsonError(j);
    EXPECT_NE(e.find("run/config.json"), std::string::npos) << b.key << ": " << e;
    EXPECT_NE(e.find(b.key), std::string::npos) << b.key << ": " << e;
  }
}

TEST(ToneMapperConfig, FromJsonRejectsUnknownKeysAndNonObjects) {
  nlohmann::json j = ToneMapperConfig().ToJson();
  j["context_windw"] = 3;
  EXPECT_NE(FromJsonError(j).find("unknown key 'context_windw'"), std::string::npos);
  EXPECT_NE(FromJsonError(nlohmann::json::array()).find("JSON object"), std::string::npos);
  EXPECT_EQ(FromJsonError(ToneMapperConfig().ToJson()), "");
}

}  // namespace
}  // namespace hdr4d::method
