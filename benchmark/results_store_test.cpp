#include "benchmark/results_store.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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
  EXPECT_TRUE(std::isinf(summaries[0].metrics.at("mu_psnr")));
  EXPECT_EQ(store.RunIds("ok"), std::set<std::string>{"r1"});
  // Through JSON (a Slurm result file) and back.
  EXPECT_EQ(RunRecord::FromJson(back.ToJson(), "f").ToJson(), back.ToJson());
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

}  // namespace
}  // namespace hdr4d::bench
