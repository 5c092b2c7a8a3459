// The stress cases with killed or corrupt state: a corrupt checkpoint, a training killed and
// resumed, a benchmark run killed and run again.
#include <fmt/format.h>
#include <sqlite3.h>

#include <chrono>
#include <fstream>
#include <map>
#include <thread>

#include "benchmark/stress_cases.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::bench::stress {
namespace fs = std::filesystem;

// Runs stored with status ok, read through a read-only connection that takes no write lock (in
// WAL mode a reader never blocks the harness's writes): the watcher of killed-harness-resumed
// polls with it. 0 while the store or its tables do not exist yet.
static int StoredOkRuns(const fs::path& store) {
  if (!fs::exists(store)) return 0;
  sqlite3* db = nullptr;
  int count = 0;
  if (sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM runs WHERE status = 'ok'", -1, &stmt,
                           nullptr) == SQLITE_OK &&
        sqlite3_step(stmt) == SQLITE_ROW) {
      count = sqlite3_column_int(stmt, 0);
    }
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return count;
}

static StressOutcome CorruptCheckpoint(const Ctx& c) {
  MakeScene(c, c.dir / "scene", {});
  const fs::path run = c.dir / "run";
  const Exec t = Hdr4d(c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "60"}));
  if (!t.r.ok()) Fail("train: {}", t.r.Describe());
  const std::string results = ReadText(run / "results.json"),
                    config = ReadText(run / "config.json");
  const fs::path ckpt = run / "checkpoint.bin";
  std::string bytes = ReadText(ckpt);
  for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i)
    bytes[i] = static_cast<char>(~bytes[i]);
  std::ofstream(ckpt, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const Exec r = Hdr4d(c, {"render", "--run", run.string(), "--out", (c.dir / "renders").string()});
  Truncate(ckpt, 0.5);
  const Exec resume =
      Hdr4d(c, TrainArgs(c, c.dir / "scene", run, {"--iterations", "120", "--resume"}));
  StressOutcome o;
  o.checks[kNoCrash] = NoCrash(r.r) && NoCrash(resume.r);
  o.checks[kClearError] = ClearError(r, "checkpoint.bin") && ClearError(resume, "checkpoint.bin");
  o.checks[kNothingLost] =
      ReadText(run / "results.json") == results && ReadText(run / "config.json") == config;
  o.detail =
      fmt::format("flipped bytes, render: {}; truncated, resume: {}", Short(r), Short(resume));
  return o;
}

static StressOutcome KilledTrainingResumed(const Ctx& c) {
  MakeScene(c, c.dir / "scene", {});
  const std::vector<std::string> extra = {"--iterations", "300",       "--checkpoint-every",
                                          "50",           "--threads", "1"};
  const Exec whole = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "whole", extra));
  if (!whole.r.ok()) Fail("train: {}", whole.r.Describe());
  std::atomic<bool> kill{false};
  std::thread watcher([&] {
    // Kill as soon as the first checkpoint is there (training is then mid-way).
    for (int i = 0; i < 6000 && !fs::exists(c.dir / "killed" / "checkpoint.bin"); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    kill = true;
  });
  const Exec killed = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "killed", extra), &kill, 9);
  watcher.join();
  std::vector<std::string> resume_args = extra;
  resume_args.push_back("--resume");
  const Exec resumed = Hdr4d(c, TrainArgs(c, c.dir / "scene", c.dir / "killed", resume_args));
  StressOutcome o;
  o.checks[kNoCrash] = NoCrash(resumed.r);
  bool same = false;
  if (resumed.r.ok()) {
    const nlohmann::json a = ReadJsonFile(c.dir / "whole" / "results.json");
    const nlohmann::json b = ReadJsonFile(c.dir / "killed" / "results.json");
    same = a["curve"] == b["curve"] && a["test"] == b["test"] && a["gaussians"] == b["gaussians"];
  }
  o.checks[kNothingLost] = killed.r.signal == 9 && same;
  o.detail = fmt::format("killed run: {}; resumed: {}; resumed == uninterrupted: {}",
                         killed.r.Describe(), Short(resumed), same ? "yes" : "no");
  return o;
}

static StressOutcome KilledHarnessResumed(const Ctx& c) {
  const fs::path suite = c.dir / "suite.json", store = c.dir / "store.db";
  WriteJsonFile(suite,
                {{"name", "stress-kill"},
                 {"scenes",
                  {{{"name", "tiny"},
                    {"builtin",
                     {{"scene", "demo"},
                      {"flags", {{"size", 24}, {"timestamps", 3}, {"cameras", 3}, {"spp", 1}}},
                      {"synth", {{"crf", "filmic"}, {"seed", 1}}}}}}}},
                 {"methods",
                  {{{"name", "hdr4dgs"}, {"train", {{"method", "hdr4dgs"}}}},
                   {{"name", "4dgs"}, {"train", {{"method", "4dgs"}}}}}},
                 {"seeds", {0, 1}},
                 {"budgets", {{{"iterations", 100}}}}});
  const std::vector<std::string> args = {"bench",
                                         "run",
                                         suite.string(),
                                         "--store",
                                         store.string(),
                                         "--cache",
                                         (c.dir / "cache").string(),
                                         "--jobs",
                                         "2"};
  std::atomic<bool> kill{false};
  std::thread watcher([&] {
    for (int i = 0; i < 12000 && !kill; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      try {
        if (StoredOkRuns(store) > 0) kill = true;
      } catch (const Error&) {
      }
    }
    kill = true;
  });
  const Exec first = Hdr4d(c, args, &kill, 9);
  watcher.join();
  StressOutcome o;
  std::map<std::string, std::string> finished_before;
  bool intact = true;
  {
    ResultsStore s(store, false);
    for (const RunSummary& r : s.Summaries()) {
      finished_before[r.run_id] = s.Record(r.run_id).finished_at;
      intact &= r.status == "ok" && !s.Frames(r.run_id).empty();
    }
  }
  const Exec second = Hdr4d(c, args);
  bool kept = second.r.ok();
  int total = 0;
  {
    ResultsStore s(store, false);
    total = static_cast<int>(s.RunIds("ok").size());
    for (const auto& [id, at] : finished_before)
      kept &= s.HasRun(id) && s.Record(id).finished_at == at;
  }
  o.checks[kNoCrash] = NoCrash(second.r);
  o.checks[kNothingLost] = first.r.signal == 9 && intact && kept && total == 4;
  o.detail = fmt::format(
      "killed with {} of 4 runs stored (all complete: {}); second run: {}, "
      "{} runs stored, the earlier ones kept: {}",
      finished_before.size(), intact ? "yes" : "no", Short(second), total, kept ? "yes" : "no");
  return o;
}

void AddKilledStateCases(std::vector<Case>& cases) {
  AddCase(
      cases, "corrupt-checkpoint", "killed or corrupt state",
      "bytes flipped inside checkpoint.bin, then a truncated one: render and resume must refuse",
      CorruptCheckpoint);
  AddCase(cases, "killed-training-resumed", "killed or corrupt state",
          "training killed (SIGKILL) after a checkpoint, then --resume: must equal an "
          "uninterrupted run",
          KilledTrainingResumed);
  AddCase(cases, "killed-harness-resumed", "killed or corrupt state",
          "bench run killed (SIGKILL) after its first stored run, then run again",
          KilledHarnessResumed);
}

}  // namespace hdr4d::bench::stress
