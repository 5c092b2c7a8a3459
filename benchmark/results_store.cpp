#include "benchmark/results_store.h"

#include <fmt/ranges.h>

#include "core/files/output_guard.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

constexpr int kSchemaVersion = 1;

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS runs (
  id TEXT PRIMARY KEY,
  source TEXT NOT NULL,
  status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
  error TEXT NOT NULL,
  config TEXT NOT NULL,
  code_version TEXT NOT NULL,
  git_describe TEXT NOT NULL,
  machine TEXT NOT NULL,
  data_checksum TEXT NOT NULL,
  scene_dir TEXT NOT NULL,
  run_dir TEXT NOT NULL,
  train_seconds REAL,
  render_fps REAL,
  peak_rss_mb REAL,
  wall_seconds REAL,
  iterations INTEGER NOT NULL,
  gaussians INTEGER NOT NULL,
  started_at TEXT NOT NULL,
  finished_at TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS run_labels (
  suite TEXT NOT NULL,
  method TEXT NOT NULL,
  scene TEXT NOT NULL,
  supervision TEXT NOT NULL,
  seed INTEGER NOT NULL,
  budget TEXT NOT NULL,
  variant TEXT NOT NULL,
  run_id TEXT NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  PRIMARY KEY (suite, method, scene, supervision, seed, budget, variant));
CREATE INDEX IF NOT EXISTS run_labels_run ON run_labels(run_id);
CREATE TABLE IF NOT EXISTS frames (
  run_id TEXT NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  frame TEXT NOT NULL,
  time REAL NOT NULL,
  camera_id INTEGER NOT NULL,
  exposure REAL NOT NULL,
  PRIMARY KEY (run_id, frame));
CREATE TABLE IF NOT EXISTS frame_metrics (
  run_id TEXT NOT NULL,
  frame TEXT NOT NULL,
  metric TEXT NOT NULL,
  value REAL,
  PRIMARY KEY (run_id, frame, metric),
  FOREIGN KEY (run_id, frame) REFERENCES frames(run_id, frame) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS frame_stats (
  run_id TEXT NOT NULL,
  frame TEXT NOT NULL,
  name TEXT NOT NULL,
  value REAL,
  PRIMARY KEY (run_id, frame, name),
  FOREIGN KEY (run_id, frame) REFERENCES frames(run_id, frame) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS series (
  run_id TEXT NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  idx INTEGER NOT NULL,
  x REAL,
  y REAL,
  PRIMARY KEY (run_id, name, idx));
CREATE TABLE IF NOT EXISTS stress_results (
  name TEXT PRIMARY KEY,
  category TEXT NOT NULL,
  description TEXT NOT NULL,
  outcome TEXT NOT NULL,
  checks TEXT NOT NULL,
  detail TEXT NOT NULL,
  code_version TEXT NOT NULL,
  finished_at TEXT NOT NULL);
)sql";

nlohmann::json ParseJson(const std::string& text, const std::filesystem::path& db,
                         const std::string& what) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: {} is not valid JSON: {}", db.string(), what, e.what());
  }
}

}  // namespace

std::set<std::string> MetricKeys(const std::vector<RunSummary>& runs) {
  std::set<std::string> keys;
  for (const RunSummary& r : runs) {
    for (const auto& [k, v] : r.metrics) keys.insert(k);
    for (const auto& [k, n] : r.identical_frames) keys.insert(k);
  }
  return keys;
}

void RequireMetricKey(const std::string& flag, const std::string& key,
                      const std::set<std::string>& known, const std::string& whose) {
  if (known.empty() || known.count(key)) return;
  Fail("{} {}: unknown metric key; the {} have: {}", flag, key, whose, fmt::join(known, ", "));
}

ResultsStore::ResultsStore(const std::filesystem::path& path, bool create)
    : db_([&] {
        if (create && path.has_parent_path()) {
          std::error_code ec;
          std::filesystem::create_directories(path.parent_path(), ec);
          if (ec) Fail("{}: cannot create its folder: {}", path.string(), ec.message());
        }
        return path;
      }(),
          create) {
  // No command writes a file over the store it reads or fills (issue 51, case 1).
  ProtectInputFile(path, "the results store " + path.string() + " (an input of this command)");
  // The statements are finished before the transaction: an open read of a snapshot that another
  // process's schema creation made stale kept BEGIN IMMEDIATE busy until the busy timeout (two
  // bench runs creating one store at once: "database is locked").
  auto user_version = [&] {
    Statement version = db_.Prepare("PRAGMA user_version");
    version.Step();
    return version.Int(0);
  };
  auto check_version = [&](std::int64_t v) {
    if (v > kSchemaVersion) {
      Fail("{}: results store of schema version {}; this hdr4d reads up to {}", path.string(), v,
           kSchemaVersion);
    }
  };
  check_version(user_version());
  // Before anything is written: a store's schema and its version are made in one transaction,
  // so a database with tables but no version (or our version with other columns) is not ours.
  RequireOurs(user_version(), create);
  db_.UseWal();  // ours, or an empty file to make ours: its header may change now
  if (user_version() != 0) return;
  Transaction t(&db_);
  const std::int64_t v = user_version();  // again, under the write lock: another may have made it
  check_version(v);
  RequireOurs(v, create);
  if (v != 0) return;
  db_.Exec(kSchema);
  db_.Exec("PRAGMA user_version = " + std::to_string(kSchemaVersion));
  t.Commit();
}

void ResultsStore::RequireOurs(std::int64_t version, bool create) {
  std::vector<std::string> tables;
  Statement list = db_.Prepare(
      "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%' "
      "ORDER BY name");
  while (list.Step()) tables.push_back(list.Text(0));
  if (version == 0 && !tables.empty())
    Fail("{}: an SQLite database with tables of its own ({}), not an hdr4d results store",
         path().string(), fmt::join(tables, ", "));
  if (version == 0 && !create)  // reading commands never make a store's schema
    Fail("{}: an empty SQLite database, not an hdr4d results store", path().string());
  if (version == 0) return;
  // Our version number alone could be another program's: the key tables' columns must match.
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"runs", "id,source,status,error,config,code_version,git_describe,machine,data_checksum,"
               "scene_dir,run_dir,train_seconds,render_fps,peak_rss_mb,wall_seconds,iterations,"
               "gaussians,started_at,finished_at"},
      {"run_labels", "suite,method,scene,supervision,seed,budget,variant,run_id"},
      {"frame_metrics", "run_id,frame,metric,value"}};
  for (const auto& [table, columns] : expected) {
    std::string found;
    Statement info = db_.Prepare("SELECT name FROM pragma_table_info(?1) ORDER BY cid");
    for (info.Bind(1, table); info.Step();) found += (found.empty() ? "" : ",") + info.Text(0);
    if (found.empty())
      Fail("{}: no table '{}': not an hdr4d results store", path().string(), table);
    if (found != columns)
      Fail("{}: table '{}' has the columns ({}), not those of an hdr4d results store",
           path().string(), table, found);
  }
}

void ResultsStore::InsertLabels(const std::string& run_id, const std::vector<RunLabel>& labels,
                                bool protect_labels) {
  Statement find = db_.Prepare(
      "SELECT run_id FROM run_labels WHERE suite=?1 AND method=?2 AND scene=?3 AND "
      "supervision=?4 AND seed=?5 AND budget=?6 AND variant=?7");
  Statement put = db_.Prepare(
      "INSERT OR REPLACE INTO run_labels (suite, method, scene, supervision, seed, budget, "
      "variant, run_id) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
  for (const RunLabel& l : labels) {
    for (Statement* s : {&find, &put}) {
      s->Bind(1, l.suite).Bind(2, l.method).Bind(3, l.scene).Bind(4, l.supervision);
      s->Bind(5, l.seed).Bind(6, l.budget).Bind(7, l.variant);
    }
    if (protect_labels && find.Step() && find.Text(0) != run_id) {
      Fail(
          "{}: suite '{}', method '{}', scene '{}', supervision '{}', seed {} already belongs to "
          "run {}; a submission never replaces another run (use another --method name)",
          path().string(), l.suite, l.method, l.scene, l.supervision, l.seed, find.Text(0));
    }
    find.Reset();
    put.Bind(8, run_id).Run();
  }
}

void ResultsStore::InsertSubmission(const RunRecord& r, bool replace) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  Statement find = db_.Prepare(
      "SELECT l.run_id, r.source FROM run_labels l JOIN runs r ON r.id = l.run_id WHERE "
      "l.suite=?1 AND l.method=?2 AND l.scene=?3 AND l.supervision=?4 AND l.seed=?5 AND "
      "l.budget=?6 AND l.variant=?7");
  // A submission under the name of a trained method would be that method's row in the tables
  // (their index has no budget for a submission): the name must be its own.
  Statement trained = db_.Prepare(
      "SELECT l.run_id FROM run_labels l JOIN runs r ON r.id = l.run_id WHERE l.method = ?1 AND "
      "r.source != 'submit' LIMIT 1");
  for (const RunLabel& l : r.labels) {
    if (trained.Bind(1, l.method).Step()) {
      Fail("{}: method '{}' is trained by the harness in this store (run {}); a submission "
           "never replaces a harness run: use another --method name",
           path().string(), l.method, trained.Text(0));
    }
    trained.Reset();
  }
  for (const RunLabel& l : r.labels) {
    find.Bind(1, l.suite).Bind(2, l.method).Bind(3, l.scene).Bind(4, l.supervision);
    find.Bind(5, l.seed).Bind(6, l.budget).Bind(7, l.variant);
    if (find.Step() && find.Text(0) != r.id) {
      const std::string holder = find.Text(0), source = find.Text(1);
      find.Reset();
      if (source != "submit" || !replace) {
        Fail("{}: method '{}' on scene '{}' ({}, seed {}) is already run {} ({}); {}",
             path().string(), l.method, l.scene, l.supervision, l.seed, holder, source,
             source == "submit" ? "add --replace to replace that submission"
                                : "a submission never replaces a harness run: use another --method name");
      }
      db_.Prepare("DELETE FROM runs WHERE id = ?1").Bind(1, holder).Run();
    }
    find.Reset();
  }
  // Deleting the earlier submission and inserting this one commit together or not at all.
  InsertRunLocked(r, /*replace=*/true, /*protect_labels=*/true);
  t.Commit();
}

void ResultsStore::InsertRun(const RunRecord& r, bool replace, bool protect_labels) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  InsertRunLocked(r, replace, protect_labels);
  t.Commit();
}

void ResultsStore::InsertRunLocked(const RunRecord& r, bool replace, bool protect_labels) {
  Statement existing = db_.Prepare("SELECT status FROM runs WHERE id = ?1");
  existing.Bind(1, r.id);
  if (existing.Step()) {
    if (existing.Text(0) == "ok" && !replace) {
      InsertLabels(r.id, r.labels, protect_labels);
      return;
    }
    // Cascades to its labels, frames, metrics and series, inside this transaction.
    db_.Prepare("DELETE FROM runs WHERE id = ?1").Bind(1, r.id).Run();
  }
  Statement run = db_.Prepare(
      "INSERT INTO runs (id, source, status, error, config, code_version, git_describe, machine, "
      "data_checksum, scene_dir, run_dir, train_seconds, render_fps, peak_rss_mb, wall_seconds, "
      "iterations, gaussians, started_at, finished_at) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, "
      "?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19)");
  run.Bind(1, r.id).Bind(2, r.source).Bind(3, r.status).Bind(4, r.error);
  run.Bind(5, r.config.dump()).Bind(6, r.code_version).Bind(7, r.git_describe);
  run.Bind(8, r.machine.dump()).Bind(9, r.data_checksum).Bind(10, r.scene_dir);
  run.Bind(11, r.run_dir).Bind(12, r.train_seconds).Bind(13, r.render_fps);
  run.Bind(14, r.peak_rss_mb).Bind(15, r.wall_seconds).Bind(16, r.iterations);
  run.Bind(17, r.gaussians).Bind(18, r.started_at).Bind(19, r.finished_at);
  run.Run();
  InsertLabels(r.id, r.labels, protect_labels);
  Statement frame = db_.Prepare(
      "INSERT INTO frames (run_id, frame, time, camera_id, exposure) VALUES (?1, ?2, ?3, ?4, ?5)");
  Statement metric = db_.Prepare(
      "INSERT INTO frame_metrics (run_id, frame, metric, value) VALUES (?1, ?2, ?3, ?4)");
  Statement stat =
      db_.Prepare("INSERT INTO frame_stats (run_id, frame, name, value) VALUES (?1, ?2, ?3, ?4)");
  for (const FrameResult& f : r.frames) {
    frame.Bind(1, r.id).Bind(2, f.frame).Bind(3, f.time).Bind(4, f.camera_id);
    frame.Bind(5, f.exposure).Run();
    for (const auto& [k, v] : f.metrics) metric.Bind(1, r.id).Bind(2, f.frame).Bind(3, k).Bind(4, v).Run();
    for (const auto& [k, v] : f.stats) stat.Bind(1, r.id).Bind(2, f.frame).Bind(3, k).Bind(4, v).Run();
  }
  Statement point =
      db_.Prepare("INSERT INTO series (run_id, name, idx, x, y) VALUES (?1, ?2, ?3, ?4, ?5)");
  for (const auto& [name, points] : r.series) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      point.Bind(1, r.id).Bind(2, name).Bind(3, static_cast<std::int64_t>(i));
      point.Bind(4, points[i].first).Bind(5, points[i].second).Run();
    }
  }
}

void ResultsStore::AddLabels(const std::string& run_id, const std::vector<RunLabel>& labels) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  InsertLabels(run_id, labels, false);
  t.Commit();
}

std::set<std::string> ResultsStore::RunIds(const std::string& status) const {
  std::lock_guard lock(mutex_);
  std::set<std::string> ids;
  Statement s = db_.Prepare("SELECT id FROM runs WHERE status = ?1");
  s.Bind(1, status);
  while (s.Step()) ids.insert(s.Text(0));
  return ids;
}

bool ResultsStore::HasRun(const std::string& run_id) const {
  std::lock_guard lock(mutex_);
  Statement s = db_.Prepare("SELECT 1 FROM runs WHERE id = ?1");
  s.Bind(1, run_id);
  return s.Step();
}

std::string ResultsStore::RunOfLabel(const RunLabel& l) const {
  std::lock_guard lock(mutex_);
  Statement s = db_.Prepare(
      "SELECT run_id FROM run_labels WHERE suite=?1 AND method=?2 AND scene=?3 AND "
      "supervision=?4 AND seed=?5 AND budget=?6 AND variant=?7");
  s.Bind(1, l.suite).Bind(2, l.method).Bind(3, l.scene).Bind(4, l.supervision);
  s.Bind(5, l.seed).Bind(6, l.budget).Bind(7, l.variant);
  return s.Step() ? s.Text(0) : "";
}

std::vector<RunSummary> ResultsStore::Summaries(const std::string& suite) const {
  std::lock_guard lock(mutex_);
  std::vector<RunSummary> out;
  Statement s = db_.Prepare(
      "SELECT l.suite, l.method, l.scene, l.supervision, l.seed, l.budget, l.variant, r.id, "
      "r.status, r.error, r.source, r.code_version, r.data_checksum, r.run_dir, r.scene_dir, "
      "r.train_seconds, r.render_fps, r.peak_rss_mb, r.wall_seconds, r.iterations, r.gaussians, "
      "r.machine FROM run_labels l JOIN runs r ON r.id = l.run_id WHERE ?1 = '' OR l.suite = ?1 "
      "ORDER BY l.suite, l.method, l.scene, l.supervision, l.seed, l.budget, l.variant");
  s.Bind(1, suite);
  while (s.Step()) {
    RunSummary r;
    r.label = {s.Text(0), s.Text(1), s.Text(2), s.Text(3), s.Int(4), s.Text(5), s.Text(6)};
    r.run_id = s.Text(7);
    r.status = s.Text(8);
    r.error = s.Text(9);
    r.source = s.Text(10);
    r.code_version = s.Text(11);
    r.data_checksum = s.Text(12);
    r.run_dir = s.Text(13);
    r.scene_dir = s.Text(14);
    r.train_seconds = s.Double(15);
    r.render_fps = s.Double(16);
    r.peak_rss_mb = s.Double(17);
    r.wall_seconds = s.Double(18);
    r.iterations = s.Int(19);
    r.gaussians = s.Int(20);
    r.machine = ParseJson(s.Text(21), path(), "machine of run " + r.run_id);
    out.push_back(std::move(r));
  }
  // Metric means per run, once per run.
  // Over the finite values (RunSummary::metrics); 1.8e308 is above the largest double.
  Statement m = db_.Prepare(
      "SELECT run_id, metric, avg(CASE WHEN abs(value) < 1.8e308 THEN value END), "
      "sum(abs(value) >= 1.8e308) FROM frame_metrics GROUP BY run_id, metric");
  std::map<std::string, std::map<std::string, double>> means;
  std::map<std::string, std::map<std::string, int>> identical;
  while (m.Step()) {
    if (!m.IsNull(2)) means[m.Text(0)][m.Text(1)] = m.Double(2);
    if (m.Int(3) > 0) identical[m.Text(0)][m.Text(1)] = static_cast<int>(m.Int(3));
  }
  for (RunSummary& r : out) {
    r.metrics = means[r.run_id];
    r.identical_frames = identical[r.run_id];
  }
  return out;
}

std::vector<FrameResult> ResultsStore::Frames(const std::string& run_id) const {
  std::lock_guard lock(mutex_);
  std::vector<FrameResult> frames;
  std::map<std::string, std::size_t> index;
  Statement f = db_.Prepare(
      "SELECT frame, time, camera_id, exposure FROM frames WHERE run_id = ?1 ORDER BY frame");
  f.Bind(1, run_id);
  while (f.Step()) {
    index[f.Text(0)] = frames.size();
    frames.push_back({f.Text(0), f.Double(1), f.Int(2), f.Double(3), {}, {}});
  }
  for (const char* table : {"frame_metrics", "frame_stats"}) {
    const bool metrics = std::string(table) == "frame_metrics";
    Statement v = db_.Prepare(std::string("SELECT frame, ") + (metrics ? "metric" : "name") +
                              ", value FROM " + table + " WHERE run_id = ?1");
    v.Bind(1, run_id);
    while (v.Step()) {
      FrameResult& fr = frames[index.at(v.Text(0))];
      (metrics ? fr.metrics : fr.stats)[v.Text(1)] = v.Double(2);
    }
  }
  return frames;
}

std::map<std::string, Series> ResultsStore::AllSeries(const std::string& run_id) const {
  std::lock_guard lock(mutex_);
  std::map<std::string, Series> series;
  Statement s = db_.Prepare("SELECT name, x, y FROM series WHERE run_id = ?1 ORDER BY name, idx");
  s.Bind(1, run_id);
  while (s.Step()) series[s.Text(0)].emplace_back(s.Double(1), s.Double(2));
  return series;
}

nlohmann::json ResultsStore::Config(const std::string& run_id) const {
  std::lock_guard lock(mutex_);
  Statement s = db_.Prepare("SELECT config FROM runs WHERE id = ?1");
  s.Bind(1, run_id);
  if (!s.Step()) Fail("{}: no run {}", path().string(), run_id);
  return ParseJson(s.Text(0), path(), "config of run " + run_id);
}

RunRecord ResultsStore::Record(const std::string& run_id) const {
  RunRecord r;
  {
    std::lock_guard lock(mutex_);
    Statement s = db_.Prepare(
        "SELECT source, status, error, config, code_version, git_describe, machine, "
        "data_checksum, scene_dir, run_dir, train_seconds, render_fps, peak_rss_mb, wall_seconds, "
        "iterations, gaussians, started_at, finished_at FROM runs WHERE id = ?1");
    s.Bind(1, run_id);
    if (!s.Step()) Fail("{}: no run {}", path().string(), run_id);
    r.id = run_id;
    r.source = s.Text(0);
    r.status = s.Text(1);
    r.error = s.Text(2);
    r.config = ParseJson(s.Text(3), path(), "config of run " + run_id);
    r.code_version = s.Text(4);
    r.git_describe = s.Text(5);
    r.machine = ParseJson(s.Text(6), path(), "machine of run " + run_id);
    r.data_checksum = s.Text(7);
    r.scene_dir = s.Text(8);
    r.run_dir = s.Text(9);
    r.train_seconds = s.Double(10);
    r.render_fps = s.Double(11);
    r.peak_rss_mb = s.Double(12);
    r.wall_seconds = s.Double(13);
    r.iterations = s.Int(14);
    r.gaussians = s.Int(15);
    r.started_at = s.Text(16);
    r.finished_at = s.Text(17);
    Statement l = db_.Prepare(
        "SELECT suite, method, scene, supervision, seed, budget, variant FROM run_labels WHERE "
        "run_id = ?1 ORDER BY suite, method, scene, supervision, seed, budget, variant");
    l.Bind(1, run_id);
    while (l.Step())
      r.labels.push_back({l.Text(0), l.Text(1), l.Text(2), l.Text(3), l.Int(4), l.Text(5), l.Text(6)});
  }
  r.frames = Frames(run_id);
  r.series = AllSeries(run_id);
  return r;
}

void ResultsStore::WriteStress(const StressOutcome& o) {
  std::lock_guard lock(mutex_);
  Transaction t(&db_);
  Statement s = db_.Prepare(
      "INSERT OR REPLACE INTO stress_results (name, category, description, outcome, checks, "
      "detail, code_version, finished_at) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
  s.Bind(1, o.name).Bind(2, o.category).Bind(3, o.description).Bind(4, o.outcome);
  s.Bind(5, o.checks.dump()).Bind(6, o.detail).Bind(7, o.code_version).Bind(8, o.finished_at);
  s.Run();
  t.Commit();
}

std::vector<StressOutcome> ResultsStore::StressOutcomes() const {
  std::lock_guard lock(mutex_);
  std::vector<StressOutcome> out;
  Statement s = db_.Prepare(
      "SELECT name, category, description, outcome, checks, detail, code_version, finished_at "
      "FROM stress_results ORDER BY category, name");
  while (s.Step()) {
    out.push_back({s.Text(0), s.Text(1), s.Text(2), s.Text(3),
                   ParseJson(s.Text(4), path(), "stress checks"), s.Text(5), s.Text(6),
                   s.Text(7)});
  }
  return out;
}

}  // namespace hdr4d::bench
