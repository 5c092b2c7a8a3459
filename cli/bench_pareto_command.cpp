// `hdr4d bench pareto SUITE --store FILE --out DIR`: run time against error (benchmark/pareto.h).
#include <fmt/format.h>

#include <memory>
#include <string>

#include "benchmark/pareto.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"

namespace hdr4d::cli {

void AddBenchPareto(CLI::App& bench) {
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

}  // namespace hdr4d::cli
