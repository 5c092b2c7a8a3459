// The stress suite as CI runs it: every case holds (no crash, no NaN, a clear error naming the
// file for invalid input, nothing lost after a kill or a corrupt checkpoint).
#include <gtest/gtest.h>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "benchmark/stress.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

TEST(Stress, EveryCaseHolds) {
  const fs::path dir = Artifacts("stress");
  fs::remove_all(dir / "work");
  fs::remove(dir / "store.db");
  const Command c = RunHdr4dArgs({"bench", "stress", "--out", (dir / "work").string(), "--store",
                                  (dir / "store.db").string(), "--threads", "1"},
                                 dir / "stress.log");
  EXPECT_TRUE(c.result.ok()) << c.text;
  const auto outcomes = ResultsStore(dir / "store.db", false).StressOutcomes();
  EXPECT_EQ(outcomes.size(), StressCaseList().size());
  std::set<std::string> categories;
  for (const StressOutcome& o : outcomes) {
    EXPECT_EQ(o.outcome, "held") << o.name << ": " << o.detail;
    EXPECT_TRUE(o.checks.value("no crash", false)) << o.name;
    categories.insert(o.category);
  }
  EXPECT_EQ(categories, (std::set<std::string>{"extreme exposure", "extreme radiance",
                                               "near-degenerate Gaussians", "degenerate scene",
                                               "corrupt input", "killed or corrupt state"}));
}

}  // namespace
}  // namespace hdr4d::bench
