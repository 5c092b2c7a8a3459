// `hdr4d bench table SUITE --store FILE`: the paper's tables from a results store
// (benchmark/table_output.h).
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/table_output.h"
#include "benchmark/tables.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"

namespace hdr4d::cli {

void AddBenchTable(CLI::App& bench) {
  struct Args {
    std::string suite, store, protocol = "own_max";
    bench::TableOutputOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "table",
      "The suite's tables from a results store: the layout of the paper's Tables 1-2 and the "
      "ablation Tables 4-7, means over scenes with the spread over seeds, best per column marked, "
      "and paired tests against each table's reference row. Every method of the store gets a row in "
      "each table whose layout it fits (submissions marked external, with their coverage). "
      "Markdown on stdout, or with --out every table as .md, .tex and .csv.");
  cmd->add_option("SUITE", a->suite, "Suite file or shipped suite name")->required()
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--store", a->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--format", a->options.format, "md, latex or csv (stdout)")
      ->check(OneOf({"md", "latex", "csv"}))
      ->capture_default_str();
  cmd->add_option("--out", a->options.out, "Write <id>.md, <id>.tex, <id>.csv for every table into this folder")
      ->check(Text("an output path"));
  cmd->add_option("--table", a->options.table, "Only this table id")
      ->check(Text("a table id"));
  cmd->add_option("--protocol", a->protocol, "HDR columns: own_max (HDR-4DGS), gt_max (HDR-NeRF) or pu21")
      ->capture_default_str()
      ->check(OneOf({"own_max", "gt_max", "pu21"}));
  cmd->add_option("--budget", a->options.tables.budget, "Budget label (default: the suite's last)")
      ->check(Text("a budget label"));
  cmd->add_option("--variant", a->options.tables.variant, "Variant name (default: the suite's first)")
      ->check(Text("a variant name"));
  auto hdr_keys = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--hdr-keys", *hdr_keys,
                  "Two metric keys (PSNR,SSIM) for the HDR columns instead of --protocol's, e.g. "
                  "metrics added to hdr4d eval later")
      ->delimiter(',')
      ->expected(2)
      ->check(Text("a metric key"));
  cmd->parse_complete_callback([a, hdr_keys] {
    if (hdr_keys->size() == 2)
      a->options.tables.hdr_psnr_key = (*hdr_keys)[0], a->options.tables.hdr_ssim_key = (*hdr_keys)[1];
  });
  cmd->add_option("--methods", a->options.tables.methods,
                  "Only these rows: method names or row labels, comma-separated (the reference "
                  "row stays for the paired tests; a table with none of them is left out; an "
                  "unknown name is an error listing the known ones)")
      ->delimiter(',')
      ->check(Text("a method name or row label"));
  cmd->add_flag("--all-metrics", a->options.all_metrics, "Also a table of every metric key the runs have");
  cmd->add_flag("--per-scene", a->options.per_scene, "Also per-scene tables of each quality column");
  cmd->callback([a] {
    const bench::Suite suite = bench::LoadSuite(a->suite);
    a->options.tables.protocol = bench::ParseHdrProtocol(a->protocol);
    const bench::ResultsStore store(a->store, /*create=*/false);
    bench::OutputSuiteTables(suite, bench::SuiteRuns(store, suite), a->options,
                             [](const std::string& text) { fmt::print("{}", text); });
  });
}

}  // namespace hdr4d::cli
