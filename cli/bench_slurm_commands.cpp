// `hdr4d bench slurm`, `bench task` and `bench collect`: a suite as Slurm job arrays, one task
// of them, and their results merged into a store (benchmark/slurm.h).
#include <fmt/format.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "benchmark/slurm.h"
#include "benchmark/suite.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"

namespace hdr4d::cli {

namespace {

void AddSlurm(CLI::App& bench) {
  struct Args {
    std::string suite;
    bench::SlurmOptions options;
    bench::SuiteFilter filter;
  };
  auto a = std::make_shared<Args>();
  CLI::App* slurm = bench.add_subcommand(
      "slurm",
      "Write a Slurm job array per resource request (one task per run) for a suite: "
      "OUT/array_<k>.sbatch, OUT/submit.sh, OUT/plan.json. Tasks write OUT/results/<run>.json; "
      "`hdr4d bench collect OUT --store FILE` merges them.");
  slurm->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  slurm->add_option("--out", a->options.out, "Job folder (on a file system every node sees)")->required()
      ->check(Text("an output path"));
  slurm->add_option("--cache", a->options.cache_dir, "Scene cache every node can read")
      ->check(Text("a scene cache folder"));
  slurm->add_option("--store", a->options.store, "Leave out runs this store already has")
      ->check(Text("a results store"));
  slurm->add_option("--partition", a->options.partition, "Slurm partition")
      ->check(Text("a Slurm partition"));
  slurm->add_option("--account", a->options.account, "Slurm account")
      ->check(Text("a Slurm account"));
  slurm->add_option("--max-parallel", a->options.max_parallel, "Tasks of an array at once (0 = no limit)")
      ->check(Integer(0, 1000000));
  slurm->add_option("--scenes", a->filter.scenes, "Only these scenes")->delimiter(',')
      ->check(Text("a scene name"));
  slurm->add_option("--methods", a->filter.methods, "Only these methods")->delimiter(',')
      ->check(Text("a method name"));
  slurm->add_option("--seeds", a->filter.seeds, "Only these seeds")->delimiter(',')
      ->check(Integer(0, std::numeric_limits<std::int64_t>::max()));
  slurm->add_option("--iterations", a->filter.iterations, "One budget of this many iterations")
      ->check(Integer(1));
  slurm->callback([a] {
    bench::Suite suite = bench::LoadSuite(a->suite);
    bench::ApplyFilter(a->filter, &suite);
    const bench::SlurmPlan p = bench::WriteSlurmJobs(suite, a->options);
    fmt::print("bench slurm: {} runs in {} job array(s) ({} already in the store); submit with {}/submit.sh\n",
               p.runs, p.arrays, p.skipped, a->options.out.string());
  });
}

void AddTask(CLI::App& bench) {
  struct TaskArgs {
    std::string dir;
    int array = 0, index = -1;
  };
  auto t = std::make_shared<TaskArgs>();
  CLI::App* task = bench.add_subcommand("task", "One task of a `bench slurm` job array (what its sbatch script runs)");
  task->add_option("DIR", t->dir, "Job folder")->required()
      ->check(Text("a job folder"));
  task->add_option("--array", t->array, "Array number")->required()
      ->check(Integer(0, 1000000));
  task->add_option("--index", t->index, "Task index ($SLURM_ARRAY_TASK_ID)")->required()
      ->check(Integer(0, 100000000));
  task->callback([t] {
    if (!bench::RunSlurmTask(t->dir, t->array, t->index))
      throw CLI::RuntimeError(1);  // the error line is printed and the record written
  });
}

void AddCollect(CLI::App& bench) {
  struct CollectArgs {
    std::string dir, store;
  };
  auto c = std::make_shared<CollectArgs>();
  CLI::App* collect = bench.add_subcommand("collect", "Merge the result files of a `bench slurm` job folder into a store");
  collect->add_option("DIR", c->dir, "Job folder")->required()
      ->check(Text("a job folder"));
  collect->add_option("--store", c->store, "Results store")->required()
      ->check(Text("a results store"));
  collect->callback([c] {
    const bench::CollectSummary s = bench::Collect(c->dir, c->store);
    fmt::print("bench collect: {} runs merged, {} failed runs merged, {} already in the store, {} "
               "planned runs without a result yet\n",
               s.merged, s.failed_runs, s.already, s.missing);
  });
}

}  // namespace

void AddBenchSlurm(CLI::App& bench) {
  AddSlurm(bench);
  AddTask(bench);
  AddCollect(bench);
}

}  // namespace hdr4d::cli
