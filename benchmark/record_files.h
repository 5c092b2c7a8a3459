// A store's runs as files: `hdr4d bench export STORE --out DIR` writes DIR/results/<run id>.json,
// one RunRecord each, the layout `bench collect DIR --store S` merges back (benchmark/slurm.h).
// Long suites run over several sessions on machines that keep nothing between them
// (scripts/bench-campaign.sh); their records travel in git this way: one small file per run,
// written once and never changed, so a session adds only its new runs to the history, where a
// committed SQLite file would be copied whole each time.
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d::bench {

struct ExportSummary {
  int written = 0;    // new or changed files
  int unchanged = 0;  // the file held this record already
};

// Writes every finished (status ok) run of `suite` ("" = every suite) in `store` to
// DIR/results/<id>.json (compact JSON, atomically); a file that holds the same text is left
// alone. Throws hdr4d::Error naming the store or the file that could not be read or written.
ExportSummary ExportRecords(const std::filesystem::path& store, const std::filesystem::path& dir,
                            const std::string& suite);

}  // namespace hdr4d::bench
