// `hdr4d bench report SUITE --store FILE --out PAGE.html`: one self-contained page
// (benchmark/report.h).
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "benchmark/report.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"

namespace hdr4d::cli {

void AddBenchReport(CLI::App& bench) {
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
      "the stress suite's table. Every method of the store has its rows and renders, submissions "
      "(bench submit) marked external.");
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
  cmd->add_option("--methods", a->options.tables.methods,
                  "Only these rows and their renders: method names or row labels, comma-separated "
                  "(as bench table --methods)")
      ->delimiter(',')
      ->check(Text("a method name or row label"));
  auto hdr_keys = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--hdr-keys", *hdr_keys, "Two metric keys (PSNR,SSIM) for the tables' HDR columns")
      ->delimiter(',')
      ->expected(2)
      ->check(Text("a metric key"));
  cmd->callback([a, hdr_keys, cmd] {
    if (hdr_keys->size() == 2)
      a->options.tables.hdr_psnr_key = (*hdr_keys)[0], a->options.tables.hdr_ssim_key = (*hdr_keys)[1];
    const bench::Suite suite = bench::LoadSuite(a->suite);
    a->options.tables.protocol = bench::ParseHdrProtocol(a->protocol);
    const bench::ResultsStore store(a->store, /*create=*/false);
    // A given key the runs lack charted nothing (rc 0); the default may be absent (LDR runs).
    if (cmd->count("--metric") > 0)
      bench::RequireMetricKey("--metric", a->options.pareto_metric,
                              bench::MetricKeys(bench::SuiteRuns(store, suite)),
                              "runs of suite '" + suite.name + "'");
    const bench::ReportSummary s = bench::WriteReport(suite, store, a->options);
    fmt::print("bench report: {} ({} tables, {} images, {} scenes, {} stress cases)\n",
               a->options.out.string(), s.tables, s.images, s.scenes, s.stress_cases);
  });
}

}  // namespace hdr4d::cli
