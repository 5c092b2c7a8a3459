// The subcommands of `hdr4d bench`, one file each (or per group: slurm, task and collect), each
// parsing its options and calling the harness (benchmark/). AddBenchCommand registers them.
#pragma once

#include <CLI/CLI.hpp>

namespace hdr4d::cli {

void AddBenchRun(CLI::App& bench);     // bench run: a suite into a results store
void AddBenchTable(CLI::App& bench);   // bench table: the paper's tables
void AddBenchPareto(CLI::App& bench);  // bench pareto: run time against error
void AddBenchReport(CLI::App& bench);  // bench report: one HTML page
void AddBenchStress(CLI::App& bench);  // bench stress: numerics and failure behaviour
void AddBenchSubmit(CLI::App& bench);  // bench submit: external renders scored
void AddBenchSlurm(CLI::App& bench);   // bench slurm, task, collect
void AddBenchCompare(CLI::App& bench);  // bench compare: two stores or code versions
void AddBenchFindings(CLI::App& bench);  // bench findings: the paper's findings as verdicts
void AddBenchCalibration(CLI::App& bench);  // bench calibration: calibrate over capture variants
void AddBenchExport(CLI::App& bench);  // bench export: a store as run record files (bench collect reads them)

}  // namespace hdr4d::cli
