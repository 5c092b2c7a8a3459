// `hdr4d bench export STORE --out DIR [--suite NAME]`: a store's finished runs as one JSON file
// each, DIR/results/<run id>.json, which `bench collect DIR --store S` merges back
// (benchmark/record_files.h): how a long suite's results move between machines and sessions.
#include <fmt/format.h>

#include <memory>
#include <string>

#include "benchmark/record_files.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/files/output_guard.h"

namespace hdr4d::cli {

void AddBenchExport(CLI::App& bench) {
  struct Args {
    std::string store, out, suite;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "export",
      "Write every finished run of a results store (or of one suite) as DIR/results/<run "
      "id>.json, one run record each; `hdr4d bench collect DIR --store S` merges them into "
      "another store. Files that hold the same record already are left alone, so a folder kept "
      "in git changes only by the new runs.");
  cmd->add_option("STORE", a->store, "Results store")->required()->check(Text("a results store"));
  cmd->add_option("--out", a->out, "Folder to write results/<run id>.json into")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option("--suite", a->suite, "Only runs of this suite (its name in the store)")
      ->check(Text("a suite name"));
  cmd->callback([a] {
    CheckOutputFolder(a->out);
    const bench::ExportSummary s = bench::ExportRecords(a->store, a->out, a->suite);
    fmt::print("bench export: {} run records written, {} unchanged, in {}/results\n", s.written,
               s.unchanged, a->out);
  });
}

}  // namespace hdr4d::cli
