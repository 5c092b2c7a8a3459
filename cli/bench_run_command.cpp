// `hdr4d bench run SUITE --store FILE`: every run of a suite not stored yet (benchmark/runner.h).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "benchmark/runner.h"
#include "benchmark/suite.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/util/error.h"

namespace hdr4d::cli {

void AddBenchRun(CLI::App& bench) {
  struct Args {
    std::string suite, store;
    bench::RunnerOptions runner;
    bench::SuiteFilter filter;
    std::string runs_dir, cache;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "run",
      "Run a suite into a results store: every method x scene x supervision x seed x budget x "
      "variant not already there (same configuration, code version and data), --jobs at a time; "
      "each finished run is stored at once, so an interrupted suite resumes where it stopped.");
  cmd->add_option("SUITE", a->suite, "Suite file, or a shipped suite: ci, paper, speed, ...")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store (SQLite file; created if missing)")->required()
      ->check(Text("a results store"));
  cmd->add_option("--jobs,-j", a->runner.jobs, "Runs at once (the cores are divided between them)")
      ->capture_default_str()
      ->check(Integer(1, 1024));
  cmd->add_option("--threads", a->runner.threads, "Threads per run (0: cores / jobs)")->capture_default_str()
      ->check(Integer(0, 4096));
  cmd->add_option("--cache", a->cache, "Where generated scenes are kept (default $HDR4D_CACHE or ~/.cache/hdr4d)")
      ->check(Text("a scene cache folder"));
  cmd->add_option("--runs-dir", a->runs_dir, "Work folders of the runs (default STORE.runs)")
      ->check(Text("a folder"));
  cmd->add_flag("--retry-failed", a->runner.retry_failed, "Run again the runs that failed before");
  cmd->add_flag("--keep-checkpoints", a->runner.keep_checkpoints,
                "Keep each run's checkpoint.bin (renders and curves are always kept)");
  cmd->add_flag("--dry-run", a->runner.dry_run, "List the runs and whether they are stored; run nothing");
  cmd->add_option("--max-runs", a->runner.max_runs,
                  "Run at most this many of the runs not stored yet, in the suite's order, then "
                  "stop (0: all; a long suite a few runs at a time, scripts/bench-campaign.sh)")
      ->capture_default_str()
      ->check(Integer(0, std::numeric_limits<int>::max()));
  cmd->add_option("--series-points", a->runner.series_points,
                  "Store each curve (loss, training PSNR, tone curves) at most this many points "
                  "(0: every point; a store small enough to commit, benchmark/results/)")
      ->capture_default_str()
      ->check(Integer(0, std::numeric_limits<int>::max()));
  cmd->add_flag("--any-code-version", a->runner.any_code_version,
                "Count a run as stored when the store has it from another code version (same "
                "configuration and data): a suite run over several sessions whose code changes "
                "in between; the report lists the code versions");
  cmd->add_option("--scenes", a->filter.scenes, "Only these scenes (a reduced pass)")->delimiter(',')
      ->check(Text("a scene name"));
  cmd->add_option("--methods", a->filter.methods, "Only these methods")->delimiter(',')
      ->check(Text("a method name"));
  cmd->add_option("--seeds", a->filter.seeds, "Only these seeds")->delimiter(',')
      ->check(Integer(0, std::numeric_limits<std::int64_t>::max()));
  cmd->add_option("--iterations", a->filter.iterations,
                  "Replace the suite's budgets by one of this many iterations")
      ->check(Integer(1));
  cmd->callback([a] {
    bench::Suite suite = bench::LoadSuite(a->suite);
    if (a->filter.iterations > 0) {  // a shortened pass says so (the first paper pass ran 300)
      std::vector<std::string> budgets;
      for (const bench::Budget& b : suite.budgets) budgets.push_back(b.Label());
      fmt::print(stderr,
                 "bench run: --iterations {} replaces suite '{}''s budget ({}): the runs are "
                 "labelled {}it, and `bench table` shows them with --budget {}it\n",
                 a->filter.iterations, suite.name, fmt::join(budgets, ", "), a->filter.iterations,
                 a->filter.iterations);
    }
    bench::ApplyFilter(a->filter, &suite);
    a->runner.store = a->store;
    a->runner.runs_dir = a->runs_dir;
    a->runner.cache_dir = a->cache;
    const bench::RunnerSummary s = bench::RunSuite(suite, a->runner);
    if (a->runner.dry_run) return;
    fmt::print("bench run: suite '{}': {} runs planned, {} were stored already, {} done now, {} "
               "failed{}{}\n",
               suite.name, s.planned, s.already_done, s.done, s.failed,
               s.skipped_failed ? fmt::format(" ({} earlier failures not retried)", s.skipped_failed) : "",
               s.taken ? fmt::format(", {} left to another bench run on the store", s.taken) : "");
    if (s.failed > 0)
      Fail("bench run: {} of {} runs failed (listed above; their errors are in {})", s.failed,
           s.done + s.failed, a->store);
  });
}

}  // namespace hdr4d::cli
