// Scale-out with Slurm. `hdr4d bench slurm SUITE --out DIR` prepares the suite's scenes (into a
// cache every node can read), plans its runs and writes:
//   DIR/plan.json           every run: identity, labels, arguments, scene, resources
//   DIR/array_<k>.sbatch    one job array per distinct resource request (cpus, memory, time):
//                           task i runs `hdr4d bench task DIR --array k --index i`
//   DIR/submit.sh           sbatch of every array
// Each task writes DIR/results/<run id>.json (a RunRecord, written atomically; a task whose
// result exists does nothing), and `hdr4d bench collect DIR --store FILE` merges them into the
// store, one transaction per run, reporting corrupt files and runs without a result.
#pragma once

#include <filesystem>
#include <string>

#include "benchmark/runner.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {

struct SlurmOptions {
  std::filesystem::path out;
  std::filesystem::path cache_dir;  // default: DefaultCacheDir() (must be shared by the nodes)
  std::filesystem::path store;      // optional: leave out runs this store already has
  std::string partition, account;
  int max_parallel = 0;  // %N throttle of each array (0 = none)
};

struct SlurmPlan {
  int runs = 0, arrays = 0, skipped = 0;
};

SlurmPlan WriteSlurmJobs(const Suite& suite, const SlurmOptions& options);

// One task of an array (what the sbatch script runs). Threads: $SLURM_CPUS_PER_TASK, else the
// run's cpus. Returns false when the run failed (its record is written all the same).
bool RunSlurmTask(const std::filesystem::path& dir, int array, int index);

struct CollectSummary {
  int merged = 0, already = 0, failed_runs = 0, bad_files = 0, missing = 0;
};
// Merges every DIR/results/*.json; throws hdr4d::Error naming the bad files (after merging the
// good ones) when any cannot be read.
CollectSummary Collect(const std::filesystem::path& dir, const std::filesystem::path& store);

}  // namespace hdr4d::bench
