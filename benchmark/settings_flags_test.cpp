#include "benchmark/settings_flags.h"

#include <gtest/gtest.h>

#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::ErrorOf;
using V = std::vector<std::string>;

TEST(SettingsFlags, EveryValueKindBecomesFlags) {
  const nlohmann::json s = nlohmann::json::parse(R"({
    "densify-grad-threshold": 0.001, "method": "hdr4dgs", "no-pixel-branch": true,
    "direct-tone-curves": false, "exposures": [0.125, 2, 32], "context-window": 5,
    "densify-until": {"of_iterations": 0.8333}, "gone": null})");
  EXPECT_EQ(SettingsToArgs(s, 3000, "x"),
            (V{"--context-window", "5", "--densify-grad-threshold", "0.001", "--densify-until",
               "2500", "--exposures", "0.125", "2", "32", "--method", "hdr4dgs",
               "--no-pixel-branch"}));
}

TEST(SettingsFlags, FractionsNeedAnIterationBudget) {
  const nlohmann::json s = {{"densify-until", {{"of_iterations", 0.5}}}};
  EXPECT_NE(ErrorOf([&] { SettingsToArgs(s, 0, "suite.json: method 'a'"); }).find("suite.json: method 'a'"),
            std::string::npos);
}

// {"of_iterations": 1e300} passed loading, then every run got --densify-until
// -9223372036854775808.
TEST(SettingsFlags, FractionsAreFromZeroToOne) {
  for (double f : {1e300, 1.5, -0.1}) {
    const nlohmann::json settings = {{"densify-until", {{"of_iterations", f}}}};
    const std::string e = ErrorOf([&] { ValidateSettings(settings, {}, "w"); });
    EXPECT_NE(e.find("flag 'densify-until'"), std::string::npos) << f << ": " << e;
  }
  ValidateSettings({{"densify-until", {{"of_iterations", 1}}}}, {}, "w");
  ValidateSettings({{"densify-until", {{"of_iterations", 0}}}}, {}, "w");
}

TEST(SettingsFlags, ValidationNamesTheKey) {
  EXPECT_NE(ErrorOf([] { ValidateSettings({{"Bad Flag", 1}}, {}, "w"); }).find("'Bad Flag'"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ValidateSettings({{"seed", 1}}, {"seed"}, "w"); }).find("set by the harness"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ValidateSettings({{"x", {{"a", 1}}}}, {}, "w"); }).find("flag 'x'"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ValidateSettings({{"x", nlohmann::json::array()}}, {}, "w"); }).find("flag 'x'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ValidateSettings(nlohmann::json::array(), {}, "w"); }).find("JSON object"),
            std::string::npos);
  EXPECT_EQ(ErrorOf([] { ValidateSettings({{"ok-flag", 1.5}, {"b", "s"}, {"c", true}}, {}, "w"); }), "");
}

TEST(SettingsFlags, MergeOverridesAndRemoves) {
  const nlohmann::json base = {{"a", 1}, {"b", 2}};
  EXPECT_EQ(MergeSettings(base, {{"b", 3}, {"c", 4}}), (nlohmann::json{{"a", 1}, {"b", 3}, {"c", 4}}));
  EXPECT_EQ(MergeSettings(base, {{"a", nullptr}}), (nlohmann::json{{"b", 2}}));
}

TEST(SettingsFlags, NumbersReadBackExactly) {
  EXPECT_EQ(FormatNumber(3000), "3000");
  EXPECT_EQ(FormatNumber(0.1), "0.1");
  EXPECT_EQ(std::stod(FormatNumber(1.0 / 3.0)), 1.0 / 3.0);
}

}  // namespace
}  // namespace hdr4d::bench
