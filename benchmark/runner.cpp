#include "benchmark/runner.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "benchmark/child_process.h"
#include "benchmark/kept_records.h"
#include "benchmark/machine.h"
#include "benchmark/results_store.h"
#include "benchmark/run_pipeline.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::atomic<bool> g_cancel{false};
std::atomic<int> g_signal{0};

extern "C" void OnStopSignal(int signal) {
  g_signal = signal;
  g_cancel = true;
}

// SIGINT / SIGTERM / SIGHUP stop the harness cleanly: children are stopped, finished runs are
// already stored, nothing half-written is stored.
class StopSignals {
 public:
  StopSignals() {
    g_cancel = false;
    g_signal = 0;
    struct sigaction action {};
    action.sa_handler = OnStopSignal;
    sigemptyset(&action.sa_mask);
    for (int i = 0; i < 3; ++i) sigaction(kSignals[i], &action, &old_[i]);
  }
  ~StopSignals() {
    for (int i = 0; i < 3; ++i) sigaction(kSignals[i], &old_[i], nullptr);
  }

 private:
  static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
  struct sigaction old_[3];
};

std::string Duration(double s) {
  if (!(s >= 0) || !std::isfinite(s)) return "?";
  const long t = std::lround(s);
  if (t >= 3600) return fmt::format("{}h{:02d}m", t / 3600, (t % 3600) / 60);
  if (t >= 60) return fmt::format("{}m{:02d}s", t / 60, t % 60);
  return fmt::format("{}s", t);
}

std::string Describe(const RunLabel& l) {
  std::string s = fmt::format("{}/{}/{}/s{}", l.method, l.scene, l.supervision, l.seed);
  if (!l.variant.empty()) s += "/" + l.variant;
  return s + "/" + l.budget;
}

struct Running {
  const RunSpec* run;
  std::string stage;
  std::chrono::steady_clock::time_point start;
};

// What the workers and the progress line share, under `mutex`.
struct Progress {
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<const RunSpec*> queue;
  std::map<std::string, Running> running;
  double units_left = 0, units_done = 0, seconds_done = 0;
  std::vector<std::string> failures, kept;
  std::string last_line, fatal;
  RunnerSummary* summary = nullptr;
  int series_points = 0;  // RunnerOptions::series_points
};

// --dry-run: every planned run with its id and whether it is stored, failed or still to run.
// `other_versions` (--any-code-version): the runs another code version stored, by identity
// without the version; they count as stored ("stored*"), as the real run counts them.
void PrintDryRun(const std::vector<PreparedScene>& scenes,
                 const std::vector<RunSpec>& runs,
                 const std::set<std::string>& ok,
                 const std::set<std::string>& failed,
                 const std::map<std::string, std::string>& other_versions) {
  for (const PreparedScene& s : scenes) {
    if (!s.ready) {
      fmt::print(stderr,
                 "bench: scene '{}' is not generated yet ({}): a real run renders it first; "
                 "its runs' ids depend on its data and are shown as '-'\n",
                 s.spec->name, s.dir.string());
    }
  }
  for (const RunSpec& r : runs) {
    if (!r.prepared->ready) {
      fmt::print("{:<16}  {:<7} {}\n", "-", "to run", Describe(r.labels.front()));
      continue;
    }
    const char* state = ok.count(r.id)                                         ? "stored"
                        : other_versions.count(IdentityKeyWithoutVersion(r.identity)) ? "stored*"
                        : failed.count(r.id)                                     ? "failed"
                                                                                 : "to run";
    fmt::print("{}  {:<7} {}\n", r.id, state, Describe(r.labels.front()));
  }
  if (!other_versions.empty())
    fmt::print("stored*: stored by another code version, counted as done (--any-code-version)\n");
}

// What became of one run taken off the queue.
struct Outcome {
  enum class Kind { kRan, kTaken, kStoredElsewhere, kLockedOut } kind = Kind::kRan;
  std::optional<RunRecord> record;  // kRan: nullopt when cancelled
  bool stored = true;               // false: the store stayed locked, the record is kept
  std::string error;                // from the harness itself (store not writable, ...)
};

// Books one run (called under the mutex): counts, the failure list, the last line. An exception
// from the harness itself stops every worker.
void Finished(Progress& p, const RunSpec& run, const Outcome& o, double took) {
  using Kind = Outcome::Kind;
  const std::string name = Describe(run.labels.front());
  if (!o.error.empty()) {
    p.fatal = fmt::format("{}: {}", name, o.error);
    g_cancel = true;
  } else if (o.kind == Kind::kTaken) {
    ++p.summary->taken;
    p.last_line = fmt::format("{} is being run by another bench run", name);
  } else if (o.kind == Kind::kStoredElsewhere) {
    ++p.summary->already_done;
  } else if (o.kind == Kind::kLockedOut) {
    ++p.summary->locked_out;
  } else if (o.record) {
    p.units_done += WorkUnits(run);
    p.seconds_done += took;
    if (!o.stored) {
      ++p.summary->kept;
      p.kept.push_back(fmt::format("{} ({})", name, run.id));
    }
    if (o.record->status == "ok") {
      ++p.summary->done;
      p.last_line = fmt::format("{} in {}", name, Duration(took));
    } else {
      ++p.summary->failed;
      p.failures.push_back(fmt::format("{} ({}): {}", name, run.id, o.record->error));
      p.last_line = fmt::format("FAILED {}", name);
    }
  }
}

// One run: claimed in the store first (another bench run on the same store may hold it), then
// a result kept from an earlier attempt is stored, or the run is made and its result stored
// (kept in its folder while the store stays locked); the claim goes when it is done.
Outcome TakeRun(const RunSpec& run, ResultsStore& store, const PipelineOptions& pipeline,
                int series_points, const std::function<void(const std::string&)>& on_stage) {
  using Kind = Outcome::Kind;
  const StoreWait wait;
  ClaimResult claim = ClaimResult::kTaken;
  // A run's time limit (and some) after it was claimed, its claim from another host is stale.
  const double max_age = run.resources.minutes * 60 + 600;
  if (!RetryWhileBusy([&] { claim = store.Claim(run.id, max_age); }, wait, &g_cancel))
    return {.kind = Kind::kLockedOut};
  if (claim == ClaimResult::kTaken) return {.kind = Kind::kTaken};
  if (claim == ClaimResult::kStored) return {.kind = Kind::kStoredElsewhere};
  Outcome o;
  const fs::path dir = pipeline.runs_dir / run.id;
  o.record = ReadKeptRecord(dir, run.id);
  if (o.record) {
    fmt::print(stderr, "bench: run {}: storing the result kept in {} (not run again)\n", run.id,
               (dir / kKeptRecordName).string());
  } else {
    o.record = ExecuteRun(run, pipeline, on_stage);
  }
  if (o.record && series_points > 0) ThinSeries(&*o.record, series_points);
  if (o.record) o.stored = StoreOrKeep(store, *o.record, dir, wait, &g_cancel);
  try {
    store.Release(run.id);
  } catch (const Error& e) {  // a claim left behind is taken over once this process is gone
    spdlog::warn("bench: run {}: claim not released: {}", run.id, e.what());
  }
  return o;
}

// One worker: takes runs off the queue until it is empty or the harness is stopped, runs each
// and stores its record.
void Work(Progress& p, ResultsStore& store, const PipelineOptions& pipeline) {
  for (;;) {
    const RunSpec* run = nullptr;
    {
      std::lock_guard lock(p.mutex);
      if (p.queue.empty() || g_cancel) return;
      run = p.queue.front();
      p.queue.pop_front();
      p.units_left -= WorkUnits(*run);
      p.running[run->id] = {run, "prepare", std::chrono::steady_clock::now()};
    }
    Outcome outcome;
    try {
      outcome = TakeRun(*run, store, pipeline, p.series_points, [&](const std::string& s) {
        std::lock_guard lock(p.mutex);
        p.running[run->id].stage = s;
      });
    } catch (const std::exception& e) {
      outcome.error = e.what();
    }
    std::lock_guard lock(p.mutex);
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - p.running[run->id].start)
            .count();
    p.running.erase(run->id);
    Finished(p, *run, outcome, took);
    p.changed.notify_all();
  }
}

// The progress line (called under the mutex), with an ETA from the seconds per budget unit so
// far, over what is left and what is still running.
std::string ProgressLine(const Progress& p, int jobs, std::chrono::steady_clock::time_point start) {
  const int finished = p.summary->done + p.summary->failed;
  std::string eta = "?";
  if (p.units_done > 0) {
    const double rate = p.seconds_done / p.units_done;
    double left = p.units_left * rate;
    const auto now = std::chrono::steady_clock::now();
    for (const auto& [id, r] : p.running)
      left += std::max(
          0.0, WorkUnits(*r.run) * rate - std::chrono::duration<double>(now - r.start).count());
    eta = Duration(left / jobs);
  }
  return fmt::format(
      "bench: {} done ({} failed), {} running, {} left, elapsed {}, ETA {}{}", finished,
      p.summary->failed, p.running.size(), p.queue.size(),
      Duration(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()),
      eta, p.last_line.empty() ? "" : "; last: " + p.last_line);
}

// Shows progress until every run has ended (or the harness is stopped and the running ones
// have): rewritten in place on a terminal; else a line per finished run, or a minute.
void ShowProgress(Progress& p, int jobs, std::chrono::steady_clock::time_point start) {
  const bool tty = isatty(fileno(stderr));
  auto last_print = std::chrono::steady_clock::now() - std::chrono::hours(1);
  int last_finished = -1;
  for (;;) {
    std::unique_lock lock(p.mutex);
    p.changed.wait_for(lock, std::chrono::seconds(1));
    const bool all_done = p.running.empty() && (p.queue.empty() || g_cancel);
    const int finished = p.summary->done + p.summary->failed;
    const std::string line = ProgressLine(p, jobs, start);
    const auto now = std::chrono::steady_clock::now();
    if (tty) {
      fmt::print(stderr, "\r\033[K{}", line);
      if (all_done) fmt::print(stderr, "\n");
    } else if (finished != last_finished || now - last_print > std::chrono::seconds(60) ||
               all_done) {
      fmt::print(stderr, "{}\n", line);
      last_print = now;
      last_finished = finished;
    }
    if (all_done) break;
  }
}

// Runs left to another bench run on the same store, and finished runs the store could not take
// (kept in their folders): said, and the latter are an error the next run resolves.
void ReportUnstored(const Progress& p, const RunnerSummary& summary, const fs::path& store,
                    const fs::path& runs_dir) {
  if (summary.taken > 0) {
    fmt::print(stderr, "bench: {} run(s) were being made by another bench run on {}; left to it\n",
               summary.taken, store.string());
  }
  for (const std::string& k : p.kept) fmt::print(stderr, "bench: not stored (kept): {}\n", k);
  if (p.fatal.empty() && (summary.kept > 0 || summary.locked_out > 0)) {
    Fail("bench run: {} stayed locked by another program: {} finished run(s) are kept in "
         "{}/<run id>/{} and {} run(s) were not started; the same command stores the kept "
         "ones without running them again (or `hdr4d bench collect {} --store {}`)",
         store.string(), summary.kept, runs_dir.string(), kKeptRecordName, summary.locked_out,
         runs_dir.string(), store.string());
  }
}

}  // namespace

void ApplyFilter(const SuiteFilter& f, Suite* suite) {
  if (!f.scenes.empty()) {
    std::vector<SceneSpec> kept;
    for (const std::string& name : f.scenes) {
      const SceneSpec* s = suite->FindScene(name);
      if (!s) Fail("{}: no scene '{}' in suite '{}'", suite->file.string(), name, suite->name);
      kept.push_back(*s);
    }
    suite->scenes = kept;
  }
  if (!f.methods.empty()) {
    std::vector<MethodSpec> kept;
    for (const std::string& name : f.methods) {
      const MethodSpec* m = suite->FindMethod(name);
      if (!m) Fail("{}: no method '{}' in suite '{}'", suite->file.string(), name, suite->name);
      kept.push_back(*m);
    }
    suite->methods = kept;
  }
  if (!f.seeds.empty()) {
    // As --scenes and --methods: a seed the suite does not list is a mistake (its runs were
    // stored, then outside every table of the suite).
    for (const std::int64_t seed : f.seeds)
      if (std::find(suite->seeds.begin(), suite->seeds.end(), seed) == suite->seeds.end())
        Fail("{}: --seeds {}: not a seed of suite '{}' (its seeds: {})", suite->file.string(),
             seed, suite->name, fmt::join(suite->seeds, ", "));
    suite->seeds = f.seeds;
  }
  if (f.iterations > 0) suite->budgets = {Budget{.iterations = f.iterations}};
}

std::vector<PreparedScene> PrepareScenes(const Suite& suite,
                                         const fs::path& cache,
                                         bool verbose,
                                         bool generate) {
  std::vector<PreparedScene> scenes;
  const SceneCacheOptions options{
      .cache_dir = cache, .hdr4d = SelfExecutable(), .verbose = verbose, .generate = generate};
  for (const SceneSpec& s : suite.scenes) scenes.push_back(PrepareScene(s, options));
  return scenes;
}

// --any-code-version: the store's ok runs by their identity without the code version.
std::map<std::string, std::string> StoredByIdentityKey(const ResultsStore& store) {
  std::map<std::string, std::string> out;
  for (const std::string& id : store.RunIds("ok")) {
    const nlohmann::json config = store.Config(id);
    if (config.is_object() && config.contains("identity"))
      out.emplace(IdentityKeyWithoutVersion(config["identity"]), id);
  }
  return out;
}

// The runs to take, in plan order: not stored (by this code version, or by any with
// any_code_version), not failed before unless retried, at most max_runs of them. A stored run's
// labels are pointed at it (this suite's names for a run made before; a dry run writes nothing).
void QueueRuns(const std::vector<RunSpec>& runs, const RunnerOptions& options,
               const std::set<std::string>& ok, const std::set<std::string>& failed,
               const std::map<std::string, std::string>& other_versions, ResultsStore* store,
               Progress* p) {
  RunnerSummary& summary = *p->summary;
  for (const RunSpec& r : runs) {
    if (ok.count(r.id) || (failed.count(r.id) && !options.retry_failed)) {
      if (!options.dry_run) store->AddLabels(r.id, r.labels);
      ++(ok.count(r.id) ? summary.already_done : summary.skipped_failed);
      continue;
    }
    if (const auto it = other_versions.find(IdentityKeyWithoutVersion(r.identity));
        it != other_versions.end()) {
      if (!options.dry_run) store->AddLabels(it->second, r.labels);
      ++summary.already_done;
      ++summary.stored_other_version;
      continue;
    }
    if (options.max_runs > 0 && static_cast<int>(p->queue.size()) >= options.max_runs) {
      ++summary.left_by_max;
      continue;
    }
    p->queue.push_back(&r);
  }
}

RunnerSummary RunSuite(const Suite& suite, const RunnerOptions& options) {
  if (options.jobs < 1) Fail("bench run: --jobs must be at least 1");
  if (options.max_runs < 0) Fail("bench run: --max-runs must be >= 0 (0: every run)");
  if (options.series_points < 0 || options.series_points == 1)
    Fail("bench run: --series-points must be 0 (every point) or at least 2");
  if (options.threads < 0) Fail("bench run: --threads must be >= 0");
  const fs::path cache = options.cache_dir.empty() ? DefaultCacheDir() : options.cache_dir;
  const fs::path runs_dir =
      options.runs_dir.empty() ? fs::path(options.store.string() + ".runs") : options.runs_dir;
  StopSignals signals;
  // A dry run reads the store when there is one; it creates none (issue 51, case 18).
  std::optional<ResultsStore> store;
  if (!options.dry_run || fs::exists(options.store)) store.emplace(options.store, !options.dry_run);
  // A dry run lists; it does not render scenes that are not in the cache yet.
  const std::vector<PreparedScene> scenes =
      PrepareScenes(suite, cache, true, /*generate=*/!options.dry_run);
  const std::vector<RunSpec> runs = PlanRuns(suite, scenes, CodeVersion());

  RunnerSummary summary;
  summary.planned = static_cast<int>(runs.size());
  Progress p;
  p.summary = &summary;
  p.series_points = options.series_points;
  const std::set<std::string> ok = store ? store->RunIds("ok") : std::set<std::string>{},
                              failed = store ? store->RunIds("failed") : std::set<std::string>{};
  std::map<std::string, std::string> other_versions;  // identity without version -> stored id
  if (options.any_code_version && store) other_versions = StoredByIdentityKey(*store);
  QueueRuns(runs, options, ok, failed, other_versions, store ? &*store : nullptr, &p);
  const int threads =
      options.threads > 0 ? options.threads : std::max(1, AvailableCores() / options.jobs);
  fmt::print(stderr,
             "bench: suite '{}': {} runs, {} already in the store{}{}{}, {} to run ({} job{} x {} "
             "thread{}); store {}\n",
             suite.name, runs.size(), summary.already_done,
             summary.stored_other_version
                 ? fmt::format(" ({} by another code version)", summary.stored_other_version)
                 : "",
             summary.skipped_failed ? fmt::format(", {} failed before (--retry-failed redoes them)",
                                                  summary.skipped_failed)
                                    : "",
             summary.left_by_max
                 ? fmt::format(", {} left for later (--max-runs {})", summary.left_by_max,
                               options.max_runs)
                 : "",
             p.queue.size(), options.jobs, options.jobs == 1 ? "" : "s", threads,
             threads == 1 ? "" : "s", options.store.string());
  if (options.dry_run) {
    PrintDryRun(scenes, runs, ok, failed, other_versions);
    return summary;
  }
  if (p.queue.empty()) return summary;

  for (const RunSpec* r : p.queue) p.units_left += WorkUnits(*r);
  const auto start = std::chrono::steady_clock::now();
  const PipelineOptions pipeline{.runs_dir = runs_dir,
                                 .hdr4d = SelfExecutable(),
                                 .threads = threads,
                                 .cancel = &g_cancel,
                                 .keep_checkpoint = options.keep_checkpoints};
  std::vector<std::thread> workers;
  for (int j = 0; j < options.jobs; ++j) workers.emplace_back([&] { Work(p, *store, pipeline); });
  ShowProgress(p, options.jobs, start);
  for (std::thread& w : workers) w.join();
  for (const std::string& f : p.failures) fmt::print(stderr, "bench: failed: {}\n", f);
  ReportUnstored(p, summary, options.store, runs_dir);
  if (!p.fatal.empty()) Fail("bench run stopped: {}", p.fatal);
  summary.interrupted = g_signal != 0;
  if (summary.interrupted) {
    Fail(
        "bench run interrupted by signal {}: {} finished runs are in {}; the unfinished ones "
        "resume when the same command runs again",
        g_signal.load(), summary.done + summary.failed, options.store.string());
  }
  return summary;
}

}  // namespace hdr4d::bench
