#include "benchmark/table_output.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/files/atomic_file.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;

namespace {

// The main table and the companion of every metric key: printed and written.
void OutputTables(const std::vector<Table>& tables,
                  const TableOutputOptions& o,
                  const std::function<void(const std::string&)>& print) {
  for (const Table& t : tables) {
    const std::string md = ToMarkdown(t) + "\n" + PairedTestsMarkdown(t);
    if (!o.out.empty()) {
      WriteTextFileAtomic(o.out / (t.id + ".md"), md);
      WriteTextFileAtomic(o.out / (t.id + ".tex"), ToLatex(t));
      WriteTextFileAtomic(o.out / (t.id + ".csv"), ToCsv(t));
    }
    if (o.format == "md") print(md + "\n");
    if (o.format == "latex") print(ToLatex(t) + "\n");
    if (o.format == "csv") print(ToCsv(t));
  }
}

}  // namespace

void OutputSuiteTables(const Suite& suite,
                       const std::vector<RunSummary>& runs,
                       const TableOutputOptions& o,
                       const std::function<void(const std::string&)>& print) {
  if (suite.tables.empty()) Fail("{}: the suite defines no tables", suite.file.string());
  if (!o.out.empty()) CheckOutputFolder(o.out);  // never among a dataset's images
  CheckRowNames(suite, runs, o.tables);
  bool found = false;
  int printed = 0;
  for (const TableSpec& spec : suite.tables) {
    if (!o.table.empty() && spec.id != o.table) continue;
    found = true;
    std::vector<Table> tables = {BuildTable(spec, suite, runs, o.tables)};
    if (!HasSelectedRows(tables.front(), o.tables)) continue;  // --methods names none of its rows
    ++printed;
    if (o.all_metrics) tables.push_back(BuildAllMetricsTable(spec, suite, runs, o.tables));
    OutputTables(tables, o, print);
    if (!o.per_scene) continue;
    for (const Column& c : tables.front().columns) {
      if (!c.quality || !c.computable) continue;
      const std::string md = PerSceneMarkdown(spec, suite, runs, o.tables, c);
      if (!o.out.empty()) WriteTextFileAtomic(o.out / (spec.id + "-" + c.key + "-per-scene.md"), md);
      if (o.format == "md") print(md + "\n");
    }
  }
  if (!found) Fail("{}: no table '{}'", suite.file.string(), o.table);
  if (printed == 0)
    Fail("--methods {}: none of these is a row of {}", fmt::join(o.tables.methods, ","),
         o.table.empty() ? "any table" : "table '" + o.table + "'");
}

}  // namespace hdr4d::bench
