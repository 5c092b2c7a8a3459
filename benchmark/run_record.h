// What one finished run leaves behind, in one value: the store writes it in one transaction
// (benchmark/results_store.h), a Slurm task writes it as one JSON file that `bench collect`
// merges. Harness runs, external submissions and collected tasks all use it.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace hdr4d::bench {

// Where a run appears in tables: a suite's method x scene x supervision x seed x budget x
// variant. One run (one identity) can carry several labels, e.g. the same configuration as
// "HDR-4DGS" in Table 1 and as "DTM" in Table 4.
struct RunLabel {
  std::string suite, method, scene, supervision;
  std::int64_t seed = 0;
  std::string budget, variant;
  nlohmann::json ToJson() const;
  static RunLabel FromJson(const nlohmann::json& json, const std::string& source);
  bool operator<(const RunLabel& o) const;
  bool operator==(const RunLabel& o) const = default;
};

// One scored test view.
struct FrameResult {
  std::string frame;  // the ground truth's file_path (the HDR one when there is no LDR image)
  double time = 0;    // normalised time
  std::int64_t camera_id = -1;
  double exposure = 0;
  std::map<std::string, double> metrics;  // the keys of `hdr4d eval` (+inf: identical images)
  std::map<std::string, double> stats;    // other per-view values (region luminance, ...)
};

using Series = std::vector<std::pair<double, double>>;  // (x, y) points

struct RunRecord {
  std::string id;                 // the run identity (benchmark/run_plan.h)
  std::string source = "harness";  // harness, submit, slurm
  std::string status = "ok";       // ok or failed
  std::string error;               // why it failed
  nlohmann::json config = nlohmann::json::object();  // resolved configuration
  std::string code_version, git_describe;
  nlohmann::json machine = nlohmann::json::object();
  std::string data_checksum;
  std::string scene_dir, run_dir;
  // NaN: not known (e.g. an external submission without timing).
  double train_seconds = std::numeric_limits<double>::quiet_NaN();
  double render_fps = std::numeric_limits<double>::quiet_NaN();
  double peak_rss_mb = std::numeric_limits<double>::quiet_NaN();
  double wall_seconds = std::numeric_limits<double>::quiet_NaN();
  std::int64_t iterations = -1, gaussians = -1;
  std::string started_at, finished_at;  // UTC, ISO 8601
  std::vector<RunLabel> labels;
  std::vector<FrameResult> frames;
  std::map<std::string, Series> series;  // loss, train_psnr, test:<metric>, tone:<t>:<c>, ...

  nlohmann::json ToJson() const;
  // Throws hdr4d::Error naming `source` (a file) and the key for a malformed record.
  static RunRecord FromJson(const nlohmann::json& json, const std::string& source);
};

// A JSON integer that fits an int64 and is at least `min` (1e3 is 1000; 2.5, 1e30 and text are
// errors naming `source` and `key`, where a plain get<int64_t>() truncated or wrapped them).
std::int64_t JsonInteger(const nlohmann::json& value, const std::string& source,
                         const std::string& key,
                         std::int64_t min = std::numeric_limits<std::int64_t>::min());

// Keeps at most `points` (>= 2) points of each series of `record`: evenly spaced by index, the
// first and the last kept (`bench run --series-points`: a store small enough to commit, whose
// tone curves held 88% of a mini run's rows at 256 points).
void ThinSeries(RunRecord* record, int points);

// The current UTC time as 2026-11-24T19:34:31Z.
std::string UtcNow();

}  // namespace hdr4d::bench
