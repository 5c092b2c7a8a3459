// `bench submit`'s checks that come before any scoring: the method's name and the meta file.
#include "benchmark/submit.h"

#include <gtest/gtest.h>

#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::ErrorOf;
using testing::TempDir;

// A submission named like a suite method replaced that method's trained row in the tables.
TEST(Submit, RefusesTheNameOfASuiteMethodOrAnOption) {
  TempDir dir;
  SubmitOptions o{.store = dir / "s.db", .method = "hdr4dgs", .scene = "x", .suite = "ci",
                  .renders = dir / "renders"};
  const std::string e = ErrorOf([&] { Submit(o); });
  EXPECT_NE(e.find("--method hdr4dgs: a method of suite 'ci'"), std::string::npos) << e;
  o.method = "--help";  // `--method=--help`
  EXPECT_NE(ErrorOf([&] { Submit(o); }).find("may not start with '-'"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
}

// {"gaussians": 1e30} was stored as -9223372036854775808, 2.5 as 2; {"machine": 5} was stored,
// then `bench collect` refused the exported record.
TEST(Submit, MetaNumbersAndMachineAreCheckedAsCollectChecksThem) {
  TempDir dir;
  const std::filesystem::path meta = dir / "meta.json";
  const std::vector<std::pair<nlohmann::json, std::string>> bad = {
      {{{"gaussians", 1e30}}, "key 'gaussians' must be an integer"},
      {{{"gaussians", 2.5}}, "key 'gaussians' must be an integer"},
      {{{"iterations", 1e19}}, "key 'iterations' must be an integer"},
      {{{"iterations", -3}}, "key 'iterations' must be at least 0"},
      {{{"machine", 5}}, "key 'machine' must be a JSON object or text"},
      {{{"machine", {1, 2}}}, "key 'machine' must be a JSON object or text"}};
  for (const auto& [json, message] : bad) {
    WriteJsonFile(meta, json);
    const std::string e = ErrorOf([&] { ReadSubmissionMeta(meta); });
    EXPECT_NE(e.find(meta.string() + ": " + message), std::string::npos) << json.dump() << e;
  }
  WriteJsonFile(meta, {{"gaussians", 1e3}, {"iterations", 30000}, {"machine", "an A100"}});
  const nlohmann::json m = ReadSubmissionMeta(meta);
  EXPECT_EQ(m["gaussians"], 1000);
  EXPECT_EQ(m["machine"], (nlohmann::json{{"description", "an A100"}}));
}

}  // namespace
}  // namespace hdr4d::bench
