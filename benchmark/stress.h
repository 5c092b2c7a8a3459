// `hdr4d bench stress`: numerical stability and failure behaviour under inputs a benchmark
// meets in the wild. Each case builds its inputs in a work folder, runs the hdr4d binary on
// them as a user would, and records what held:
//   no crash      the process ended by itself with exit code 0 or 1 (no signal, no abort)
//   no NaN        valid input: training, renders and scores are finite
//   clear error   invalid input: exit code 1 and one "hdr4d: error:" line naming the file
//   nothing lost  killed or corrupt state: what was finished before is intact, a resumed run
//                 equals an uninterrupted one
// A check that does not apply to a case is null. Cases cover extreme exposures (1e-4 to 1e3 s),
// extreme radiance (1e-6 and 1e6), near-degenerate Gaussians, single-timestamp, -exposure and
// -camera scenes, corrupt inputs (NaN/Inf pixels, broken JSON, a bad key, truncated and
// missing images), a killed training resumed, a killed harness resumed, a corrupt checkpoint,
// a NaN submission and an unwritable output.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "benchmark/results_store.h"

namespace hdr4d::bench {

struct StressOptions {
  std::filesystem::path work;   // scratch folder (kept for inspection)
  std::filesystem::path store;  // optional: outcomes are written here for the report
  std::vector<std::string> cases;  // empty: all
  int threads = 0;                 // per training (0: all cores)
};

struct StressCaseInfo {
  std::string name, category, description;
};
std::vector<StressCaseInfo> StressCaseList();

// Runs the cases in order, printing one line each; returns their outcomes.
std::vector<StressOutcome> RunStress(const StressOptions& options);

}  // namespace hdr4d::bench
