// Claims of runs in the results store: two `bench run`s on one store took the same runs in
// shared run folders and deleted each other's checkpoints (issue 51, case 23). A run is claimed
// in the store, in one transaction with the check that it is not stored yet, before it starts.
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>

#include "benchmark/results_store.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

constexpr const char* kClaimsTable = R"sql(
CREATE TABLE IF NOT EXISTS claims (
  run_id TEXT PRIMARY KEY,
  pid INTEGER NOT NULL,
  pid_start TEXT NOT NULL,
  host TEXT NOT NULL,
  claimed_at REAL NOT NULL))sql";

double UnixSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "?";
  return name;
}

// Whether the claim's process still works on it, as far as this host can tell.
bool Live(const ClaimOwner& holder, double claimed_at, double max_age_seconds) {
  if (holder.host == HostName())
    return !holder.pid_start.empty() && ProcessStartTime(holder.pid) == holder.pid_start;
  return UnixSeconds() - claimed_at < max_age_seconds;
}

}  // namespace

std::string ProcessStartTime(std::int64_t pid) {
  if (pid <= 0) return "";
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!in || !std::getline(in, line)) return "";
  // Fields after the command name (which may hold spaces and ')'): state is field 3, the start
  // time (clock ticks after boot) field 22.
  const auto close = line.rfind(')');
  if (close == std::string::npos) return "";
  std::istringstream fields(line.substr(close + 1));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
    if (i == 22) return field;
  }
  return "";
}

ClaimOwner ClaimOwner::Self() {
  const std::int64_t pid = getpid();
  return {pid, HostName(), ProcessStartTime(pid)};
}

void ResultsStore::SetBusyTimeout(int milliseconds) {
  std::lock_guard lock(mutex_);
  db_.SetBusyTimeout(milliseconds);
}

ClaimResult ResultsStore::Claim(const std::string& run_id, double max_age_seconds,
                                const ClaimOwner& owner) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  db_.Exec(kClaimsTable);
  Statement stored = db_.Prepare("SELECT 1 FROM runs WHERE id = ?1 AND status = 'ok'");
  stored.Bind(1, run_id);
  if (stored.Step()) return ClaimResult::kStored;  // rolled back: nothing written
  Statement held =
      db_.Prepare("SELECT pid, pid_start, host, claimed_at FROM claims WHERE run_id = ?1");
  held.Bind(1, run_id);
  if (held.Step()) {
    const ClaimOwner holder{held.Int(0), held.Text(2), held.Text(1)};
    const bool same = holder.pid == owner.pid && holder.host == owner.host &&
                      holder.pid_start == owner.pid_start;
    if (!same && Live(holder, held.Double(3), max_age_seconds)) return ClaimResult::kTaken;
  }
  db_.Prepare(
         "INSERT OR REPLACE INTO claims (run_id, pid, pid_start, host, claimed_at) VALUES "
         "(?1, ?2, ?3, ?4, ?5)")
      .Bind(1, run_id)
      .Bind(2, owner.pid)
      .Bind(3, owner.pid_start)
      .Bind(4, owner.host)
      .Bind(5, UnixSeconds())
      .Run();
  t.Commit();
  return ClaimResult::kClaimed;
}

void ResultsStore::Release(const std::string& run_id, const ClaimOwner& owner) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  db_.Exec(kClaimsTable);
  db_.Prepare("DELETE FROM claims WHERE run_id = ?1 AND pid = ?2 AND host = ?3")
      .Bind(1, run_id)
      .Bind(2, owner.pid)
      .Bind(3, owner.host)
      .Run();
  t.Commit();
}

std::map<std::string, ClaimOwner> ResultsStore::Claims() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, ClaimOwner> out;
  Statement exists =
      db_.Prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'claims'");
  if (!exists.Step()) return out;
  Statement s = db_.Prepare("SELECT run_id, pid, pid_start, host FROM claims ORDER BY run_id");
  while (s.Step()) out[s.Text(0)] = {s.Int(1), s.Text(3), s.Text(2)};
  return out;
}

}  // namespace hdr4d::bench
