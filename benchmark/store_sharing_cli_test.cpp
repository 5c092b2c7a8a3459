// One store, several writers (issue 51, cases 22 and 23): a finished run's result kept in its
// folder while the store was locked is stored by the next `bench run` (or `bench collect` of the
// runs folder) without running it again, and two `bench run`s started together on one store
// share its runs: every run is trained once, in one folder, and stored once.
#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <thread>

#include "benchmark/bench_test_util.h"
#include "benchmark/kept_records.h"
#include "benchmark/results_store.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

// "N done now" of a bench run's last line.
int DoneNow(const std::string& text) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex("(\\d+) done now"))) return -1;
  return std::stoi(m[1]);
}

TEST(StoreSharing, AKeptResultIsStoredLaterWithoutRunningAgain) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", cache = dir / "cache", log = dir / "log.txt";
  WriteTinySuite(suite, "kept", {{{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}, {0}, 20);
  const Command first = RunHdr4dArgs({"bench", "run", suite.string(), "--store", (dir / "a.db").string(),
                                      "--cache", cache.string()}, log);
  ASSERT_TRUE(first.result.ok()) << first.text;
  const std::set<std::string> ids = ResultsStore(dir / "a.db", false).RunIds("ok");
  ASSERT_EQ(ids.size(), 1u);
  const std::string id = *ids.begin();
  const RunRecord record = ResultsStore(dir / "a.db", false).Record(id);
  // What a bench run leaves when its store stays locked: the record in the run's folder.
  WriteJsonFile(dir / "b.db.runs" / id / kKeptRecordName, record.ToJson());
  const Command later = RunHdr4dArgs({"bench", "run", suite.string(), "--store", (dir / "b.db").string(),
                                      "--cache", cache.string()}, log);
  ASSERT_TRUE(later.result.ok()) << later.text;
  EXPECT_NE(later.text.find("storing the result kept in"), std::string::npos) << later.text;
  EXPECT_FALSE(fs::exists(dir / "b.db.runs" / id / "train")) << "trained again";
  EXPECT_FALSE(fs::exists(dir / "b.db.runs" / id / kKeptRecordName));
  EXPECT_EQ(ResultsStore(dir / "b.db", false).Record(id).ToJson(), record.ToJson());
  // `bench collect` of the runs folder stores a kept record too.
  WriteJsonFile(dir / "c.runs" / id / kKeptRecordName, record.ToJson());
  const Command collect = RunHdr4dArgs({"bench", "collect", (dir / "c.runs").string(), "--store",
                                        (dir / "c.db").string()}, log);
  ASSERT_TRUE(collect.result.ok()) << collect.text;
  EXPECT_NE(collect.text.find("1 runs merged"), std::string::npos) << collect.text;
  EXPECT_EQ(ResultsStore(dir / "c.db", false).Record(id).ToJson(), record.ToJson());
}

// A campaign on a machine that keeps nothing (scripts/bench-campaign.sh): `bench export` writes
// each finished run as results/<id>.json, `bench collect` of that folder gives a new store the
// same records, and a second export changes no file (the folder is kept in git).
TEST(StoreSharing, ExportedRecordsMakeTheSameStoreElsewhere) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", cache = dir / "cache", log = dir / "log.txt";
  WriteTinySuite(suite, "moved", {{{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}, {0, 1}, 20);
  const fs::path a = dir / "a.db", b = dir / "b.db", records = dir / "records";
  const Command run = RunHdr4dArgs({"bench", "run", suite.string(), "--store", a.string(), "--cache",
                                    cache.string()}, log);
  ASSERT_TRUE(run.result.ok()) << run.text;
  const Command out = RunHdr4dArgs({"bench", "export", a.string(), "--suite", "moved", "--out",
                                    records.string()}, log);
  ASSERT_TRUE(out.result.ok()) << out.text;
  EXPECT_NE(out.text.find("2 run records written, 0 unchanged"), std::string::npos) << out.text;
  const std::set<std::string> ids = ResultsStore(a, false).RunIds("ok");
  ASSERT_EQ(ids.size(), 2u);
  for (const std::string& id : ids) EXPECT_TRUE(fs::exists(records / "results" / (id + ".json"))) << id;
  const auto stamp = fs::last_write_time(records / "results" / (*ids.begin() + ".json"));

  const Command in = RunHdr4dArgs({"bench", "collect", records.string(), "--store", b.string()}, log);
  ASSERT_TRUE(in.result.ok()) << in.text;
  EXPECT_NE(in.text.find("2 runs merged"), std::string::npos) << in.text;
  const ResultsStore sa(a, false), sb(b, false);
  for (const std::string& id : ids) EXPECT_EQ(sb.Record(id).ToJson(), sa.Record(id).ToJson()) << id;
  // The new store needs no run: the harness finds both stored.
  const Command dry = RunHdr4dArgs({"bench", "run", suite.string(), "--store", b.string(), "--cache",
                                    cache.string(), "--dry-run"}, log);
  ASSERT_TRUE(dry.result.ok()) << dry.text;
  EXPECT_FALSE(std::regex_search(dry.text, std::regex("\\n\\S+ +to run "))) << dry.text;
  EXPECT_NE(dry.text.find("2 already in the store, 0 to run"), std::string::npos) << dry.text;

  const Command again = RunHdr4dArgs({"bench", "export", b.string(), "--out", records.string()}, log);
  ASSERT_TRUE(again.result.ok()) << again.text;
  EXPECT_NE(again.text.find("0 run records written, 2 unchanged"), std::string::npos) << again.text;
  EXPECT_EQ(fs::last_write_time(records / "results" / (*ids.begin() + ".json")), stamp);

  // A store that is not there is named, and nothing is written.
  const Command missing = RunHdr4dArgs({"bench", "export", (dir / "none.db").string(), "--out",
                                        (dir / "empty").string()}, log);
  EXPECT_FALSE(missing.result.ok());
  EXPECT_NE(missing.text.find("none.db"), std::string::npos) << missing.text;
  EXPECT_FALSE(fs::exists(dir / "empty" / "results"));
}

TEST(StoreSharing, TwoHarnessesOnOneStoreNeverTakeTheSameRun) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", cache = dir / "cache", store = dir / "store.db";
  WriteTinySuite(suite, "shared",
                 {{{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}},
                  {{"name", "hdr4dgs"}, {"train", {{"method", "hdr4dgs"}}}}},
                 {0, 1}, 40);
  // The scene first, so that both harnesses start their runs together.
  const Command scene = RunHdr4dArgs({"bench", "run", suite.string(), "--store", (dir / "warm.db").string(),
                                      "--cache", cache.string(), "--iterations", "1", "--methods", "4dgs",
                                      "--seeds", "0"}, dir / "warm.txt");
  ASSERT_TRUE(scene.result.ok()) << scene.text;
  Command a, b;
  auto run = [&](Command* c, const char* log) {
    *c = RunHdr4dArgs({"bench", "run", suite.string(), "--store", store.string(), "--cache",
                       cache.string(), "--threads", "1"}, dir / log, 600);
  };
  std::thread ta(run, &a, "a.txt"), tb(run, &b, "b.txt");
  ta.join();
  tb.join();
  ASSERT_TRUE(a.result.ok()) << a.text;
  ASSERT_TRUE(b.result.ok()) << b.text;
  EXPECT_EQ(DoneNow(a.text) + DoneNow(b.text), 4) << a.text << b.text;
  ResultsStore s(store, false);
  EXPECT_EQ(s.RunIds("ok").size(), 4u);
  EXPECT_TRUE(s.Claims().empty());
  // One training per run folder (each child appends "$ <command>" to the run's log), and no
  // renders made from a checkpoint another harness deleted.
  for (const std::string& id : s.RunIds("ok")) {
    const std::string text = testing::ReadTextFile(store.string() + ".runs/" + id + "/log.txt");
    EXPECT_EQ(std::regex_search(text, std::regex("checkpoint.*not found|no checkpoint")), false) << text;
    const std::regex train_line("(^|\\n)\\$ \\S+ train ");
    const auto trainings = std::distance(
        std::sregex_iterator(text.begin(), text.end(), train_line), std::sregex_iterator());
    EXPECT_EQ(trainings, 1) << id << "\n" << text;
  }
}

// A long suite over several sessions (scripts/bench-campaign.sh): --max-runs takes a few runs at
// a time in the suite's order, and --any-code-version counts a run stored by an earlier code
// version (the same configuration and data) as done instead of making it again.
TEST(StoreSharing, MaxRunsAndRunsOfAnotherCodeVersion) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", cache = dir / "cache", log = dir / "log.txt";
  WriteTinySuite(suite, "campaign", {{{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}, {0, 1}, 20);
  const auto bench_run = [&](const fs::path& store, std::vector<std::string> extra) {
    std::vector<std::string> args = {"bench", "run", suite.string(), "--store", store.string(),
                                     "--cache", cache.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunHdr4dArgs(args, log);
  };
  const Command first = bench_run(dir / "a.db", {"--max-runs", "1"});
  ASSERT_TRUE(first.result.ok()) << first.text;
  EXPECT_EQ(DoneNow(first.text), 1) << first.text;
  EXPECT_NE(first.text.find("1 left for later (--max-runs 1)"), std::string::npos) << first.text;
  const std::set<std::string> ids = ResultsStore(dir / "a.db", false).RunIds("ok");
  ASSERT_EQ(ids.size(), 1u);
  // The same run as an earlier session's code version made it, in another store.
  RunRecord old = ResultsStore(dir / "a.db", false).Record(*ids.begin());
  ASSERT_EQ(old.labels.size(), 1u);
  EXPECT_EQ(old.labels[0].seed, 0);  // the suite's order: seed 0 first
  old.id = "0123456789abcdef0123";
  old.code_version = "earlier";
  old.config["identity"]["code_version"] = "earlier";
  ResultsStore(dir / "b.db").InsertRun(old);
  const Command plain = bench_run(dir / "b.db", {"--dry-run"});
  ASSERT_TRUE(plain.result.ok()) << plain.text;
  EXPECT_NE(plain.text.find("0 already in the store"), std::string::npos) << plain.text;
  // The dry run lists the earlier version's run as stored, as the real run counts it.
  const Command listed = bench_run(dir / "b.db", {"--dry-run", "--any-code-version"});
  ASSERT_TRUE(listed.result.ok()) << listed.text;
  EXPECT_NE(listed.text.find("(1 by another code version), 1 to run"), std::string::npos) << listed.text;
  EXPECT_EQ(CountLines(listed.text, "stored*:"), 1) << listed.text;
  std::size_t to_run = 0, stored_other = 0;
  for (std::size_t at = 0; (at = listed.text.find("  to run ", at)) != std::string::npos; ++at) ++to_run;
  for (std::size_t at = 0; (at = listed.text.find("  stored* ", at)) != std::string::npos; ++at) ++stored_other;
  EXPECT_EQ(to_run, 1u) << listed.text;
  EXPECT_EQ(stored_other, 1u) << listed.text;
  const Command any = bench_run(dir / "b.db", {"--any-code-version"});
  ASSERT_TRUE(any.result.ok()) << any.text;
  EXPECT_EQ(DoneNow(any.text), 1) << any.text;  // seed 1 only
  EXPECT_NE(any.text.find("(1 by another code version)"), std::string::npos) << any.text;
  const std::set<std::string> b = ResultsStore(dir / "b.db", false).RunIds("ok");
  EXPECT_EQ(b.size(), 2u);
  EXPECT_TRUE(b.count(old.id));
  const Command bad = bench_run(dir / "b.db", {"--max-runs", "-1"});
  EXPECT_FALSE(bad.result.ok()) << bad.text;
  EXPECT_NE(bad.text.find("--max-runs"), std::string::npos) << bad.text;
}

}  // namespace
}  // namespace hdr4d::bench
