// `hdr4d bench stress`: numerical stability and failure behaviour (benchmark/stress.h).
#include <fmt/format.h>

#include <memory>
#include <string>

#include "benchmark/stress.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/util/error.h"

namespace hdr4d::cli {

void AddBenchStress(CLI::App& bench) {
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

}  // namespace hdr4d::cli
