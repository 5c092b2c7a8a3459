// A thin RAII layer over SQLite's C API (Debian's libsqlite3): a connection, prepared statements
// and transactions. Every failure throws hdr4d::Error naming the database file and SQLite's
// message, so a caller never sees a raw result code.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "core/util/error.h"

struct sqlite3;
struct sqlite3_stmt;

namespace hdr4d::bench {

class Statement;

// The database stayed locked by another connection past the busy timeout: nothing was written,
// and the same write may succeed later (issue 51, case 22).
class DatabaseBusy : public Error {
 public:
  using Error::Error;
};

class Database {
 public:
  // Opens (creating when `create`) the file with foreign keys on, a busy timeout and
  // synchronous=FULL; with UseWal, a committed transaction survives the process being killed
  // at any moment, an uncommitted one leaves no trace. Opening writes nothing to the file.
  Database(const std::filesystem::path& path, bool create);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  // Switches the file to the WAL journal (kept in its header): call it once the file is known
  // to be ours, as it rewrites a foreign database's header (`bench table` on another
  // program's database changed its bytes).
  void UseWal();
  void Exec(const std::string& sql);
  // Exec, retrying while SQLite answers busy without calling the busy handler (in WAL mode it
  // does so when another connection is opening the file or switching its journal), up to the
  // busy timeout.
  void ExecWhenFree(const std::string& sql);
  Statement Prepare(const std::string& sql);
  const std::filesystem::path& path() const { return path_; }
  // How long a statement waits for another connection's lock (default 60 s).
  void SetBusyTimeout(int milliseconds);
  sqlite3* handle() { return db_; }
  // Throws DatabaseBusy when SQLite's last answer was busy or locked, else hdr4d::Error.
  [[noreturn]] void Throw(const std::string& what) const;

 private:
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
  int busy_timeout_ms_ = 60000;
};

class Statement {
 public:
  Statement(Database* db, sqlite3_stmt* stmt) : db_(db), stmt_(stmt) {}
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters are 1-based, as in SQLite. A NaN double binds as NULL (unknown); +-inf stay.
  Statement& Bind(int index, const std::string& value);
  Statement& Bind(int index, double value);
  Statement& Bind(int index, std::int64_t value);
  Statement& Bind(int index, int value) { return Bind(index, static_cast<std::int64_t>(value)); }
  Statement& BindNull(int index);
  // One step: true while a row is available.
  bool Step();
  // Runs a statement that returns no rows and resets it for the next bindings.
  void Run();
  void Reset();

  bool IsNull(int column) const;
  std::string Text(int column) const;
  double Double(int column) const;  // NULL reads as NaN
  std::int64_t Int(int column) const;

 private:
  Database* db_;
  sqlite3_stmt* stmt_;
};

// BEGIN IMMEDIATE on construction; Commit() makes it durable; destruction without Commit rolls
// everything back (an exception half-way through leaves the database as it was).
class Transaction {
 public:
  explicit Transaction(Database* db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void Commit();

 private:
  Database* db_;
  bool done_ = false;
};

}  // namespace hdr4d::bench
