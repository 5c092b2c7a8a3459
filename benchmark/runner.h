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
  // At most this many of the runs not stored yet, in plan order (0: all): a suite run a few
  // runs at a time (scripts/bench-campaign.sh).
  int max_runs = 0;
  // A run counts as stored when the store has it from another code version: an ok run whose
  // identity is the same but for the code version (IdentityKeyWithoutVersion). For a suite run
  // over several sessions, whose code changes in between; the report lists the versions.
  bool any_code_version = false;
  // Each curve (loss, training PSNR, tone curves) stored at most this many points (0: as
  // made; ThinSeries): a store committed with the repository (benchmark/results/).
  int series_points = 0;
};

struct RunnerSummary {
  int planned = 0, already_done = 0, done = 0, failed = 0, skipped_failed = 0;
  // stored_other_version: counted in already_done, stored by another code version
  // (any_code_version); left_by_max: not started because of max_runs.
  int stored_other_version = 0, left_by_max = 0;
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
