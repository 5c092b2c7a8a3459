#include "benchmark/record_files.h"

#include <fstream>
#include <set>
#include <sstream>

#include "benchmark/results_store.h"
#include "core/files/atomic_file.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;

namespace {

// The file's text, or "" when there is none (or it cannot be read: it is written anew).
std::string ExistingText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "";
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

ExportSummary ExportRecords(const fs::path& store_path, const fs::path& dir, const std::string& suite) {
  const ResultsStore store(store_path, /*create=*/false);
  std::set<std::string> ids;
  for (const RunSummary& s : store.Summaries(suite))
    if (s.status == "ok") ids.insert(s.run_id);
  const fs::path results = dir / "results";
  ExportSummary summary;
  for (const std::string& id : ids) {
    const fs::path file = results / (id + ".json");
    // Compact: a record is read by programs; one line keeps a 3000-iteration run near 20 KB.
    const std::string text = store.Record(id).ToJson().dump() + "\n";
    if (ExistingText(file) == text) {
      ++summary.unchanged;
      continue;
    }
    WriteTextFileAtomic(file, text);
    ++summary.written;
  }
  return summary;
}

}  // namespace hdr4d::bench
