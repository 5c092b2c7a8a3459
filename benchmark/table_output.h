// `hdr4d bench table`'s output: every table of a suite (or one), with the paired tests, and
// optionally the all-metrics companion and per-scene tables, printed in one format and written
// as <id>.md, <id>.tex and <id>.csv into a folder.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "benchmark/tables.h"

namespace hdr4d::bench {

struct TableOutputOptions {
  TableOptions tables;
  std::string format = "md";   // what is printed: md, latex or csv
  std::filesystem::path out;   // "": no files; else every table's .md, .tex and .csv here
  std::string table;           // "": every table; else this id only
  bool all_metrics = false;    // also the table of every metric key the runs have
  bool per_scene = false;      // also per-scene tables of each quality column (md)
};

// Prints through `print` (table by table, as they are made) and writes the files. Throws
// hdr4d::Error when the suite defines no tables or none has the id asked for.
void OutputSuiteTables(const Suite& suite,
                       const std::vector<RunSummary>& runs,
                       const TableOutputOptions& options,
                       const std::function<void(const std::string&)>& print);

}  // namespace hdr4d::bench
