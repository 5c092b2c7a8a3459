#include "benchmark/kept_records.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>

#include "benchmark/sqlite_db.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;

bool RetryWhileBusy(const std::function<void()>& write, const StoreWait& wait,
                    const std::atomic<bool>* cancel) {
  double pause = wait.first_pause_seconds;
  for (int attempt = 1;; ++attempt) {
    try {
      write();
      return true;
    } catch (const DatabaseBusy& e) {
      if (attempt >= wait.attempts) {
        spdlog::warn("bench: {} (gave up after {} attempts)", e.what(), attempt);
        return false;
      }
      spdlog::warn("bench: {}; trying again in {} s", e.what(), pause);
    }
    // Sleeps in short steps so that a stop signal is heard.
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(pause);
    while (std::chrono::steady_clock::now() < until) {
      if (cancel && *cancel) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    pause *= 3;
  }
}

bool StoreOrKeep(ResultsStore& store, const RunRecord& record, const fs::path& run_dir,
                 const StoreWait& wait, const std::atomic<bool>* cancel) {
  const fs::path kept = run_dir / kKeptRecordName;
  fs::create_directories(run_dir);
  WriteJsonFile(kept, record.ToJson());
  if (!RetryWhileBusy([&] { store.InsertRun(record); }, wait, cancel)) return false;
  std::error_code ec;
  fs::remove(kept, ec);  // stored; a leftover file is only read for a run the store lacks
  return true;
}

std::optional<RunRecord> ReadKeptRecord(const fs::path& run_dir, const std::string& id) {
  const fs::path kept = run_dir / kKeptRecordName;
  std::error_code ec;
  if (!fs::exists(kept, ec)) return std::nullopt;
  try {
    RunRecord r = RunRecord::FromJson(ReadJsonFile(kept), kept.string());
    if (r.id == id) return r;
    spdlog::warn("bench: {} holds run {}, not {}; left alone, the run is done again",
                 kept.string(), r.id, id);
  } catch (const Error& e) {
    spdlog::warn("bench: {}; the run is done again", e.what());
  }
  return std::nullopt;
}

}  // namespace hdr4d::bench
