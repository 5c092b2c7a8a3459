#include "core/files/json_util.h"

#include <gtest/gtest.h>

#include <string>

#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
using nlohmann::json;
using testing::ErrorOf;

std::string Nested(int depth, const std::string& inner = "") {
  return std::string(depth, '[') + inner + std::string(depth, ']');
}

// Issue 11, case 5: 60000 nested brackets segfaulted `dataset check`, `train` and `synth-ldr`
// (the recursive dump of the error preview, and nlohmann's recursive copy and compare).
TEST(JsonUtil, NestingIsBoundedBeforeTheDocumentIsBuilt) {
  const std::string error = ErrorOf([] { ParseJson(Nested(100000), "deep.json"); });
  EXPECT_NE(error.find("deep.json: invalid JSON: nested deeper than 256 levels at line 1, column "
                       "257"),
            std::string::npos)
      << error;
  const std::string in_a_key = "{\"frames\": [{\"time\": " + Nested(60000, "1") + "}]}";
  EXPECT_THROW(ParseJson(in_a_key, "t.json"), Error);
  EXPECT_NO_THROW(ParseJson(Nested(kMaxJsonDepth, "1"), "ok.json"));
  // Brackets inside strings are text, not nesting.
  const json doc = ParseJson("{\"a\": \"" + Nested(1000) + "\\\"[\"}", "s.json");
  EXPECT_EQ(doc["a"].get<std::string>().size(), 2002u);
}

TEST(JsonUtil, SyntaxErrorsNameTheSource) {
  EXPECT_NE(ErrorOf([] { ParseJson("{\"a\": }", "x.json"); }).find("x.json: invalid JSON"),
            std::string::npos);
}

TEST(JsonUtil, PreviewIsShortWhateverTheValue) {
  EXPECT_EQ(JsonPreview(json("x")), "string \"x\"");
  EXPECT_EQ(JsonPreview(json::parse("[1, 2]")), "array [1,2]");
  json big = json::array();
  for (int i = 0; i < 100000; ++i) big.push_back(i);
  EXPECT_LE(JsonPreview(big).size(), 50u);
  json deep = json::array();
  for (int i = 0; i < 200; ++i) deep = json::array({deep});
  const std::string preview = JsonPreview(deep, 20);
  EXPECT_EQ(preview, "array [[[[[[[[[[[[[[[[[...");
}

// Issue 11, case 16: nlohmann's "[json.exception.type_error.302] type must be number, but is
// string" named neither the file nor the key.
TEST(JsonUtil, FieldErrorsNameTheFileAndTheKey) {
  const json doc = json::parse(R"({"background": "x", "resolved": {"hdr": 3}, "n": 2.5,
                                   "seed": -1, "big": 18446744073709551615})");
  const JsonField f(doc, "run/config.json");
  EXPECT_EQ(ErrorOf([&] { f["background"].Number(); }),
            "run/config.json: key 'background': expected a number, got string \"x\"");
  EXPECT_EQ(ErrorOf([&] { f["resolved"]["hdr"].Bool(); }),
            "run/config.json: key 'resolved.hdr': expected true or false, got number 3");
  EXPECT_EQ(ErrorOf([&] { f["resolved"]["ldr"]; }),
            "run/config.json: key 'resolved.ldr' is missing");
  EXPECT_NE(ErrorOf([&] { f["n"].Int(0, 10); }).find("key 'n': expected an integer in [0, 10]"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { f["seed"].Uint64(); }).find("key 'seed'"), std::string::npos);
  EXPECT_EQ(f["big"].Uint64(), 18446744073709551615ull);
  EXPECT_NE(ErrorOf([&] { f["big"].Int(0, 100); }).find("key 'big'"), std::string::npos);
  EXPECT_EQ(f.NumberOr("absent", 0.5), 0.5);
  EXPECT_THROW(f.NumberOr("background", 0.5), Error);
}

}  // namespace
}  // namespace hdr4d
