#include "benchmark/results_store.h"

#include <gtest/gtest.h>

#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "benchmark/kept_records.h"
#include "benchmark/sqlite_db.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::ErrorOf;
using testing::TempDir;

RunRecord Sample(const std::string& id, const std::string& method = "m", double psnr = 20) {
  RunRecord r;
  r.id = id;
  r.config = {{"k", 1}};
  r.code_version = "v1";
  r.machine = {{"cpu_model", "x"}};
  r.data_checksum = "abc";
  r.train_seconds = 12.5;
  r.render_fps = 30;
  r.iterations = 100;
  r.gaussians = 5000;
  r.labels = {{"suite", method, "lego", "ldr", 0, "100it", ""}};
  // In file-name order, the order the store returns them in.
  r.frames = {{"hdr/a.exr", 0.0, 0, 0.0, {{"mu_psnr", std::numeric_limits<double>::infinity()}}, {}},
              {"images/a.png", 0.0, 0, 2.0, {{"psnr", psnr}, {"ssim", 0.8}}, {{"region_ldr", 0.3}}},
              {"images/b.png", 1.0, 0, 2.0, {{"psnr", psnr + 2}, {"ssim", 0.9}}, {}}};
  r.series = {{"loss", {{1, 0.5}, {2, 0.25}}}};
  r.started_at = r.finished_at = "2026-01-01T00:00:00Z";
  return r;
}

TEST(ResultsStore, RoundTripsARunWithItsFramesSeriesAndInfinity) {
  TempDir dir;
  ResultsStore store(dir / "sub" / "s.db");
  store.InsertRun(Sample("r1"));
  const RunRecord back = store.Record("r1");
  EXPECT_EQ(back.ToJson(), Sample("r1").ToJson());
  const auto summaries = store.Summaries();
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_DOUBLE_EQ(summaries[0].metrics.at("psnr"), 21);  // mean over the LDR frames
  // Identical images (+inf) are counted, not averaged: tables printed inf and marked it best.
  EXPECT_FALSE(summaries[0].metrics.count("mu_psnr"));
  EXPECT_EQ(summaries[0].identical_frames, (std::map<std::string, int>{{"mu_psnr", 1}}));
  EXPECT_EQ(store.RunIds("ok"), std::set<std::string>{"r1"});
  // Through JSON (a Slurm result file) and back.
  EXPECT_EQ(RunRecord::FromJson(back.ToJson(), "f").ToJson(), back.ToJson());
}

// As `hdr4d eval`: the mean over the finite values, the identical frames counted beside it.
TEST(ResultsStore, MeansLeaveIdenticalFramesOut) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  RunRecord r = Sample("r1");
  r.frames[1].metrics["psnr"] = std::numeric_limits<double>::infinity();
  r.frames[2].metrics["psnr"] = 30;
  store.InsertRun(r);
  const RunSummary s = store.Summaries().at(0);
  EXPECT_DOUBLE_EQ(s.metrics.at("psnr"), 30);
  EXPECT_EQ(s.identical_frames.at("psnr"), 1);
  EXPECT_DOUBLE_EQ(s.metrics.at("ssim"), 0.85);
}

TEST(ResultsStore, AFailedInsertLeavesNoHalfRow) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  store.InsertRun(Sample("r1"));
  RunRecord bad = Sample("r2");
  bad.frames.push_back(bad.frames.front());  // same frame twice: the primary key refuses it
  EXPECT_THROW(store.InsertRun(bad), Error);
  EXPECT_FALSE(store.HasRun("r2"));
  EXPECT_EQ(store.Summaries().size(), 1u);
  EXPECT_EQ(store.Record("r1").ToJson(), Sample("r1").ToJson());
}

TEST(ResultsStore, FinishedRunsAreKeptFailuresReplaced) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  store.InsertRun(Sample("r1", "m", 20));
  RunRecord again = Sample("r1", "alias", 99);
  store.InsertRun(again);  // same identity: only the new label is added
  EXPECT_EQ(store.Record("r1").frames[1].metrics.at("psnr"), 20);  // images/a.png
  EXPECT_EQ(store.Record("r1").labels.size(), 2u);
  RunRecord failed = Sample("r2");
  failed.status = "failed";
  failed.error = "train: exit code 1";
  failed.frames.clear();
  store.InsertRun(failed);
  EXPECT_EQ(store.RunIds("failed"), std::set<std::string>{"r2"});
  store.InsertRun(Sample("r2"));
  EXPECT_EQ(store.RunIds("failed").size(), 0u);
  EXPECT_EQ(store.Record("r2").frames.size(), 3u);
}

TEST(ResultsStore, SubmissionsNeverTakeAnotherRunsLabel) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  store.InsertRun(Sample("harness"));
  RunRecord sub = Sample("sub-1");
  sub.source = "submit";
  const std::string e = ErrorOf([&] { store.InsertSubmission(sub, /*replace=*/true); });
  EXPECT_NE(e.find("never replaces a harness run"), std::string::npos) << e;
  EXPECT_FALSE(store.HasRun("sub-1"));
  EXPECT_EQ(store.Record("harness").ToJson(), Sample("harness").ToJson());
  // Under the submission's own budget label, the trained method's name is still refused: the
  // tables have no budget for a submission, which replaced the trained run's row.
  sub.labels[0].budget = "external";
  const std::string e2 = ErrorOf([&] { store.InsertSubmission(sub, /*replace=*/true); });
  EXPECT_NE(e2.find("method 'm' is trained by the harness"), std::string::npos) << e2;
  EXPECT_FALSE(store.HasRun("sub-1"));
  // Under its own name it is stored; a second submission there needs --replace.
  sub.labels[0].method = "external";
  store.InsertSubmission(sub, false);
  RunRecord sub2 = sub;
  sub2.id = "sub-2";
  EXPECT_NE(ErrorOf([&] { store.InsertSubmission(sub2, false); }).find("--replace"), std::string::npos);
  EXPECT_TRUE(store.HasRun("sub-1"));
  store.InsertSubmission(sub2, true);
  EXPECT_FALSE(store.HasRun("sub-1"));
  EXPECT_TRUE(store.HasRun("sub-2"));
  EXPECT_TRUE(store.HasRun("harness"));
}

TEST(ResultsStore, RefusesFilesThatAreNotAStore) {
  TempDir dir;
  testing::WriteTextFile(dir / "text.db", "this is not a database, just text that is long enough\n");
  const std::string e = ErrorOf([&] { ResultsStore s(dir / "text.db"); });
  EXPECT_NE(e.find("text.db"), std::string::npos) << e;
  {
    Database other(dir / "other.db", true);
    other.Exec("CREATE TABLE photos (id INTEGER)");
  }
  EXPECT_NE(ErrorOf([&] { ResultsStore s(dir / "other.db"); }).find("not an hdr4d results store"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ResultsStore s(dir / "missing.db", false); }).find("no such results store"),
            std::string::npos);
}

// A foreign database with a table named like ours was made a store (user_version 1 and seven
// tables added) even by `bench table`, then failed with a raw SQL error.
TEST(ResultsStore, NeverChangesAFileThatIsNotAStore) {
  TempDir dir;
  auto schema = [](const std::filesystem::path& p) {
    Database db(p, false);
    std::string s;
    for (Statement q = db.Prepare("SELECT name FROM sqlite_master ORDER BY name"); q.Step();)
      s += q.Text(0) + ",";
    Statement v = db.Prepare("PRAGMA user_version");
    v.Step();
    return s + std::to_string(v.Int(0));
  };
  {
    Database other(dir / "x.db", true);
    other.Exec("CREATE TABLE runs (id TEXT PRIMARY KEY, status TEXT)");
  }
  const std::string before = schema(dir / "x.db");
  for (bool create : {false, true}) {
    const std::string e = ErrorOf([&] { ResultsStore s(dir / "x.db", create); });
    EXPECT_NE(e.find("x.db: an SQLite database with tables of its own (runs)"), std::string::npos)
        << e;
    EXPECT_EQ(schema(dir / "x.db"), before);
  }
  // Our version number on other columns.
  {
    Database other(dir / "y.db", true);
    other.Exec("CREATE TABLE runs (id TEXT PRIMARY KEY, status TEXT); PRAGMA user_version = 1");
  }
  const std::string e = ErrorOf([&] { ResultsStore s(dir / "y.db", false); });
  EXPECT_NE(e.find("table 'runs' has the columns (id,status)"), std::string::npos) << e;
  // An empty database: a reading command does not make it a store.
  { Database empty(dir / "e.db", true); }
  EXPECT_NE(ErrorOf([&] { ResultsStore s(dir / "e.db", false); }).find("an empty SQLite database"),
            std::string::npos);
  EXPECT_EQ(schema(dir / "e.db"), "0");
  ResultsStore made(dir / "e.db", true);
  EXPECT_NO_THROW(ResultsStore(dir / "e.db", false));
}

// The connection set the WAL journal on opening, before the check that the file is a store:
// a reading command on another program's database rewrote its header.
TEST(ResultsStore, LeavesAForeignDatabasesBytesAlone) {
  TempDir dir;
  const auto bytes = [](const std::filesystem::path& p) { return testing::ReadTextFile(p); };
  // Made with SQLite itself (rollback journal, as most programs' files): Database's opening
  // is what is tested.
  for (const char* sql : {"CREATE TABLE photos (id INTEGER); INSERT INTO photos VALUES (1)",
                          "PRAGMA user_version = 7"}) {
    const std::filesystem::path p = dir / "foreign.db";
    std::filesystem::remove(p);
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(p.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sql;
    sqlite3_close(db);
    const std::string before = bytes(p);
    ASSERT_FALSE(before.empty());
    for (const bool create : {false, true}) {
      EXPECT_NE(ErrorOf([&] { ResultsStore s(p, create); }), "") << sql;
      EXPECT_EQ(bytes(p), before) << sql << " create=" << create;
    }
  }
  { ResultsStore made(dir / "ours.db"); }  // a store of ours is in WAL mode
  Database ours(dir / "ours.db", false);
  Statement mode = ours.Prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode.Step());
  EXPECT_EQ(mode.Text(0), "wal");
}

TEST(ResultsStore, StressOutcomesKeepTheLatestPerCase) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  store.WriteStress({"case", "cat", "what", "failed", {{"no crash", false}}, "d1", "v1", "t1"});
  store.WriteStress({"case", "cat", "what", "held", {{"no crash", true}, {"no NaN", nullptr}}, "d2", "v2", "t2"});
  const auto all = store.StressOutcomes();
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].outcome, "held");
  EXPECT_TRUE(all[0].checks["no NaN"].is_null());
}

// 1e30 gaussians were stored as -9223372036854775808 and 2.5 as 2 (a plain get<int64_t>()).
TEST(RunRecord, IntegerKeysMustBeIntegersInRange) {
  for (const nlohmann::json& bad : {nlohmann::json(1e30), nlohmann::json(1e19),
                                    nlohmann::json(2.5), nlohmann::json(18446744073709551615ull)}) {
    nlohmann::json j = Sample("r").ToJson();
    j["gaussians"] = bad;
    const std::string e = ErrorOf([&] { RunRecord::FromJson(j, "results/r.json"); });
    EXPECT_NE(e.find("results/r.json: key 'gaussians' must be an integer"), std::string::npos)
        << bad.dump() << ": " << e;
  }
  nlohmann::json j = Sample("r").ToJson();
  j["gaussians"] = 1e3;
  j["labels"][0]["seed"] = 1e300;
  EXPECT_NE(ErrorOf([&] { RunRecord::FromJson(j, "f.json"); }).find("key 'seed'"),
            std::string::npos);
  j["labels"][0]["seed"] = 2;
  EXPECT_EQ(RunRecord::FromJson(j, "f.json").gaussians, 1000);
  EXPECT_EQ(JsonInteger(-0x1p63, "f", "k"), std::numeric_limits<std::int64_t>::min());
  EXPECT_NE(ErrorOf([] { JsonInteger(0x1p63, "f", "k"); }).find("'k'"), std::string::npos);
  EXPECT_NE(ErrorOf([] { JsonInteger(-1, "f", "k", 0); }).find("at least 0"), std::string::npos);
}

TEST(RunRecord, MalformedRecordsNameTheFileAndKey) {
  nlohmann::json j = Sample("r").ToJson();
  j.erase("labels");
  EXPECT_NE(ErrorOf([&] { RunRecord::FromJson(j, "results/r.json"); }).find("results/r.json: key 'labels'"),
            std::string::npos);
  j = Sample("r").ToJson();
  j["frames"][1]["metrics"]["psnr"] = "high";
  EXPECT_NE(ErrorOf([&] { RunRecord::FromJson(j, "f.json"); }).find("psnr"), std::string::npos);
  j = Sample("r").ToJson();
  j["status"] = "maybe";
  EXPECT_NE(ErrorOf([&] { RunRecord::FromJson(j, "f.json"); }).find("status"), std::string::npos);
}

// An optional key of the wrong type gave a raw "[json.exception.type_error.302]" naming neither
// the file nor the key (issue 51, case 24); a label that is a path is refused (case 9).
TEST(RunRecord, WrongTypesOfOptionalKeysNameTheFileAndKey) {
  const std::vector<std::pair<std::string, nlohmann::json>> cases = {
      {"/iterations", "many"},          {"/gaussians", {1, 2}},
      {"/git_describe", 3},             {"/config", "text"}, {"/machine", 1},
      {"/frames/0/exposure", "bright"}, {"/frames/0/camera_id", "cam0"},
      {"/frames/0/metrics", {1, 2}},    {"/series", 3},
      {"/series/loss", "points"},       {"/frames", {{"a", 1}}},
      {"/labels/0/method", "../../x"},  {"/labels/0/scene", "/tmp/victim"},
  };
  for (const auto& [pointer, value] : cases) {
    nlohmann::json j = Sample("r").ToJson();
    j[nlohmann::json::json_pointer(pointer)] = value;
    std::string e;
    try {
      RunRecord::FromJson(j, "results/r.json");
    } catch (const Error& error) {
      e = error.what();
    } catch (const std::exception& other) {
      e = std::string("raw: ") + other.what();
    }
    const std::string key = pointer.substr(pointer.rfind('/') + 1);
    EXPECT_EQ(e.rfind("results/r.json", 0), 0u) << pointer << ": " << e;
    EXPECT_NE(e.find("'" + key + "'"), std::string::npos) << pointer << ": " << e;
    EXPECT_EQ(e.find("json.exception"), std::string::npos) << pointer << ": " << e;
  }
}

// A process that lives until it is killed: a live claim holder other than this test.
pid_t StartSleeper() {
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sleep", "sleep", "60", static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Two bench runs on one store took the same runs (issue 51, case 23): a run is claimed in the
// store, by one owner at a time, through two connections; the claim of a process that is gone
// (or whose pid was reused) is taken over, and one from another host once it is older than the
// run's time limit.
TEST(RunClaims, OneOwnerAtATimeAndDeadClaimsAreTakenOver) {
  TempDir dir;
  ResultsStore a(dir / "s.db"), b(dir / "s.db");
  const ClaimOwner me = ClaimOwner::Self();
  ASSERT_FALSE(me.pid_start.empty());
  const pid_t sleeper = StartSleeper();
  ASSERT_GT(sleeper, 0);
  const ClaimOwner other{sleeper, me.host, ProcessStartTime(sleeper)};
  ASSERT_FALSE(other.pid_start.empty());
  EXPECT_EQ(a.Claim("r1", 3600, me), ClaimResult::kClaimed);
  EXPECT_EQ(b.Claim("r1", 3600, other), ClaimResult::kTaken);
  EXPECT_EQ(a.Claim("r1", 3600, me), ClaimResult::kClaimed);  // its own claim
  EXPECT_EQ(b.Claim("r2", 3600, other), ClaimResult::kClaimed);
  EXPECT_EQ(a.Claim("r2", 3600, me), ClaimResult::kTaken);
  kill(sleeper, SIGKILL);
  waitpid(sleeper, nullptr, 0);
  EXPECT_EQ(ProcessStartTime(sleeper), "");
  EXPECT_EQ(a.Claim("r2", 3600, me), ClaimResult::kClaimed);  // its holder is gone
  // This pid, but another process's start time: a reused pid, a stale claim.
  EXPECT_EQ(b.Claim("r3", 3600, {me.pid, me.host, "1"}), ClaimResult::kClaimed);
  EXPECT_EQ(a.Claim("r3", 3600, me), ClaimResult::kClaimed);
  // Another host's claim: held while younger than the run's time limit.
  EXPECT_EQ(b.Claim("r4", 3600, {4242, "elsewhere", "7"}), ClaimResult::kClaimed);
  EXPECT_EQ(a.Claim("r4", 3600, me), ClaimResult::kTaken);
  EXPECT_EQ(a.Claim("r4", 0, me), ClaimResult::kClaimed);
  // A run stored meanwhile is not claimed at all.
  b.InsertRun(Sample("r5"));
  EXPECT_EQ(a.Claim("r5", 3600, me), ClaimResult::kStored);
  a.Release("r1", me);
  b.Release("r2", other);  // not its claim any more: nothing happens
  const auto claims = b.Claims();
  EXPECT_EQ(claims.count("r1"), 0u);
  ASSERT_EQ(claims.count("r2"), 1u);
  EXPECT_EQ(claims.at("r2").pid, me.pid);
  EXPECT_EQ(claims.count("r5"), 0u);
}

// A store locked by another connection past the busy timeout threw a finished run away
// (issue 51, case 22): the record is kept in the run's folder, the writer waits with growing
// pauses, and a later attempt stores the kept record.
TEST(KeptRecords, AStoreLockedPastTheTimeoutKeepsTheFinishedRun) {
  TempDir dir;
  ResultsStore store(dir / "s.db");
  store.SetBusyTimeout(50);
  const std::filesystem::path run_dir = dir / "runs" / "r1";
  {
    Database locker(dir / "s.db", false);
    locker.Exec("BEGIN IMMEDIATE");
    EXPECT_THROW(store.InsertRun(Sample("r1")), DatabaseBusy);
    const auto start = std::chrono::steady_clock::now();
    EXPECT_FALSE(StoreOrKeep(store, Sample("r1"), run_dir, {.attempts = 3, .first_pause_seconds = 0.05}));
    // Three waits of 50 ms and pauses of 50 and 150 ms.
    EXPECT_GE(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 0.3);
    EXPECT_TRUE(std::filesystem::exists(run_dir / kKeptRecordName));
    locker.Exec("ROLLBACK");
  }
  EXPECT_FALSE(store.HasRun("r1"));
  const std::optional<RunRecord> kept = ReadKeptRecord(run_dir, "r1");
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept->ToJson(), Sample("r1").ToJson());
  EXPECT_FALSE(ReadKeptRecord(run_dir, "r2"));  // another run's folder: not taken
  EXPECT_TRUE(StoreOrKeep(store, *kept, run_dir, {}));
  EXPECT_EQ(store.Record("r1").ToJson(), Sample("r1").ToJson());
  EXPECT_FALSE(std::filesystem::exists(run_dir / kKeptRecordName));

  // A lock released during the pauses: stored by a later attempt.
  Database locker(dir / "s.db", false);
  locker.Exec("BEGIN IMMEDIATE");
  std::thread release([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    locker.Exec("ROLLBACK");
  });
  EXPECT_TRUE(StoreOrKeep(store, Sample("r2"), dir / "runs" / "r2", {.attempts = 6, .first_pause_seconds = 0.05}));
  release.join();
  EXPECT_TRUE(store.HasRun("r2"));
}

// --series-points: each curve keeps at most N points, evenly spaced, first and last kept; a
// curve already that short is kept as it is.
TEST(ResultsStore, ThinnedSeriesKeepTheirEndsAndSpacing) {
  RunRecord r;
  for (int i = 0; i < 256; ++i) r.series["tone:0:r"].push_back({i * 0.1, i * 2.0});
  r.series["loss"] = {{1, 5}, {2, 4}, {3, 3}};
  ThinSeries(&r, 32);
  const Series& tone = r.series["tone:0:r"];
  ASSERT_EQ(tone.size(), 32u);
  EXPECT_EQ(tone.front().second, 0.0);
  EXPECT_EQ(tone.back().second, 510.0);
  for (std::size_t k = 1; k < tone.size(); ++k) {
    const double step = tone[k].second - tone[k - 1].second;  // 2 x an index step of 8 or 9
    EXPECT_GE(step, 16.0);
    EXPECT_LE(step, 18.0);
  }
  EXPECT_EQ(r.series["loss"].size(), 3u);
  ThinSeries(&r, 2);
  EXPECT_EQ(r.series["loss"], (Series{{1, 5}, {3, 3}}));
}

}  // namespace
}  // namespace hdr4d::bench
