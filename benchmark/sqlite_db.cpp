#include "benchmark/sqlite_db.h"

#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <thread>
#include <utility>

#include "core/util/error.h"

namespace hdr4d::bench {
namespace {
bool IsBusy(int code) { return (code & 0xff) == SQLITE_BUSY || (code & 0xff) == SQLITE_LOCKED; }
}  // namespace

Database::Database(const std::filesystem::path& path, bool create) : path_(path) {
  if (!create && !std::filesystem::exists(path)) Fail("{}: no such results store", path.string());
  const int flags =
      SQLITE_OPEN_READWRITE | SQLITE_OPEN_FULLMUTEX | (create ? SQLITE_OPEN_CREATE : 0);
  if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    Fail("{}: cannot open the results store: {}", path.string(), message);
  }
  sqlite3_busy_timeout(db_, busy_timeout_ms_);  // another harness on the same store: wait
  sqlite3_extended_result_codes(db_, 1);
  Exec("PRAGMA foreign_keys = ON");
  // A file that is not a database fails here, on its first read, which writes nothing.
  ExecWhenFree("PRAGMA schema_version");
  Exec("PRAGMA synchronous = FULL");
}

void Database::UseWal() { ExecWhenFree("PRAGMA journal_mode = WAL"); }

Database::~Database() { sqlite3_close_v2(db_); }

void Database::SetBusyTimeout(int milliseconds) {
  busy_timeout_ms_ = milliseconds;
  sqlite3_busy_timeout(db_, milliseconds);
}

void Database::Throw(const std::string& what) const {
  const std::string message = fmt::format("{}: {}: {}", path_.string(), what, sqlite3_errmsg(db_));
  if (IsBusy(sqlite3_extended_errcode(db_))) throw DatabaseBusy(message);
  throw Error(message);
}

void Database::ExecWhenFree(const std::string& sql) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(busy_timeout_ms_);
  for (;;) {
    const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr);
    if (rc == SQLITE_OK) return;
    if ((rc & 0xff) != SQLITE_BUSY || std::chrono::steady_clock::now() > give_up) Throw(sql.substr(0, 60));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void Database::Exec(const std::string& sql) {
  char* error = nullptr;
  if (const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error); rc != SQLITE_OK) {
    const std::string message = fmt::format("{}: {}: {}", path_.string(),
                                            sql.substr(0, sql.find('\n')),
                                            error ? error : sqlite3_errmsg(db_));
    sqlite3_free(error);
    if (IsBusy(rc)) throw DatabaseBusy(message);
    throw Error(message);
  }
}

Statement Database::Prepare(const std::string& sql) {
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK)
    Throw("cannot prepare '" + sql.substr(0, 60) + "'");
  return Statement(this, stmt);
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement::Statement(Statement&& other) noexcept
    : db_(other.db_), stmt_(std::exchange(other.stmt_, nullptr)) {}

Statement& Statement::Bind(int index, const std::string& value) {
  if (sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()),
                        SQLITE_TRANSIENT) != SQLITE_OK)
    db_->Throw("bind");
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  if (std::isnan(value)) return BindNull(index);
  if (sqlite3_bind_double(stmt_, index, value) != SQLITE_OK) db_->Throw("bind");
  return *this;
}

Statement& Statement::Bind(int index, std::int64_t value) {
  if (sqlite3_bind_int64(stmt_, index, value) != SQLITE_OK) db_->Throw("bind");
  return *this;
}

Statement& Statement::BindNull(int index) {
  if (sqlite3_bind_null(stmt_, index) != SQLITE_OK) db_->Throw("bind");
  return *this;
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  db_->Throw("statement failed");
}

void Statement::Run() {
  while (Step()) {
  }
  Reset();
}

void Statement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

bool Statement::IsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

std::string Statement::Text(int column) const {
  const unsigned char* text = sqlite3_column_text(stmt_, column);
  return text ? std::string(reinterpret_cast<const char*>(text),
                            static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)))
              : std::string();
}

double Statement::Double(int column) const {
  return IsNull(column) ? std::nan("") : sqlite3_column_double(stmt_, column);
}

std::int64_t Statement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }

Transaction::Transaction(Database* db) : db_(db) { db_->ExecWhenFree("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (!done_) sqlite3_exec(db_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::Commit() {
  db_->Exec("COMMIT");
  done_ = true;
}

}  // namespace hdr4d::bench
