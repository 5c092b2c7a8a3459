// The paper's tables from the results store: Tables 1-2 (method, supervision, HDR PSNR / SSIM /
// LPIPS, LDR PSNR / SSIM / LPIPS, training time, inference fps) and the ablation Tables 4-7
// (HDR PSNR / SSIM / LPIPS), as Markdown, LaTeX and CSV.
//
// A cell is the mean over the table's scenes, averaged over seeds, with the spread over seeds:
// the sample standard deviation over seeds of the mean over scenes (seeds with every scene
// only). The best mean per column is marked. Each row is compared with the table's reference
// row by PairedSeedTest (benchmark/stats.h) on every quality column. LPIPS cannot be computed
// here (no network weights) and says so. A companion table lists every metric key the runs
// have, so metrics added to `hdr4d eval` later appear without code changes.
//
// Every method a row: a method of the store that no table of the suite names (a submission
// under any name, or a suite method left out of the tables) gets its own row in every table
// whose layout it fits (runs on the table's scenes, a supervision of the table's rows, a value
// in one of its quality columns), marked external when it came through `bench submit`, with
// its coverage (scenes and seeds it has).
#pragma once

#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/stats.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {

// Which HDR numbers fill the HDR PSNR / SSIM columns.
enum class HdrProtocol {
  kOwnMax,  // mu_psnr, mu_ssim: each image over its own maximum (HDR-4DGS, the paper's)
  kGtMax,   // mu_psnr_gt_max, mu_ssim_gt_max: both over the ground truth's maximum (HDR-NeRF)
  kPu21,    // pu21_psnr, pu21_ssim: PU21 on absolute luminance
};
// The budget label (default: the suite's last) and variant name (default: its first) a reading
// command shows; a name the suite does not have is an error listing those it has (it printed
// empty tables).
std::string TableBudget(const Suite& suite, const std::string& budget);
std::string TableVariant(const Suite& suite, const std::string& variant);
HdrProtocol ParseHdrProtocol(const std::string& name);  // own_max, gt_max, pu21
std::string HdrProtocolDescription(HdrProtocol protocol);

struct Column {
  std::string key;    // metric key, or "train_minutes", "fps", "gaussians", "peak_rss_mb"
  std::string group;  // "HDR", "LDR" or ""
  std::string label;  // "PSNR", "Training time (min)", ...
  int direction = 1;  // +1 higher is better, -1 lower is better, 0 no "best"
  int digits = 2;
  bool computable = true;  // false: LPIPS
  bool quality = true;     // a quality metric (paired-tested), not a cost
};

struct Cell {
  double mean = 0, spread = 0;
  bool has_value = false, has_spread = false, best = false;
  int runs = 0, expected = 0;  // runs with this value / scenes x seeds
  bool complete() const { return runs == expected; }
};

struct RowResult {
  std::string label, method, supervision;
  std::vector<Cell> cells;
  int runs = 0, failed = 0, expected = 0;
  std::vector<PairedTest> tests;  // per column, against the reference row
  bool is_reference = false;
  bool external = false;  // its runs came through `bench submit`
  bool added = false;     // not a row of the suite's table: a method of the store that fits it
  int scenes_with_runs = 0;
  std::vector<std::int64_t> seeds_with_runs;
  int identical_frames = 0;  // frame values of identical images (+inf) left out of its cells
};
// "3/8 scenes, 1 seed": the scenes of the table a row has runs on, and the seeds it has.
std::string CoverageText(const RowResult& row, std::size_t table_scenes);
// The row's name as the tables print it: its label, with "(external; 3/8 scenes, 1 seed)" for
// a submission and the coverage for a row added from the store.
std::string RowName(const RowResult& row, std::size_t table_scenes);

struct Table {
  std::string id, title, note;
  std::string reference;
  std::vector<Column> columns;
  std::vector<RowResult> rows;
  std::vector<std::string> scenes;
  std::vector<std::int64_t> seeds;
  std::string budget, variant, protocol;
  std::vector<std::string> footnotes;
};

struct TableOptions {
  HdrProtocol protocol = HdrProtocol::kOwnMax;
  // Any two metric keys for the HDR PSNR / SSIM columns instead of the protocol's (e.g. metrics
  // added to `hdr4d eval` later, such as scale-aligned ones); both or neither.
  std::string hdr_psnr_key, hdr_ssim_key;
  std::string budget;   // "" = the suite's last (largest) budget
  std::string variant;  // "" = the suite's first variant
  double alpha = 0.05;
  // Rows to keep (`bench table --methods`): a row stays when its method or its label is named;
  // the reference row always stays (the paired tests need it). Empty: every row.
  std::vector<std::string> methods;
};

// Runs of the suite, plus external submissions (suite "external") on the same scene names.
std::vector<RunSummary> SuiteRuns(const ResultsStore& store, const Suite& suite);

Table BuildTable(const TableSpec& spec, const Suite& suite, const std::vector<RunSummary>& runs,
                 const TableOptions& options);
// Every metric key the table's rows have, one column each (no LPIPS, no cost columns).
Table BuildAllMetricsTable(const TableSpec& spec, const Suite& suite,
                           const std::vector<RunSummary>& runs, const TableOptions& options);

// Every method name and row label the suite's tables have for these runs (added rows
// included), sorted: what `--methods` may name.
std::vector<std::string> KnownRowNames(const Suite& suite, const std::vector<RunSummary>& runs,
                                       const TableOptions& options);
// Throws hdr4d::Error for a name of options.methods that is no row or method of any table,
// listing the known ones.
void CheckRowNames(const Suite& suite, const std::vector<RunSummary>& runs,
                   const TableOptions& options);
// Whether a table built with options.methods has a selected row besides its reference.
bool HasSelectedRows(const Table& table, const TableOptions& options);

// Per scene (rows: scenes and "mean over scenes", columns: the table's rows) of one column's
// key: the mean over seeds, best per scene in bold (what tone_mapper_table.py printed).
std::string PerSceneMarkdown(const TableSpec& spec, const Suite& suite,
                             const std::vector<RunSummary>& runs, const TableOptions& options,
                             const Column& column);

// Cell and header text shared by the formats.
std::string SupervisionLabel(const std::string& supervision);  // "LDR", "HDR", "LDR+HDR"
std::string ArrowOf(const Column& column);                    // "↑", "↓" or ""
std::string FormatValue(double value, int digits);             // "inf" for infinity

std::string ToMarkdown(const Table& table);
std::string ToLatex(const Table& table);
// Tidy: one line per row and column with mean, spread, run counts, best flag and the test.
std::string ToCsv(const Table& table);
// The paired tests as a Markdown table (rows against the reference, quality columns).
std::string PairedTestsMarkdown(const Table& table);

}  // namespace hdr4d::bench
