// `hdr4d bench compare STORE_A STORE_B` or `bench compare STORE --versions V1,V2`: two sets of
// runs per configuration with the paired verdict (benchmark/compare.h).
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "benchmark/compare.h"
#include "benchmark/results_store.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/files/atomic_file.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"

namespace hdr4d::cli {

void AddBenchCompare(CLI::App& bench) {
  struct Args {
    std::string store_a, store_b, format = "md", out;
    std::vector<std::string> versions;
    bench::CompareOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = bench.add_subcommand(
      "compare",
      "Two results stores (A, B), or two code versions in one store (--versions V1,V2), side by "
      "side: per configuration (suite x method x scene x supervision x budget) and metric the "
      "means over the seeds both have, B - A, and the paired verdict (B better, A better, or "
      "undecided where the difference is within the seed noise or one seed cannot tell), then "
      "per method over every scene. Markdown on stdout (or CSV), --out writes compare.md and "
      "compare.csv.");
  cmd->add_option("STORE_A", a->store_a, "Results store of side A (with --versions: the store)")
      ->required()
      ->check(Text("a results store"));
  cmd->add_option("STORE_B", a->store_b, "Results store of side B")->check(Text("a results store"));
  cmd->add_option("--versions", a->versions,
                  "Two code versions in STORE_A: A,B, each a prefix of a run's stored code "
                  "version or part of its git description (runs a later version replaced are "
                  "found through their run identity)")
      ->delimiter(',')
      ->expected(2)
      ->check(Text("a code version"));
  cmd->add_option("--suite", a->options.suite, "Only runs of this suite (its name in the store)")
      ->check(Text("a suite name"));
  cmd->add_option("--metrics", a->options.metrics,
                  "Metric keys to compare, comma-separated, or 'all' (default: the tables' "
                  "mu_psnr, mu_ssim, hdr_flip, psnr, ssim, flip)")
      ->delimiter(',')
      ->check(Text("a metric key"));
  cmd->add_option("--format", a->format, "md or csv (stdout)")->capture_default_str()
      ->check(OneOf({"md", "csv"}));
  cmd->add_option("--out", a->out, "Write compare.md and compare.csv into this folder")
      ->check(Text("an output folder"));
  cmd->callback([a] {
    if (a->versions.empty() == a->store_b.empty())
      Fail("bench compare: give two stores (STORE_A STORE_B) or one store with --versions V1,V2");
    const bench::ResultsStore store_a(a->store_a, /*create=*/false);
    bench::Comparison c;
    if (a->versions.empty()) {
      const bench::ResultsStore store_b(a->store_b, /*create=*/false);
      c = bench::Compare(bench::StoreSide(store_a), bench::StoreSide(store_b), a->options);
    } else {
      c = bench::Compare(bench::VersionSide(store_a, a->versions[0]),
                         bench::VersionSide(store_a, a->versions[1]), a->options);
    }
    const std::string md = bench::CompareMarkdown(c), csv = bench::CompareCsv(c);
    if (!a->out.empty()) {
      CheckOutputFolder(a->out);
      std::filesystem::create_directories(a->out);
      WriteTextFileAtomic(std::filesystem::path(a->out) / "compare.md", md);
      WriteTextFileAtomic(std::filesystem::path(a->out) / "compare.csv", csv);
    }
    fmt::print("{}", a->format == "csv" ? csv : md);
  });
}

}  // namespace hdr4d::cli
