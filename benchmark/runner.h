// `hdr4d bench run SUITE --store FILE`: prepares the suite's scenes, plans its runs, skips the
// ones the store already has (same identity), and runs the rest, --jobs at a time with the
// cores divided between them, showing runs done / running / left and an ETA. Each finished run
// is written to the store in one transaction as soon as it ends, so an interrupted suite loses
// only the runs in progress (their folders stay, and training resumes from its last
// checkpoint next time). Each run is claimed in the store before it starts, so two harnesses on
// one store share its runs instead of making the same ones in the same folders; a result the
// store cannot take (locked by another program) is kept in the run's folder and stored later.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "benchmark/run_plan.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {

// Narrows a suite to a quick pass (a reduced paper run): only these scenes, methods and seeds,
// and one budget of this many iterations. Empty / 0 keeps the suite's. Throws hdr4d::Error
// naming an unknown scene or method.
struct SuiteFilter {
  std::vector<std::string> scenes, methods;
  std::vector<std::int64_t> seeds;
  std::int64_t iterations = 0;
};
void ApplyFilter(const SuiteFilter& filter, Suite* suite);

struct RunnerOptions {
  std::filesystem::path store;
  std::filesystem::path runs_dir;   // default: <store>.runs
  std::filesystem::path cache_dir;  // default: DefaultCacheDir()
  int jobs = 1;
  int threads = 0;  // per job; 0 = the available cores divided by jobs (at least 1)
  bool retry_failed = false;
  bool keep_checkpoints = false;
  bool dry_run = false;  // print the plan, run nothing
};

struct RunnerSummary {
  int planned = 0, already_done = 0, done = 0, failed = 0, skipped_failed = 0;
  // taken: claimed by another bench run on the same store (left to it); kept: finished, but the
  // store stayed locked (the record is kept in the run's folder); locked_out: not started, the
  // store stayed locked when it was to be claimed.
  int taken = 0, kept = 0, locked_out = 0;
  bool interrupted = false;
};

// Prepares every scene of the suite (generating into the cache; with generate off, a scene not
// in the cache is returned not ready instead).
std::vector<PreparedScene> PrepareScenes(const Suite& suite, const std::filesystem::path& cache,
                                         bool verbose, bool generate = true);

RunnerSummary RunSuite(const Suite& suite, const RunnerOptions& options);

}  // namespace hdr4d::bench
