// `hdr4d bench`: the leaderboard harness (benchmark/). Each subcommand lives in its own file
// (cli/bench_commands.h), parses its options and calls the library.
#include "cli/bench_commands.h"
#include "cli/commands.h"

namespace hdr4d::cli {

void AddBenchCommand(CLI::App& app) {
  CLI::App* bench = app.add_subcommand(
      "bench",
      "The benchmark harness: run suites of methods x scenes x settings x seeds into a results "
      "store, print the paper's tables, plot run time against error, write an HTML report, "
      "stress-test numerics, score external renders, compare two stores or code versions, state the paper's findings as verdicts, scale out "
      "with Slurm.");
  bench->require_subcommand(1);
  AddBenchRun(*bench);
  AddBenchTable(*bench);
  AddBenchPareto(*bench);
  AddBenchReport(*bench);
  AddBenchStress(*bench);
  AddBenchSubmit(*bench);
  AddBenchCompare(*bench);
  AddBenchFindings(*bench);
  AddBenchSlurm(*bench);
  AddBenchExport(*bench);
  AddBenchCalibration(*bench);
}

}  // namespace hdr4d::cli
