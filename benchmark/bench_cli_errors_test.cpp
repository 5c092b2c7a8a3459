// Mistakes with `hdr4d bench` end in one line "hdr4d: error: ..." naming the file or option,
// exit code 1, and create nothing.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

TEST(BenchCliErrors, UserMistakesEndInOneLineAndCreateNothing) {
  testing::TempDir dir;
  testing::WriteTextFile(dir / "broken.json", "{\"name\": \"x\", ");
  WriteJsonFile(dir / "unknown_key.json", {{"name", "x"}, {"scenes", nlohmann::json::array()}, {"colour", 1}});
  WriteTinySuite(dir / "tiny.json", "tiny", {{{"name", "m"}}}, {0}, 10);
  testing::WriteTextFile(dir / "not_a_db.db", "plain text, not SQLite, and long enough to be read\n");
  const std::string store = (dir / "store.db").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"bench", "table", "ci", "--store", store}, "no such results store"},
      {{"bench", "run", (dir / "broken.json").string(), "--store", store}, "broken.json"},
      {{"bench", "run", (dir / "unknown_key.json").string(), "--store", store}, "unknown key 'colour'"},
      {{"bench", "run", "no-such-suite", "--store", store}, "no suite 'no-such-suite'"},
      {{"bench", "run", (dir / "tiny.json").string(), "--store", store, "--jobs", "0"}, "--jobs"},
      {{"bench", "run", (dir / "tiny.json").string(), "--store", store, "--scenes", "nope"}, "no scene 'nope'"},
      {{"bench", "run", (dir / "tiny.json").string(), "--store", store, "--seeds", "7",
        "--dry-run"},
       "--seeds 7: not a seed of suite 'tiny' (its seeds: 0)"},
      {{"bench", "run", (dir / "tiny.json").string(), "--store", (dir / "not_a_db.db").string(), "--dry-run"}, "not_a_db.db"},
      {{"bench", "report", "ci", "--store", (dir / "not_a_db.db").string(), "--out", (dir / "r.html").string()}, "not_a_db.db"},
      {{"bench", "collect", dir.path().string(), "--store", store}, "not a bench slurm folder"},
      {{"bench", "task", dir.path().string(), "--array", "0", "--index", "0"}, "plan.json"},
      {{"bench", "submit", "--store", store, "--method", "m", "--scene", (dir / "nowhere").string(),
        "--renders", dir.path().string()}, "nowhere"},
      {{"bench", "stress", "--out", (dir / "s").string(), "--case", "no-such-case"}, "no case 'no-such-case'"},
      {{"bench", "submit", "--store", store, "--method", "../m", "--scene", dir.path().string(),
        "--renders", dir.path().string()}, "--method: '../m' has a '/'"},
      {{"bench", "table", "ci", "--store", (dir / "not_a_db.db").string(), "--protocol", "max"}, "--protocol: expected one of own_max, gt_max, pu21, got 'max'"},
  };
  for (const auto& [args, names] : cases) {
    const Command c = RunHdr4dArgs(args, dir / "log.txt");
    const std::string what = args[1] + " " + args[2];
    EXPECT_EQ(c.result.exit_code, 1) << what << "\n" << c.text;
    EXPECT_EQ(CountLines(c.text, "hdr4d: error: "), 1) << what << "\n" << c.text;
    EXPECT_NE(c.result.error_line.find(names), std::string::npos) << what << ": " << c.result.error_line;
    EXPECT_EQ(c.text.find("terminate"), std::string::npos) << c.text;
  }
  EXPECT_FALSE(fs::exists(dir / "store.db"));
  EXPECT_FALSE(fs::exists(dir / "r.html"));
}

// A metric key the store's runs do not have: `bench report --metric` charted nothing and
// `bench findings --metrics` said 'no runs', both with exit code 0.
TEST(BenchCliErrors, UnknownMetricKeysAreNamedWithTheKnownOnes) {
  testing::TempDir dir;
  WriteTinySuite(dir / "tiny.json", "tiny", {{{"name", "m"}}}, {0}, 10);
  {
    ResultsStore store(dir / "runs.db");
    RunRecord r;
    r.id = "run0";
    r.labels = {{"tiny", "m", "tiny", "ldr", 0, "10it", ""}};
    r.frames.push_back({"f0", 0, 0, 1, {{"psnr", 20}, {"mu_psnr", 15}}, {}});
    store.InsertRun(r);
  }
  const std::string suite = (dir / "tiny.json").string(), store = (dir / "runs.db").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"bench", "report", suite, "--store", store, "--out", (dir / "r.html").string(),
        "--metric", "nosuch"}, "--metric nosuch: unknown metric key; the runs of suite 'tiny' "
                               "have: mu_psnr, psnr"},
      {{"bench", "findings", suite, "--store", store, "--metrics", "psnr,nosuch"},
       "--metrics nosuch: unknown metric key"},
      {{"bench", "compare", store, store, "--metrics", "nosuch"},
       "--metrics nosuch: unknown metric key"},
  };
  for (const auto& [args, names] : cases) {
    const Command c = RunHdr4dArgs(args, dir / "log.txt");
    EXPECT_EQ(c.result.exit_code, 1) << args[1] << "\n" << c.text;
    EXPECT_NE(c.result.error_line.find(names), std::string::npos) << c.result.error_line;
  }
  EXPECT_FALSE(fs::exists(dir / "r.html"));
}

// `bench table` on another program's SQLite file set its journal to WAL before refusing it.
TEST(BenchCliErrors, AReadingCommandLeavesAForeignDatabaseAsItWas) {
  testing::TempDir dir;
  const fs::path p = dir / "photos.db";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(p.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE photos (id INTEGER)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const std::string before = testing::ReadTextFile(p);
  const Command c = RunHdr4dArgs({"bench", "table", "ci", "--store", p.string()}, dir / "log.txt");
  EXPECT_EQ(c.result.exit_code, 1) << c.text;
  EXPECT_NE(c.result.error_line.find("not an hdr4d results store"), std::string::npos) << c.text;
  EXPECT_EQ(testing::ReadTextFile(p), before);
  EXPECT_FALSE(fs::exists(dir / "photos.db-wal"));
}

// A dry run lists the plan without rendering: a Blender-made scene that is not in the cache is
// named as such, its runs listed with '-' for an id, and nothing is generated or stored.
TEST(BenchDryRun, ListsThePlanWithoutGeneratingScenes) {
  testing::TempDir dir;
  WriteJsonFile(dir / "suite.json",
                {{"name", "dry"},
                 {"scenes", {{{"name", "lego"}, {"datagen", {{"scene", "lego"}, {"preset", "ci"}, {"seed", 0}}}}}},
                 {"methods", {{{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}},
                 {"seeds", {0, 1}},
                 {"budgets", {{{"iterations", 10}}}}});
  const Command c = RunHdr4dArgs({"bench", "run", (dir / "suite.json").string(), "--store",
                                  (dir / "store.db").string(), "--cache", (dir / "cache").string(),
                                  "--dry-run"},
                                 dir / "log.txt", 60);
  EXPECT_EQ(c.result.exit_code, 0) << c.text;
  EXPECT_NE(c.text.find("scene 'lego' is not generated yet"), std::string::npos) << c.text;
  EXPECT_EQ(CountLines(c.text, "-"), 2) << c.text;  // one run per seed, no id yet
  EXPECT_EQ(c.text.find("generating scene"), std::string::npos) << c.text;
  // Nor is a store created (issue 51, case 18).
  EXPECT_FALSE(fs::exists(dir / "store.db"));
  bool generated = false;
  std::error_code ec;
  for (const auto& entry : fs::recursive_directory_iterator(dir / "cache", ec))
    generated |= entry.path().filename() == "transforms_train.json";
  EXPECT_FALSE(generated);
}

}  // namespace
}  // namespace hdr4d::bench
