// The shipped suites run the budgets they name: `paper` 3000 iterations per run and
// `paper-trained` the reference's 20000, with nothing that shortens a run (the first paper pass
// ran 300 because `--iterations 300` replaced the budget, not because of the suite), and
// `bench run paper-trained --dry-run` lists its 132 runs without generating a scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "benchmark/bench_test_util.h"
#include "benchmark/run_plan.h"
#include "benchmark/suite.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

// The value after `flag` in args, every time it appears.
std::vector<std::string> ValuesOf(const std::vector<std::string>& args, const std::string& flag) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == flag) out.push_back(args[i + 1]);
  return out;
}

void ExpectEveryRunTrains(const std::string& name, int iterations, std::size_t runs_expected,
                          std::size_t scenes_expected) {
  const Suite suite = LoadSuite(name);
  ASSERT_EQ(suite.budgets.size(), 1u) << name;
  EXPECT_EQ(suite.budgets[0].iterations, iterations) << name;
  EXPECT_EQ(suite.budgets[0].seconds, 0) << name;  // no wall-clock cap either
  EXPECT_EQ(suite.scenes.size(), scenes_expected) << name;
  EXPECT_EQ(suite.seeds, (std::vector<std::int64_t>{0, 1, 2})) << name;
  std::vector<PreparedScene> scenes;
  for (const SceneSpec& s : suite.scenes) scenes.push_back({&s, "/data/" + s.name, "sum" + s.name});
  const std::vector<RunSpec> runs = PlanRuns(suite, scenes, "v");
  std::size_t labels = 0;
  for (const RunSpec& r : runs) {
    labels += r.labels.size();
    EXPECT_EQ(ValuesOf(r.train_args, "--iterations"), (std::vector<std::string>{std::to_string(iterations)}))
        << name << " " << r.labels[0].method;
    EXPECT_TRUE(ValuesOf(r.train_args, "--max-seconds").empty()) << name;
    EXPECT_EQ(r.labels[0].budget, std::to_string(iterations) + "it");
  }
  EXPECT_EQ(runs.size(), runs_expected) << name;  // Table 1's DTM and Table 4's are one run
  EXPECT_GE(labels, runs.size());
  // The description says the same numbers.
  EXPECT_NE(suite.description.find(std::to_string(runs_expected) + " runs"), std::string::npos)
      << suite.description;
}

TEST(SuiteBudgets, PaperTrainsEveryRunThreeThousandIterations) {
  ExpectEveryRunTrains("paper", 3000, 528, 8);  // 22 configurations with the grid rows
}

TEST(SuiteBudgets, PaperTrainedIsTable1AndTable4AtTwentyThousandOnFourScenes) {
  ExpectEveryRunTrains("paper-trained", 20000, 132, 4);
  const Suite suite = LoadSuite("paper-trained");
  std::vector<std::string> ids;
  for (const TableSpec& t : suite.tables) ids.push_back(t.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"table1", "table4"}));
  for (const TableSpec& t : suite.tables)  // every row is a suite method or a submission slot
    for (const TableRow& r : t.rows)
      if (!suite.FindMethod(r.method))
        EXPECT_TRUE(r.method == "HexPlane" || r.method == "HDR-NeRF" || r.method == "HDR-HexPlane")
            << r.method;
}

TEST(SuiteBudgets, DryRunListsEveryRunWithoutGeneratingAScene) {
  testing::TempDir dir;
  const Command c = RunHdr4dArgs({"bench", "run", "paper-trained", "--dry-run", "--store",
                                  (dir / "s.db").string(), "--cache", (dir / "cache").string()},
                                 dir / "log.txt");
  ASSERT_TRUE(c.result.ok()) << c.text;
  EXPECT_EQ(CountLines(c.text, "-                 to run"), 132) << c.text;
  EXPECT_EQ(CountLines(c.text, "bench: scene '"), 4) << c.text;  // not generated: said, not done
  EXPECT_NE(c.text.find("hdr4dgs/lego/ldr+hdr/s0/20000it"), std::string::npos);
  EXPECT_NE(c.text.find("tm-durand/standup/ldr/s2/20000it"), std::string::npos);
  EXPECT_TRUE(!fs::exists(dir / "cache") || fs::is_empty(dir / "cache"));  // nothing generated
  // A shortened pass says that it replaces the suite's budget.
  const Command short_pass = RunHdr4dArgs({"bench", "run", "paper", "--dry-run", "--iterations",
                                           "300", "--store", (dir / "s.db").string(), "--cache",
                                           (dir / "cache").string(), "--scenes", "lego"},
                                          dir / "log.txt");
  ASSERT_TRUE(short_pass.result.ok()) << short_pass.text;
  EXPECT_NE(short_pass.text.find("--iterations 300 replaces suite 'paper''s budget (3000it)"),
            std::string::npos) << short_pass.text;
}

}  // namespace
}  // namespace hdr4d::bench
