// `hdr4d bench`: the leaderboard harness (benchmark/). Each subcommand parses its options and
// calls the library.
#include <fmt/format.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "benchmark/pareto.h"
#include "benchmark/report.h"
#include "benchmark/results_store.h"
#include "benchmark/runner.h"
#include "benchmark/slurm.h"
#include "benchmark/stress.h"
#include "benchmark/submit.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"
#include "cli/commands.h"
#include "cli/flags.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d::cli {
namespace {
namespace fs = std::filesystem;

void AddRun(CLI::App& bench) {
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
    bench::ApplyFilter(a->filter, &suite);
    a->runner.store = a->store;
    a->runner.runs_dir = a->runs_dir;
    a->runner.cache_dir = a->cache;
    const bench::RunnerSummary s = bench::RunSuite(suite, a->runner);
    if (a->runner.dry_run) return;
    fmt::print("bench run: suite '{}': {} runs planned, {} were stored already, {} done now, {} "
               "failed{}\n",
               suite.name, s.planned, s.already_done, s.done, s.failed,
               s.skipped_failed ? fmt::format(" ({} earlier failures not retried)", s.skipped_failed) : "");
    if (s.failed > 0)
      Fail("bench run: {} of {} runs failed (listed above; their errors are in {})", s.failed,
           s.done + s.failed, a->store);
  });
}

void AddTable(CLI::App& bench) {
  struct Args {
    std::string suite, store, format = "md", out, table, protocol = "own_max";
    bench::TableOptions options;
    bool all_metrics = false, per_scene = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "table",
      "The suite's tables from a results store: the layout of the paper's Tables 1-2 and the "
      "ablation Tables 4-7, means over scenes with the spread over seeds, best per column marked, "
      "and paired tests against each table's reference row. Markdown on stdout, or with --out "
      "every table as .md, .tex and .csv.");
  cmd->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--format", a->format, "md, latex or csv (stdout)")
      ->check(OneOf({"md", "latex", "csv"}))
      ->capture_default_str();
  cmd->add_option("--out", a->out, "Write <id>.md, <id>.tex, <id>.csv for every table into this folder")
      ->check(Text("an output path"));
  cmd->add_option("--table", a->table, "Only this table id")
      ->check(Text("a table id"));
  cmd->add_option("--protocol", a->protocol, "HDR columns: own_max (HDR-4DGS), gt_max (HDR-NeRF) or pu21")
      ->capture_default_str()
      ->check(OneOf({"own_max", "gt_max", "pu21"}));
  cmd->add_option("--budget", a->options.budget, "Budget label (default: the suite's last)")
      ->check(Text("a budget label"));
  cmd->add_option("--variant", a->options.variant, "Variant name (default: the suite's first)")
      ->check(Text("a variant name"));
  auto hdr_keys = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--hdr-keys", *hdr_keys,
                  "Two metric keys (PSNR,SSIM) for the HDR columns instead of --protocol's, e.g. "
                  "metrics added to hdr4d eval later")
      ->delimiter(',')
      ->expected(2)
      ->check(Text("a metric key"));
  cmd->parse_complete_callback([a, hdr_keys] {
    if (hdr_keys->size() == 2) a->options.hdr_psnr_key = (*hdr_keys)[0], a->options.hdr_ssim_key = (*hdr_keys)[1];
  });
  cmd->add_flag("--all-metrics", a->all_metrics, "Also a table of every metric key the runs have");
  cmd->add_flag("--per-scene", a->per_scene, "Also per-scene tables of each quality column");
  cmd->callback([a] {
    const bench::Suite suite = bench::LoadSuite(a->suite);
    a->options.protocol = bench::ParseHdrProtocol(a->protocol);
    const bench::ResultsStore store(a->store, /*create=*/false);
    const std::vector<bench::RunSummary> runs = bench::SuiteRuns(store, suite);
    if (suite.tables.empty()) Fail("{}: the suite defines no tables", suite.file.string());
    if (!a->out.empty()) CheckOutputFolder(a->out);  // never among a dataset's images
    bool found = false;
    std::string md_all;
    for (const bench::TableSpec& spec : suite.tables) {
      if (!a->table.empty() && spec.id != a->table) continue;
      found = true;
      std::vector<bench::Table> tables = {bench::BuildTable(spec, suite, runs, a->options)};
      if (a->all_metrics) tables.push_back(bench::BuildAllMetricsTable(spec, suite, runs, a->options));
      for (const bench::Table& t : tables) {
        const std::string md = bench::ToMarkdown(t) + "\n" + bench::PairedTestsMarkdown(t);
        if (!a->out.empty()) {
          WriteTextFileAtomic(fs::path(a->out) / (t.id + ".md"), md);
          WriteTextFileAtomic(fs::path(a->out) / (t.id + ".tex"), bench::ToLatex(t));
          WriteTextFileAtomic(fs::path(a->out) / (t.id + ".csv"), bench::ToCsv(t));
        }
        if (a->format == "md") fmt::print("{}\n", md);
        if (a->format == "latex") fmt::print("{}\n", bench::ToLatex(t));
        if (a->format == "csv") fmt::print("{}", bench::ToCsv(t));
      }
      if (a->per_scene) {
        const bench::Table main = tables.front();
        for (const bench::Column& c : main.columns) {
          if (!c.quality || !c.computable) continue;
          const std::string md = bench::PerSceneMarkdown(spec, suite, runs, a->options, c);
          if (!a->out.empty()) WriteTextFileAtomic(fs::path(a->out) / (spec.id + "-" + c.key + "-per-scene.md"), md);
          if (a->format == "md") fmt::print("{}\n", md);
        }
      }
    }
    if (!found) Fail("{}: no table '{}'", suite.file.string(), a->table);
  });
}

void AddPareto(CLI::App& bench) {
  struct Args {
    std::string suite, store;
    bench::ParetoOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "pareto",
      "Run time against error: every configuration (method x supervision x variant x budget, "
      "mean over seeds) as training time and render time per frame against a quality metric, "
      "per scene and over all scenes, with the Pareto front; PNG and SVG charts and pareto.csv.");
  cmd->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--out", a->options.out, "Output folder")->required()
      ->check(Text("an output path"));
  cmd->add_option("--metric", a->options.metric, "Quality metric key (higher is better)")
      ->capture_default_str()
      ->check(Text("a metric key"));
  cmd->callback([a] {
    const bench::Suite suite = bench::LoadSuite(a->suite);
    const bench::ResultsStore store(a->store, /*create=*/false);
    const auto charts = bench::WritePareto(bench::SuiteRuns(store, suite), suite, a->options);
    fmt::print("bench pareto: {} charts (PNG and SVG) and pareto.csv in {}\n", charts.size(),
               a->options.out.string());
  });
}

void AddReport(CLI::App& bench) {
  struct Args {
    std::string suite, store, protocol = "own_max";
    bench::ReportOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "report",
      "One self-contained HTML page: the suite's tables and paired tests, run time against "
      "error, per scene the renders of every method beside the ground truth with error maps, "
      "learned tone curves over time, the temporal luminance of a region, training curves, and "
      "the stress suite's table.");
  cmd->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--out", a->options.out, "The HTML file to write")->required()
      ->check(Text("an output path"));
  cmd->add_option("--protocol", a->protocol, "HDR columns: own_max, gt_max or pu21")->capture_default_str()
      ->check(OneOf({"own_max", "gt_max", "pu21"}));
  cmd->add_option("--budget", a->options.tables.budget, "Budget label of the tables (default: the suite's last)")
      ->check(Text("a budget label"));
  cmd->add_option("--metric", a->options.pareto_metric, "Quality metric of the time charts")->capture_default_str()
      ->check(Text("a metric key"));
  auto hdr_keys = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--hdr-keys", *hdr_keys, "Two metric keys (PSNR,SSIM) for the tables' HDR columns")
      ->delimiter(',')
      ->expected(2)
      ->check(Text("a metric key"));
  cmd->callback([a, hdr_keys] {
    if (hdr_keys->size() == 2)
      a->options.tables.hdr_psnr_key = (*hdr_keys)[0], a->options.tables.hdr_ssim_key = (*hdr_keys)[1];
    const bench::Suite suite = bench::LoadSuite(a->suite);
    a->options.tables.protocol = bench::ParseHdrProtocol(a->protocol);
    const bench::ResultsStore store(a->store, /*create=*/false);
    const bench::ReportSummary s = bench::WriteReport(suite, store, a->options);
    fmt::print("bench report: {} ({} tables, {} images, {} scenes, {} stress cases)\n",
               a->options.out.string(), s.tables, s.images, s.scenes, s.stress_cases);
  });
}

void AddStress(CLI::App& bench) {
  auto options = std::make_shared<bench::StressOptions>();
  auto list = std::make_shared<bool>(false);
  CLI::App* cmd = bench.add_subcommand(
      "stress",
      "Numerical stability and failure behaviour: trains and renders under extreme exposures and "
      "radiance, near-degenerate Gaussians, single-timestamp/-exposure/-camera scenes, corrupt "
      "inputs, killed and resumed runs and a corrupt checkpoint; reports per case what held (no "
      "crash, no NaN, a clear error, nothing lost). Exit code 1 when a case failed.");
  cmd->add_option("--out", options->work, "Work folder of the cases")
      ->check(Text("an output path"));
  cmd->add_option("--store", options->store, "Also write the outcomes to this results store (for the report)")
      ->check(Text("a results store"));
  cmd->add_option("--case", options->cases, "Only these cases")->delimiter(',')
      ->check(Text("a stress case name"));
  cmd->add_option("--threads", options->threads, "Threads per training (0 = all cores)")->capture_default_str()
      ->check(Integer(0, 4096));
  cmd->add_flag("--list", *list, "List the cases");
  cmd->callback([options, list] {
    if (*list) {
      for (const auto& c : bench::StressCaseList())
        fmt::print("{:<30} {:<26} {}\n", c.name, c.category, c.description);
      return;
    }
    if (options->work.empty()) Fail("bench stress: --out is required");
    const auto outcomes = bench::RunStress(*options);
    int failed = 0;
    for (const auto& o : outcomes) failed += o.outcome != "held";
    fmt::print("bench stress: {} of {} cases held\n", outcomes.size() - failed, outcomes.size());
    if (failed) Fail("bench stress: {} case(s) failed (listed above)", failed);
  });
}

void AddSubmit(CLI::App& bench) {
  auto o = std::make_shared<bench::SubmitOptions>();
  CLI::App* cmd = bench.add_subcommand(
      "submit",
      "Score a folder of renders from any method (named like the ground truth: each test "
      "frame's file_path as PNG, its exr_file_path as EXR) into the store, so external methods "
      "sit in the same tables. Missing or extra frames, wrong sizes and NaN pixels are errors; "
      "a submission never changes another run's rows.");
  cmd->add_option("--store", o->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--method", o->method, "Method name in the tables")->required()
      ->check(Text("a method name"));
  cmd->add_option("--scene", o->scene, "Dataset folder, or a scene name of --suite")->required()
      ->check(Text("a dataset folder or scene name"));
  cmd->add_option("--renders", o->renders, "Folder of renders")->required()
      ->check(Text("a folder of renders"));
  cmd->add_option("--suite", o->suite, "Suite whose tables the submission joins (and whose scene --scene names)")
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--meta", o->meta, "JSON with train_seconds, render_fps, gaussians, peak_rss_mb, iterations, code_version, machine, notes")
      ->check(Text("a JSON file"));
  cmd->add_option("--supervision", o->supervision, "ldr, hdr or ldr+hdr")->capture_default_str()
      ->check(OneOf({"ldr", "hdr", "ldr+hdr"}));
  cmd->add_option("--seed", o->seed, "Seed of the submitted run")->capture_default_str()
      ->check(Integer(0, std::numeric_limits<std::int64_t>::max()));
  cmd->add_option("--cache", o->cache_dir, "Scene cache (for suite scenes)")
      ->check(Text("a scene cache folder"));
  cmd->add_flag("--replace", o->replace, "Replace an earlier submission of this method, scene, supervision and seed");
  cmd->callback([o] {
    const bench::RunRecord r = bench::Submit(*o);
    fmt::print("bench submit: {} on {}: {} frames scored, stored as run {}\n", o->method,
               r.labels.front().scene, r.frames.size(), r.id);
  });
}

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

void AddBenchCommand(CLI::App& app) {
  CLI::App* bench = app.add_subcommand(
      "bench",
      "The benchmark harness: run suites of methods x scenes x settings x seeds into a results "
      "store, print the paper's tables, plot run time against error, write an HTML report, "
      "stress-test numerics, score external renders, scale out with Slurm.");
  bench->require_subcommand(1);
  AddRun(*bench);
  AddTable(*bench);
  AddPareto(*bench);
  AddReport(*bench);
  AddStress(*bench);
  AddSubmit(*bench);
  AddSlurm(*bench);
}

}  // namespace hdr4d::cli
