// `hdr4d bench findings`: the paper's findings as verdicts. Every ablation table of a suite
// states one finding: its reference row (the paper's choice: the DTM, k = 20, the GRU) beats
// each other row of the table. Per table (one per camera pipeline in the `pipelines` suite) and
// metric, the verdict is
//   holds          every other row is worse than the reference by more than the seed noise;
//   does not hold  some other row is better than the reference by more than the seed noise;
//   undecided      neither: some difference is within the noise, the results are identical (a
//                  setting that changes nothing on these scenes), or it cannot be tested (one
//                  seed, or no pairs).
// The tests are the tables' paired tests (BuildAllMetricsTable, PairedSeedTest: pairs by scene
// and seed, seed noise pooled within scenes), so a verdict covers exactly the scenes and seeds
// both rows have; the coverage says which. Rows the store adds to a table (submissions, methods
// no table names) are not part of the paper's finding and are left out of the verdict.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/stats.h"
#include "benchmark/suite.h"
#include "core/viz/plot.h"

namespace hdr4d::bench {

struct FindingsOptions {
  std::vector<std::string> metrics = {"psnr", "mu_psnr"};  // held-out LDR PSNR, HDR mu-PSNR
  std::string budget, variant;  // "": the suite's last budget, first variant
  double alpha = 0.05;
  std::string table;  // "": every ablation table; else this id only
};

// One other row against the reference, on one metric.
struct FindingComparison {
  std::string label, method;
  double mean = 0;     // the row's table cell
  bool has_value = false;  // false: the row has no run with this metric
  PairedTest test;     // row - reference, pairs by scene and seed
  // "reference better", "row better", "within noise", "identical" (every pair equal), "not
  // testable"
  std::string outcome;
};

struct Finding {
  std::string table_id, claim, pipeline;  // pipeline: the table's scene group
  std::string metric;
  int direction = 1;  // +1 higher is better, -1 lower
  std::string reference;
  double reference_mean = 0, reference_spread = 0;
  bool reference_has_value = false;
  // Where reference_spread comes from: "all" (the table cell: every scene of the table),
  // "covered" (the covered scenes alone, the table's cell having none yet) or "none" (fewer
  // than two seeds: no spread). While the table is not complete, reference_mean and each
  // comparison's mean are over the covered scenes and seeds too, as the paired tests are.
  std::string reference_spread_scope = "none";
  std::vector<FindingComparison> against;
  std::string verdict;  // "holds", "does not hold", "undecided"
  std::string why;      // the deciding comparisons in words
  std::vector<std::string> left_out;  // main tables: rows without a run of the metric
  // Coverage: scenes of the table with runs of every row, the seeds the rows share.
  std::vector<std::string> scenes_covered;
  std::size_t table_scenes = 0;
  std::vector<std::int64_t> seeds;
};

// The claim a table states: its "finding" key, else "<reference> beats each other row".
std::string FindingClaim(const TableSpec& spec);
// The reference row as the findings show it: its mean, with its seed spread where there is one.
std::string ReferenceText(const Finding& f);

// Every ablation table of the suite, and every main table that words a finding (or
// options.table), x options.metrics. A main table compares its reference with its
// finding_rows (every other row when it names none) and leaves out, by name, the rows without
// a run of the metric (the paper's GPU baselines, HDR-only rows on an LDR metric). Throws
// hdr4d::Error for a table id that is not in the suite or has no finding, or for no metrics.
std::vector<Finding> BuildFindings(const Suite& suite, const std::vector<RunSummary>& runs,
                                   const FindingsOptions& options);

// One line per finding, pipeline and metric: | claim | pipeline | metric | verdict | reference
// | each other row: mean, difference, p | coverage |.
std::string FindingsMarkdown(const std::vector<Finding>& findings);
// Tidy: one line per finding and compared row.
std::string FindingsCsv(const std::vector<Finding>& findings);

// The chart of one table and metric: per row, its seeds' means over the covered scenes (dots)
// and the mean with its seed spread (a bar of +-1 sample standard deviation), the reference
// in its own colour; rows left to right in the table's order. Empty series when no row has a
// value.
PlotPanel FindingChart(const Suite& suite, const std::vector<RunSummary>& runs,
                       const Finding& finding, const FindingsOptions& options);

}  // namespace hdr4d::bench
