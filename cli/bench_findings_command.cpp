// `hdr4d bench findings SUITE --store FILE`: the paper's findings as verdicts per ablation table
// and pipeline, with a chart per table (benchmark/findings.h).
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "benchmark/findings.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/files/atomic_file.h"
#include "core/files/output_guard.h"
#include "core/viz/plot.h"

namespace hdr4d::cli {
namespace {

// findings.md, findings.csv and <table>-<metric>.svg / .png per finding into `out`.
void WriteFindingsFolder(const std::filesystem::path& out, const bench::Suite& suite,
                         const std::vector<bench::RunSummary>& runs,
                         const std::vector<bench::Finding>& findings,
                         const bench::FindingsOptions& options) {
  CheckOutputFolder(out);
  std::filesystem::create_directories(out);
  WriteTextFileAtomic(out / "findings.md", bench::FindingsMarkdown(findings));
  WriteTextFileAtomic(out / "findings.csv", bench::FindingsCsv(findings));
  for (const bench::Finding& f : findings) {
    const PlotPanel chart = bench::FindingChart(suite, runs, f, options);
    if (chart.first.empty()) continue;  // no row has a value: nothing to draw
    const std::string stem = fmt::format("{}-{}", f.table_id, f.metric);
    WritePlot(out / (stem + ".svg"), chart.first, chart.second);
    WritePlot(out / (stem + ".png"), chart.first, chart.second);
  }
}

}  // namespace

void AddBenchFindings(CLI::App& bench) {
  struct Args {
    std::string suite, store, format = "md", out;
    bench::FindingsOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "findings",
      "The paper's findings as verdicts: per ablation table of the suite (one per camera "
      "pipeline in `pipelines`) and metric, whether its reference row (the DTM, k = 20, the GRU) "
      "beats each other row: 'holds' (every other row worse beyond the seed noise), 'does not "
      "hold' (some row better beyond it) or 'undecided', with each paired test (pairs by scene "
      "and seed) and the scenes and seeds covered. Markdown on stdout (or CSV); --out writes "
      "findings.md, findings.csv and a chart per table and metric (<table>-<metric>.svg/.png: "
      "each row's seed means over the covered scenes and its mean +- the seed spread).");
  cmd->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store")->required()->check(Text("a results store"));
  cmd->add_option("--metrics", a->options.metrics,
                  "Metric keys, comma-separated (default psnr,mu_psnr: held-out LDR PSNR and "
                  "HDR mu-PSNR)")
      ->delimiter(',')
      ->check(Text("a metric key"));
  cmd->add_option("--table", a->options.table, "Only this table id")->check(Text("a table id"));
  cmd->add_option("--budget", a->options.budget, "Budget label (default: the suite's last)")
      ->check(Text("a budget label"));
  cmd->add_option("--variant", a->options.variant, "Variant name (default: the suite's first)")
      ->check(Text("a variant name"));
  cmd->add_option("--alpha", a->options.alpha, "Significance level of the paired tests")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--format", a->format, "md or csv (stdout)")->capture_default_str()
      ->check(OneOf({"md", "csv"}));
  cmd->add_option("--out", a->out, "Write findings.md, findings.csv and the charts into this folder")
      ->check(Text("an output folder"));
  cmd->callback([a, cmd] {
    const bench::Suite suite = bench::LoadSuite(a->suite);
    const bench::ResultsStore store(a->store, /*create=*/false);
    const std::vector<bench::RunSummary> runs = bench::SuiteRuns(store, suite);
    // A given key the runs lack was 'undecided: no runs' (rc 0); the defaults may be absent.
    if (cmd->count("--metrics") > 0)
      for (const std::string& m : a->options.metrics)
        bench::RequireMetricKey("--metrics", m, bench::MetricKeys(runs),
                                "runs of suite '" + suite.name + "'");
    const std::vector<bench::Finding> findings = bench::BuildFindings(suite, runs, a->options);
    if (!a->out.empty()) WriteFindingsFolder(a->out, suite, runs, findings, a->options);
    fmt::print("{}", a->format == "csv" ? bench::FindingsCsv(findings) : bench::FindingsMarkdown(findings));
  });
}

}  // namespace hdr4d::cli
