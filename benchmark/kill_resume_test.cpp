// Killing the harness (SIGKILL, no chance to clean up) loses no finished run and leaves no
// half-written row: the store is checked after a kill during the first training and after a
// kill right behind the first stored run, and the next `bench run` finishes the rest without
// redoing what was stored.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "benchmark/sqlite_db.h"
#include "core/dataset/dataset.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

// Every stored run is whole: labels, status ok, one frame row per expected render with metrics,
// and the database has no dangling rows.
void ExpectWholeStore(const fs::path& path, std::size_t ldr_frames, std::size_t hdr_frames) {
  {
    Database db(path, false);
    Statement check = db.Prepare("PRAGMA integrity_check");
    ASSERT_TRUE(check.Step());
    EXPECT_EQ(check.Text(0), "ok");
    Statement fk = db.Prepare("PRAGMA foreign_key_check");
    EXPECT_FALSE(fk.Step()) << "dangling rows";
    Statement orphans = db.Prepare(
        "SELECT (SELECT count(*) FROM frames WHERE run_id NOT IN (SELECT id FROM runs)) + "
        "(SELECT count(*) FROM runs WHERE id NOT IN (SELECT run_id FROM run_labels))");
    orphans.Step();
    EXPECT_EQ(orphans.Int(0), 0);
  }
  ResultsStore store(path, false);
  for (const RunSummary& r : store.Summaries()) {
    EXPECT_EQ(r.status, "ok") << r.error;
    std::size_t ldr = 0, hdr = 0;
    for (const FrameResult& f : store.Frames(r.run_id)) {
      EXPECT_FALSE(f.metrics.empty()) << f.frame;
      (f.frame.rfind("hdr/", 0) == 0 ? hdr : ldr)++;
    }
    EXPECT_EQ(ldr, ldr_frames) << r.label.method;
    EXPECT_EQ(hdr, r.label.method == "4dgs" ? 0 : hdr_frames) << r.label.method;
  }
}

TEST(KillResume, KilledHarnessLosesNothingFinishedAndLeavesNoHalfRow) {
  testing::TempDir dir;
  const fs::path suite = dir / "suite.json", store = dir / "store.db";
  WriteTinySuite(suite, "kill",
                 nlohmann::json::parse(R"([{"name": "hdr4dgs", "train": {"method": "hdr4dgs"}},
                                           {"name": "4dgs", "train": {"method": "4dgs"}}])"),
                 {0, 1, 2}, 300);
  const std::vector<std::string> args = {"bench", "run", suite.string(), "--store", store.string(),
                                         "--cache", (dir / "cache").string(), "--jobs", "2"};
  auto stored = [&] {
    try {
      return fs::exists(store) ? ResultsStore(store, false).RunIds("ok").size() : 0;
    } catch (const Error&) {
      return std::size_t{0};  // being created
    }
  };
  auto run_killed_when = [&](const std::function<bool()>& condition) {
    std::atomic<bool> kill{false};
    std::thread watcher([&] {
      while (!kill) {
        if (condition()) kill = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
    const Command c = RunHdr4dArgs(args, dir / "log.txt", 300, &kill, /*SIGKILL*/ 9);
    kill = true;
    watcher.join();
    return c;
  };

  // 1. Killed while the first trainings run (a training child has started).
  const Command early = run_killed_when([&] { return fs::exists(store.string() + ".runs"); });
  EXPECT_EQ(early.result.signal, 9) << early.text;
  EXPECT_EQ(stored(), 0u);
  const Dataset scene = [&] {
    for (const auto& e : fs::directory_iterator(dir / "cache" / "builtin"))
      if (fs::is_directory(e) && fs::exists(e.path() / "transforms_test.json")) return LoadDataset(e.path());
    throw Error("no scene in the cache");
  }();
  std::set<std::string> hdr_files;
  for (const Frame& f : scene.test) hdr_files.insert(*f.exr_file_path);
  ExpectWholeStore(store, scene.test.size(), hdr_files.size());

  // 2. Killed just after the first run is stored.
  const Command second = run_killed_when([&] { return stored() >= 1; });
  EXPECT_EQ(second.result.signal, 9) << second.text;
  const std::size_t kept = stored();
  EXPECT_GE(kept, 1u);
  EXPECT_LT(kept, 6u) << "the kill came too late to test anything";
  ExpectWholeStore(store, scene.test.size(), hdr_files.size());
  std::map<std::string, std::string> finished;
  {
    ResultsStore s(store, false);
    for (const std::string& id : s.RunIds("ok")) finished[id] = s.Record(id).finished_at;
  }

  // 3. The same command finishes the suite; the stored runs are not redone.
  const Command last = RunHdr4dArgs(args, dir / "log.txt");
  ASSERT_TRUE(last.result.ok()) << last.text;
  EXPECT_NE(last.text.find(std::to_string(kept) + " already in the store"), std::string::npos) << last.text;
  ExpectWholeStore(store, scene.test.size(), hdr_files.size());
  ResultsStore s(store, false);
  EXPECT_EQ(s.RunIds("ok").size(), 6u);
  for (const auto& [id, at] : finished) EXPECT_EQ(s.Record(id).finished_at, at) << id;
}

}  // namespace
}  // namespace hdr4d::bench
