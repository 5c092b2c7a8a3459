// `hdr4d bench report`: one self-contained HTML page (every picture a data URI, no external
// file or network access) with the suite's tables and paired tests, the run time against
// error charts, per scene the tone-mapped renders of every method beside the ground truth with
// error maps, the learned tone curves over time, the temporal luminance of a pixel region
// (the paper's Figs. 4-5 analysis), the training curves, and the stress suite's table. A
// script on the page counts its tables and images when it loads and logs an error to the
// console for any image that fails to decode (the browser test reads both).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"

namespace hdr4d::bench {

struct ReportOptions {
  std::filesystem::path out;  // the .html file
  TableOptions tables;
  std::string pareto_metric = "mu_psnr";
};

struct ReportSummary {
  int tables = 0, images = 0, scenes = 0, stress_cases = 0;
};

// The runs `--methods` (options.methods) selects for the report's charts and the scenes'
// renders: a run whose method is named, or whose method and supervision a named row of the
// suite's tables shows; every run when nothing is named. The tables keep their reference row
// besides (their paired tests need it); a chart or render of it is shown only when named.
std::vector<RunSummary> ReportSelectedRuns(const std::vector<RunSummary>& runs, const Suite& suite,
                                           const std::vector<std::string>& methods);

ReportSummary WriteReport(const Suite& suite, const ResultsStore& store, const ReportOptions& options);

}  // namespace hdr4d::bench
