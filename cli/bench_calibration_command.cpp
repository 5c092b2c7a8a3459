// `hdr4d bench calibration GRID --out DIR`: calibrate over a grid of synthetic capture variants
// and seeds, one table of errors against the truth (benchmark/calibration_suite.h).
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "benchmark/calibration_suite.h"
#include "benchmark/suite.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"
#include "core/util/error.h"

namespace hdr4d::cli {
namespace {

// A name without a slash or .json is a grid of the shipped suites (bench::SuitesDir()).
std::filesystem::path CalibrationGridFile(const std::string& name) {
  if (name.find('/') != std::string::npos || name.ends_with(".json")) return name;
  return bench::SuitesDir() / (name + ".json");
}

}  // namespace

void AddBenchCalibration(CLI::App& bench) {
  auto options = std::make_shared<bench::CalibrationSuiteOptions>();
  auto grid = std::make_shared<std::string>();
  CLI::App* cmd = bench.add_subcommand(
      "calibration",
      "Run `hdr4d calibrate` over a grid of synthetic capture variants and seeds (datagen --capture, "
      "then calibrate --truth) and tabulate the errors against the truth: rotation, camera centres, "
      "focal length, distortion kept, fused HDR slope and shadows, the cameras' disagreement; writes "
      "calibration_table.{md,csv} into --out. Captures and COLMAP models already there are reused.");
  cmd->add_option("grid", *grid, "Grid JSON file, or a name in benchmark/suites/ (calibration)")
      ->required()
      ->check(Text("a calibration grid"));
  cmd->add_option("--out", options->work, "Work folder: one folder per variant and seed")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option("--variant", options->only, "Only these variants")->delimiter(',')->check(Text("a variant name"));
  cmd->add_flag("--recalibrate", options->recalibrate,
                "Calibrate again where a result exists (the capture and COLMAP's model are reused)");
  cmd->add_flag("--dry-run", options->dry_run, "Print the commands; run nothing");
  cmd->add_option("--timeout-minutes", options->timeout_minutes, "Wall-clock limit of each command")
      ->capture_default_str()
      ->check(PositiveReal(1e6));
  cmd->callback([options, grid] {
    const bench::CalibrationGrid g = bench::LoadCalibrationGrid(CalibrationGridFile(*grid));
    const auto rows = bench::RunCalibrationSuite(g, *options);
    if (options->dry_run) return;
    fmt::print("{}", bench::CalibrationTableMarkdown(rows));
    int failed = 0;
    for (const auto& r : rows) failed += !r.failed.empty();
    if (failed) Fail("bench calibration: {} of {} variant(s) failed (listed above)", failed, rows.size());
  });
}

}  // namespace hdr4d::cli
