// A finished run's record is kept in its run folder (RUN/record.json) before the store is
// written, and removed once the store has it: a store locked by another program for longer than
// SQLite's busy timeout made `bench run` throw a finished result away, to be retrained next time
// (issue 51, case 22). The writer waits and retries with growing pauses; if the store is still
// locked the record stays, and the next `bench run` (or `bench collect RUNS_DIR`) stores it
// without running the run again.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "benchmark/results_store.h"
#include "benchmark/run_record.h"

namespace hdr4d::bench {

// Attempts at a locked store: each waits the store's busy timeout (60 s), and the pauses
// between them grow threefold from `first_pause_seconds` (4 attempts: about 5 minutes in all).
struct StoreWait {
  int attempts = 4;
  double first_pause_seconds = 5;
};

inline constexpr const char* kKeptRecordName = "record.json";

// Runs `write` until it does not throw DatabaseBusy; false when the store stayed locked through
// every attempt, or `cancel` was set during a pause. Other errors pass through.
bool RetryWhileBusy(const std::function<void()>& write, const StoreWait& wait,
                    const std::atomic<bool>* cancel = nullptr);

// Writes `record` to RUN_DIR/record.json, then stores it (retrying as above). True: stored, and
// the file removed; false: the store stayed locked and the file holds the record.
bool StoreOrKeep(ResultsStore& store, const RunRecord& record, const std::filesystem::path& run_dir,
                 const StoreWait& wait, const std::atomic<bool>* cancel = nullptr);

// The record kept in RUN_DIR for run `id`; nullopt when there is none. A file that cannot be
// read, or holds another run, is named in a warning and left alone (the run is done again).
std::optional<RunRecord> ReadKeptRecord(const std::filesystem::path& run_dir, const std::string& id);

}  // namespace hdr4d::bench
