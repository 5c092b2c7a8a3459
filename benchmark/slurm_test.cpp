// `hdr4d bench slurm` and `hdr4d bench collect` without Slurm's daemons: the generated array
// scripts are checked line by line and then executed the way slurmd would (bash with
// SLURM_ARRAY_TASK_ID and SLURM_CPUS_PER_TASK set), their result files merged into a store,
// a corrupt result file reported by name, and `bench run` finds every collected run stored.
#include <gtest/gtest.h>

#include <algorithm>
#include <regex>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

TEST(Slurm, GeneratedArraysRunAsTasksAndCollectIntoTheStore) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", jobs = dir / "jobs", store = dir / "store.db";
  WriteTinySuite(suite, "slurm-test",
                 nlohmann::json::parse(R"([
                   {"name": "hdr4dgs", "train": {"method": "hdr4dgs"}},
                   {"name": "4dgs", "train": {"method": "4dgs"},
                    "resources": {"cpus": 2, "memory_gb": 3, "minutes": 90}}])"),
                 {0, 1}, 60);
  const fs::path log = dir / "log.txt";
  const Command plan = RunHdr4dArgs({"bench", "slurm", suite.string(), "--out", jobs.string(),
                                     "--cache", (dir / "cache").string(), "--partition", "cpu",
                                     "--max-parallel", "3"},
                                    log);
  ASSERT_TRUE(plan.result.ok()) << plan.text;
  EXPECT_NE(plan.text.find("4 runs in 2 job array(s)"), std::string::npos) << plan.text;

  // One array per resource request, each task one run.
  const nlohmann::json p = ReadJsonFile(jobs / "plan.json");
  ASSERT_EQ(p["arrays"].size(), 2u);
  std::map<int, int> cpus_to_array;
  for (int k = 0; k < 2; ++k) {
    const std::string script = testing::ReadTextFile(jobs / ("array_" + std::to_string(k) + ".sbatch"));
    const nlohmann::json& a = p["arrays"][k];
    EXPECT_EQ(script.rfind("#!/bin/bash\n", 0), 0u);
    EXPECT_NE(script.find("#SBATCH --array=0-1%3\n"), std::string::npos) << script;
    const int cpus = a["resources"]["cpus"];
    cpus_to_array[cpus] = k;
    EXPECT_NE(script.find("#SBATCH --cpus-per-task=" + std::to_string(cpus) + "\n"), std::string::npos);
    EXPECT_NE(script.find(cpus == 2 ? "#SBATCH --mem=3072M\n" : "#SBATCH --mem=1024M\n"), std::string::npos) << script;
    EXPECT_NE(script.find(cpus == 2 ? "#SBATCH --time=1:30:00\n" : "#SBATCH --time=0:05:00\n"), std::string::npos) << script;
    EXPECT_NE(script.find("#SBATCH --partition=cpu\n"), std::string::npos);
    EXPECT_NE(script.find("#SBATCH --output=" + fs::absolute(jobs).string() + "/logs/%A_%a.out"), std::string::npos);
    EXPECT_NE(script.find(" bench task " + fs::absolute(jobs).string() + " --array " + std::to_string(k) +
                          " --index \"$SLURM_ARRAY_TASK_ID\""), std::string::npos) << script;
    EXPECT_EQ(a["tasks"].size(), 2u);
  }
  ASSERT_EQ(cpus_to_array.size(), 2u);
  EXPECT_NE(testing::ReadTextFile(jobs / "submit.sh").find("sbatch --parsable array_1.sbatch"), std::string::npos);

  // Outside a Slurm task the script refuses to run.
  const ChildResult outside = RunChild({.argv = {"/bin/bash", (jobs / "array_0.sbatch").string()}, .log = log});
  EXPECT_EQ(outside.exit_code, 1);

  // Every task, as slurmd runs it; the second run of a task finds its result and does nothing.
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 2; ++i) {
      const ChildResult t = RunChild({.argv = {"/bin/bash", (jobs / ("array_" + std::to_string(k) + ".sbatch")).string()},
                                      .log = log,
                                      .env = {{"SLURM_ARRAY_TASK_ID", std::to_string(i)}, {"SLURM_CPUS_PER_TASK", "1"}}});
      EXPECT_TRUE(t.ok()) << t.Describe() << testing::ReadTextFile(log);
    }
  }
  const ChildResult again = RunChild({.argv = {"/bin/bash", (jobs / "array_0.sbatch").string()}, .log = log,
                                      .env = {{"SLURM_ARRAY_TASK_ID", "0"}}});
  EXPECT_TRUE(again.ok());
  EXPECT_NE(testing::ReadTextFile(log).find("is done already"), std::string::npos);

  // Hostile result files (issue 51, cases 18 and 24), into a store of their own: a key of the
  // wrong type (a raw json type_error stopped the merges behind it), a result under another
  // run's file name, one whose id is in no plan, one with a label the plan does not give it.
  // Each is named with its key and not merged; every good file is merged; exit 1 at the end.
  {
    std::vector<fs::path> good;
    for (const auto& e : fs::directory_iterator(jobs / "results")) good.push_back(e.path());
    std::sort(good.begin(), good.end());
    ASSERT_EQ(good.size(), 4u);
    nlohmann::json typed = ReadJsonFile(good[0]);
    typed["iterations"] = "many";
    WriteJsonFile(jobs / "results" / "0-typed.json", typed);  // sorted before every good file
    WriteJsonFile(jobs / "results" / "stolen.json", ReadJsonFile(good[1]));
    nlohmann::json stray = ReadJsonFile(good[2]);
    stray["id"] = "00000000000000000000";
    WriteJsonFile(jobs / "results" / "00000000000000000000.json", stray);
    nlohmann::json relabelled = ReadJsonFile(good[3]);
    relabelled["labels"][0]["method"] = "someone-else";
    WriteJsonFile(jobs / "results" / "relabelled.json", relabelled);
    const fs::path hostile_store = dir / "hostile.db";
    const Command c = RunHdr4dArgs({"bench", "collect", jobs.string(), "--store", hostile_store.string()}, log);
    EXPECT_EQ(c.result.exit_code, 1) << c.text;
    EXPECT_NE(c.result.error_line.find("4 result file(s) could not be merged"), std::string::npos) << c.text;
    EXPECT_NE(c.text.find("0-typed.json: key 'iterations'"), std::string::npos) << c.text;
    EXPECT_NE(c.text.find("stolen.json: key 'id'"), std::string::npos) << c.text;
    EXPECT_NE(c.text.find("00000000000000000000.json: run 00000000000000000000 is not in plan.json"),
              std::string::npos) << c.text;
    EXPECT_NE(c.text.find("relabelled.json: key 'id'"), std::string::npos) << c.text;
    EXPECT_EQ(c.text.find("json.exception"), std::string::npos) << c.text;
    EXPECT_EQ(ResultsStore(hostile_store, false).RunIds("ok").size(), 4u);
    for (const char* f : {"0-typed.json", "stolen.json", "00000000000000000000.json", "relabelled.json"})
      fs::remove(jobs / "results" / f);
    // The plan's own file name with a label the plan does not give that run.
    relabelled["labels"][0]["method"] = "someone-else";
    const fs::path own = good[3];
    const nlohmann::json original = ReadJsonFile(own);
    WriteJsonFile(own, relabelled);
    const Command l = RunHdr4dArgs({"bench", "collect", jobs.string(), "--store", (dir / "label.db").string()}, log);
    EXPECT_EQ(l.result.exit_code, 1) << l.text;
    EXPECT_NE(l.text.find("key 'labels'"), std::string::npos) << l.text;
    EXPECT_EQ(ResultsStore(dir / "label.db", false).RunIds("ok").size(), 3u);
    WriteJsonFile(own, original);
  }

  // A corrupt result file is named; the good ones are merged all the same.
  testing::WriteTextFile(jobs / "results" / "broken.json", "{\"id\": ");
  const Command bad = RunHdr4dArgs({"bench", "collect", jobs.string(), "--store", store.string()}, log);
  EXPECT_EQ(bad.result.exit_code, 1);
  EXPECT_NE(bad.result.error_line.find("1 result file(s) could not be merged"), std::string::npos) << bad.text;
  EXPECT_NE(bad.text.find("broken.json"), std::string::npos);
  EXPECT_EQ(ResultsStore(store, false).RunIds("ok").size(), 4u);
  fs::remove(jobs / "results" / "broken.json");
  const Command good = RunHdr4dArgs({"bench", "collect", jobs.string(), "--store", store.string()}, log);
  ASSERT_TRUE(good.result.ok()) << good.text;
  EXPECT_NE(good.text.find("0 runs merged, 0 failed runs merged, 4 already in the store, 0 planned runs without a result"),
            std::string::npos) << good.text;
  {
    ResultsStore s(store, false);
    for (const RunSummary& r : s.Summaries()) EXPECT_EQ(r.source, "slurm");
  }
  // The collected runs are the suite's runs: a local `bench run` has nothing left to do.
  const Command run = RunHdr4dArgs({"bench", "run", suite.string(), "--store", store.string(), "--cache",
                                    (dir / "cache").string()}, log);
  ASSERT_TRUE(run.result.ok()) << run.text;
  EXPECT_NE(run.text.find("4 already in the store"), std::string::npos) << run.text;
}

}  // namespace
}  // namespace hdr4d::bench

namespace hdr4d::bench {
namespace {
// Issue 51, case 7: a newline in the suite name, --partition or --account became a shell command
// of the generated sbatch script. Every such value is refused before anything is written.
TEST(Slurm, ValuesThatWouldBreakOutOfTheScriptAreRefused) {
  testing::TempDir dir;
  const fs::path good = dir / "good.json", bad = dir / "bad.json", jobs = dir / "jobs";
  WriteTinySuite(good, "ok", nlohmann::json::parse(R"([{"name": "hdr4dgs", "train": {"method": "hdr4dgs"}}])"),
                 {0}, 10);
  WriteTinySuite(bad, "x\ntouch " + (dir / "pwned").string(),
                 nlohmann::json::parse(R"([{"name": "hdr4dgs", "train": {"method": "hdr4dgs"}}])"), {0}, 10);
  const std::vector<std::vector<std::string>> cases = {
      {"bench", "slurm", bad.string(), "--out", jobs.string()},
      {"bench", "slurm", good.string(), "--out", jobs.string(), "--partition", "cpu\ntouch x"},
      {"bench", "slurm", good.string(), "--out", jobs.string(), "--account", "a;touch x"},
      {"bench", "slurm", good.string(), "--out", (dir / "j\nk").string()}};
  for (const auto& args : cases) {
    const Command c = RunHdr4dArgs(args, dir / "log.txt");
    EXPECT_FALSE(c.result.ok()) << c.text;
    // The suite's name is refused where the suite is read (a name, case 9), the rest by slurm.
    EXPECT_TRUE(c.text.find("bench slurm: ") != std::string::npos ||
                c.text.find("bad.json.name: the name has a control character") != std::string::npos)
        << c.text;
    EXPECT_FALSE(fs::exists(jobs)) << c.text;
    EXPECT_FALSE(fs::exists(dir / "j\nk")) << c.text;
  }
  EXPECT_FALSE(fs::exists(dir / "pwned"));
}
}  // namespace
}  // namespace hdr4d::bench
