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

}  // namespace
}  // namespace hdr4d::bench
