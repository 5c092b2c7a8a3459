// The results store: one SQLite file holding every run of every suite (ARCHITECTURE §2).
//
// Schema (PRAGMA user_version 1):
//   runs           one row per run identity: status, resolved config (JSON), code version,
//                  machine (JSON: CPU model, cores, SIMD target), data checksum, training
//                  seconds, render fps, Gaussian count, peak resident memory, wall time
//   run_labels     (suite, method, scene, supervision, seed, budget, variant) -> run id; the
//                  tables read runs through their labels
//   frames         one row per scored test view: time, camera, exposure
//   frame_metrics  (run, frame, metric) -> value: whatever keys `hdr4d eval` reports, so a new
//                  metric needs no schema change; +inf is stored as inf
//   frame_stats    (run, frame, name) -> value: per-view values that are not metrics
//   series         (run, name, index) -> (x, y): loss and PSNR curves, tone curves, ...
//   stress_results the latest outcome of each stress case
//   claims         run id -> the `bench run` working on it (pid, its start time, host, since
//                  when), created on first use: two harnesses on one store never take one run
// Every write is one transaction: a run appears with all its rows or not at all, and killing
// the writer at any moment loses nothing committed before.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "benchmark/run_record.h"
#include "benchmark/sqlite_db.h"

namespace hdr4d::bench {

// One label of a run with the run's headline numbers and its metric means over frames.
struct RunSummary {
  RunLabel label;
  std::string run_id, status, error, source, code_version, data_checksum, run_dir, scene_dir;
  double train_seconds = 0, render_fps = 0, peak_rss_mb = 0, wall_seconds = 0;
  std::int64_t iterations = -1, gaussians = -1;
  // Mean over the frames with a finite value of the key, as `hdr4d eval` means: a PSNR of
  // identical images (+inf) would make every mean +inf. Those frames are counted in
  // identical_frames; a key no frame has a finite value of is absent from metrics.
  std::map<std::string, double> metrics;
  std::map<std::string, int> identical_frames;
  nlohmann::json machine;
};

// Every metric key of these runs (a key whose frames are all +inf included).
std::set<std::string> MetricKeys(const std::vector<RunSummary>& runs);
// Throws hdr4d::Error "<flag> <key>: unknown metric key; the <whose> have: ..." when `key` is
// not in `known` (a misspelt key printed empty columns, or a chart of nothing). With no key
// at all (no finished run) there is nothing to check against, and it returns.
void RequireMetricKey(const std::string& flag, const std::string& key,
                      const std::set<std::string>& known, const std::string& whose);

struct StressOutcome {
  std::string name, category, description;
  std::string outcome;  // "held" or "failed"
  nlohmann::json checks = nlohmann::json::object();  // {"no crash": true/false/null, ...}
  std::string detail;
  std::string code_version, finished_at;
};

// Who claims a run: a process on a host. `pid_start` (the process's start time, from
// /proc/<pid>/stat) tells a live claim from a dead one whose pid was reused.
struct ClaimOwner {
  std::int64_t pid = 0;
  std::string host, pid_start;
  static ClaimOwner Self();
};
// "" when no process `pid` runs on this machine.
std::string ProcessStartTime(std::int64_t pid);

enum class ClaimResult { kClaimed, kTaken, kStored };

class ResultsStore {
 public:
  // Opens or creates the store (creating its folder); throws hdr4d::Error naming the file when
  // it is not a results store (another SQLite file, a newer schema, not a database at all).
  explicit ResultsStore(const std::filesystem::path& path, bool create = true);

  const std::filesystem::path& path() const { return db_.path(); }
  // How long one write waits for another connection's lock before it throws DatabaseBusy.
  void SetBusyTimeout(int milliseconds);

  // Claims run `run_id` for `owner` before it starts (issue 51, case 23), in one transaction:
  // kStored when the store has it (status ok) already, kTaken when another live bench run holds
  // it, else kClaimed. A claim is taken over when its process is gone (same host: no process
  // with that pid and start time) or, from another host, when it is older than
  // `max_age_seconds` (the run's time limit: that run is over by then).
  ClaimResult Claim(const std::string& run_id, double max_age_seconds,
                    const ClaimOwner& owner = ClaimOwner::Self());
  // Drops `owner`'s claim on the run (nothing when it holds none).
  void Release(const std::string& run_id, const ClaimOwner& owner = ClaimOwner::Self());
  // The claims held now: run id -> owner.
  std::map<std::string, ClaimOwner> Claims() const;

  // Writes the run and its labels in one transaction. A run already stored with status ok is
  // kept (only the labels are added) unless `replace`; a stored failure is replaced. A label
  // already pointing at another run is moved to this one, except when `protect_labels` (for
  // submissions), which throws instead, naming the label and the run that holds it.
  void InsertRun(const RunRecord& record, bool replace = false, bool protect_labels = false);
  // A submission: its labels may only replace an earlier submission under the same labels,
  // and only with `replace` (the earlier one is deleted in the same transaction); a label held
  // by a harness run, or by a submission without `replace`, throws naming both.
  void InsertSubmission(const RunRecord& record, bool replace);
  // Labels only (the run must exist).
  void AddLabels(const std::string& run_id, const std::vector<RunLabel>& labels);

  std::set<std::string> RunIds(const std::string& status) const;  // "ok" or "failed"
  bool HasRun(const std::string& run_id) const;
  // The run a label points at, or "".
  std::string RunOfLabel(const RunLabel& label) const;

  // Every label with its run (status, numbers, metric means), optionally of one suite.
  std::vector<RunSummary> Summaries(const std::string& suite = "") const;
  std::vector<FrameResult> Frames(const std::string& run_id) const;
  std::map<std::string, Series> AllSeries(const std::string& run_id) const;
  nlohmann::json Config(const std::string& run_id) const;

  void WriteStress(const StressOutcome& outcome);
  std::vector<StressOutcome> StressOutcomes() const;

  // The whole record of a run (for export and tests).
  RunRecord Record(const std::string& run_id) const;

 private:
  // Throws unless the file is a store of ours (`version`: its user_version) or, when `create`,
  // an empty database to make one in.
  void RequireOurs(std::int64_t version, bool create);
  void InsertRunLocked(const RunRecord& record, bool replace, bool protect_labels);
  void InsertLabels(const std::string& run_id, const std::vector<RunLabel>& labels,
                    bool protect_labels);

  mutable Database db_;
  mutable std::mutex mutex_;  // one connection shared by the harness's job threads
};

}  // namespace hdr4d::bench
