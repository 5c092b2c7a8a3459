// The shipped `ci` suite end to end (CTest fixture ci_store: the output tests read its store):
// every configuration of the paper's Tables 1 and 4-7 on two tiny scenes and two seeds, then a
// second `bench run` that finds everything stored and redoes nothing.
#include <gtest/gtest.h>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

TEST(CiSuite, RunsEveryConfigurationIntoTheStoreAndResumesWithoutRedoing) {
  const fs::path dir = Artifacts("ci");
  fs::remove(dir / "store.db");
  fs::remove(dir / "store.db-wal");
  fs::remove(dir / "store.db-shm");
  fs::remove_all(dir / "runs");
  const std::vector<std::string> args = {"bench", "run", "ci", "--store", (dir / "store.db").string(),
                                         "--cache", (dir / "cache").string(), "--runs-dir",
                                         (dir / "runs").string(), "--jobs", "2"};
  const Command first = RunHdr4dArgs(args, dir / "run.log");
  ASSERT_TRUE(first.result.ok()) << first.text;

  const Suite suite = LoadSuite("ci");
  std::size_t labels = 0;
  for (const MethodSpec& m : suite.methods)
    labels += (m.supervision.empty() ? suite.supervision : m.supervision).size();
  labels *= suite.scenes.size() * suite.seeds.size();
  ResultsStore store(dir / "store.db", false);
  const std::vector<RunSummary> runs = store.Summaries("ci");
  EXPECT_EQ(runs.size(), labels);
  std::map<std::string, std::string> finished;
  for (const RunSummary& r : runs) {
    EXPECT_EQ(r.status, "ok") << r.label.method << " " << r.error;
    EXPECT_GT(r.train_seconds, 0);
    EXPECT_GT(r.render_fps, 0);
    // The grid family (HexPlane, HDR-HexPlane) has no Gaussians to count.
    if (r.label.method == "HexPlane" || r.label.method == "HDR-HexPlane")
      EXPECT_EQ(r.gaussians, -1) << r.label.method;
    else
      EXPECT_GT(r.gaussians, 0) << r.label.method;
    EXPECT_GT(r.peak_rss_mb, 10);
    EXPECT_FALSE(store.Frames(r.run_id).empty());
    EXPECT_EQ(r.machine.value("cores", 0) > 0, true);
    EXPECT_FALSE(r.machine.value("simd_target", "").empty());
    const auto series = store.AllSeries(r.run_id);
    EXPECT_TRUE(series.count("loss")) << r.run_id;
    finished[r.run_id] = store.Record(r.run_id).finished_at;
  }

  // Same command again: everything is in the store, nothing runs, nothing changes.
  const Command second = RunHdr4dArgs(args, dir / "run.log");
  ASSERT_TRUE(second.result.ok()) << second.text;
  EXPECT_NE(second.text.find(" 0 to run"), std::string::npos) << second.text;
  for (const auto& [id, at] : finished) EXPECT_EQ(store.Record(id).finished_at, at) << id;
}

}  // namespace
}  // namespace hdr4d::bench
