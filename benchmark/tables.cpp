#include "benchmark/tables.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

using Key = std::tuple<std::string, std::string, std::string, std::int64_t>;  // method, sup, scene, seed

const char* kLpipsNote =
    "LPIPS: not computed. It needs the LPIPS network weights, which cannot be obtained on these "
    "machines. FLIP (NVIDIA's weight-free perceptual metric, lower is better) is reported beside "
    "SSIM instead. HDR FLIP is HDR-FLIP of the prediction times its scale against the truth "
    "(hdr_flip_aligned, as the aligned mu-PSNR): HDR-FLIP is not scale-free, and a model supervised on "
    "each image divided by its own maximum renders in those units. Runs scored before it have none (-).";

std::vector<Column> HdrColumns(const TableOptions& o, bool with_lpips) {
  std::string psnr = "mu_psnr", ssim = "mu_ssim";
  if (o.protocol == HdrProtocol::kGtMax) psnr = "mu_psnr_gt_max", ssim = "mu_ssim_gt_max";
  if (o.protocol == HdrProtocol::kPu21) psnr = "pu21_psnr", ssim = "pu21_ssim";
  if (!o.hdr_psnr_key.empty()) psnr = o.hdr_psnr_key, ssim = o.hdr_ssim_key;
  std::vector<Column> c = {
      {psnr, "HDR", "PSNR", 1, 2}, {ssim, "HDR", "SSIM", 1, 3}, {"hdr_flip_aligned", "HDR", "FLIP", -1, 3}};
  if (with_lpips) c.push_back({"lpips_hdr", "HDR", "LPIPS", -1, 3, false});
  return c;
}

std::vector<Column> MainColumns(const TableOptions& o) {
  std::vector<Column> c = HdrColumns(o, true);
  c.push_back({"psnr", "LDR", "PSNR", 1, 2});
  c.push_back({"ssim", "LDR", "SSIM", 1, 3});
  c.push_back({"flip", "LDR", "FLIP", -1, 3});
  c.push_back({"lpips", "LDR", "LPIPS", -1, 3, false});
  c.push_back({"train_minutes", "", "Training time (min)", -1, 2, true, false});
  c.push_back({"fps", "", "Inference (fps)", 1, 1, true, false});
  return c;
}
int GuessDirection(const std::string& key) {
  for (const char* up : {"psnr", "ssim", "corr"})
    if (key.find(up) != std::string::npos) return 1;
  for (const char* down : {"lpips", "flip", "mse", "error", "rmse"})
    if (key.find(down) != std::string::npos) return -1;
  return 0;  // e.g. a slope, where the best is 1, not the largest
}

using MethodSup = std::pair<std::string, std::string>;

struct Index {
  std::map<Key, const RunSummary*> ok;
  std::map<MethodSup, int> failed;  // (method, sup) -> count
  std::map<std::string, std::set<std::int64_t>> seeds_of_method;
  std::set<MethodSup> submitted;  // (method, sup) with a run from `bench submit`
};

Index BuildIndex(const std::vector<RunSummary>& runs, const std::string& budget,
                 const std::string& variant) {
  Index ix;
  for (const RunSummary& r : runs) {
    const RunLabel& l = r.label;
    const bool external = r.source == "submit";
    if (!external && (l.budget != budget || l.variant != variant)) continue;
    if (external) ix.submitted.insert({l.method, l.supervision});
    if (r.status != "ok") {
      ++ix.failed[{l.method, l.supervision}];
      continue;
    }
    const auto [it, added] = ix.ok.insert({{l.method, l.supervision, l.scene, l.seed}, &r});
    if (!added && it->second->run_id != r.run_id) {  // one cell, two runs: never pick silently
      const RunSummary& o = *it->second;
      Fail("the store holds two runs of method '{}' ({}) on scene '{}', seed {}: {} ({}) and {} "
           "({}); a submission must not take a trained method's name: export the store (`bench "
           "export`), delete the submission's file and collect the rest into a new store",
           l.method, l.supervision, l.scene, l.seed, o.run_id, o.source, r.run_id, r.source);
    }
    ix.seeds_of_method[l.method].insert(l.seed);
  }
  return ix;
}

std::optional<double> ValueOf(const RunSummary& r, const Column& c) {
  double v = std::nan("");
  if (c.key == "train_minutes") {
    v = r.train_seconds / 60.0;
  } else if (c.key == "fps") {
    v = r.render_fps;
  } else if (c.key == "gaussians") {
    v = r.gaussians >= 0 ? static_cast<double>(r.gaussians) : std::nan("");
  } else if (c.key == "peak_rss_mb") {
    v = r.peak_rss_mb;
  } else if (auto it = r.metrics.find(c.key); it != r.metrics.end()) {
    v = it->second;
  }
  if (!std::isfinite(v)) return std::nullopt;  // +inf: identical images, left out of means
  return v;
}

std::vector<std::string> GroupScenes(const Suite& suite, const std::string& group) {
  std::vector<std::string> scenes;
  for (const SceneSpec& s : suite.scenes)
    if (s.group == group) scenes.push_back(s.name);
  return scenes;
}

std::vector<std::int64_t> RowSeeds(const Suite& suite, const Index& ix, const std::string& method) {
  if (suite.FindMethod(method)) return suite.seeds;
  const auto it = ix.seeds_of_method.find(method);  // external: the seeds it was submitted with
  if (it == ix.seeds_of_method.end()) return {0};
  return {it->second.begin(), it->second.end()};
}

// A row's values per column, by (scene, seed).
using RowValues = std::vector<std::map<std::pair<std::string, std::int64_t>, double>>;

// One cell: the mean over seeds of the per-seed scene means when every run is there (with the
// spread between seeds from two seeds on), else the mean of the runs there are.
Cell SummariseCell(const std::map<std::pair<std::string, std::int64_t>, double>& vals,
                   const std::vector<std::int64_t>& seeds,
                   const std::vector<std::string>& scenes,
                   int expected) {
  Cell cell;
  cell.expected = expected;
  cell.runs = static_cast<int>(vals.size());
  if (vals.empty()) return cell;
  cell.has_value = true;
  std::vector<double> all, complete_seed_means;
  for (const auto& [k, v] : vals) all.push_back(v);
  for (std::int64_t seed : seeds) {
    std::vector<double> per_seed;
    for (const std::string& scene : scenes)
      if (auto it = vals.find({scene, seed}); it != vals.end()) per_seed.push_back(it->second);
    if (per_seed.size() == scenes.size()) complete_seed_means.push_back(Mean(per_seed));
  }
  cell.mean = cell.complete() ? Mean(complete_seed_means) : Mean(all);
  if (complete_seed_means.size() >= 2) {
    cell.spread = SampleStdDev(complete_seed_means);
    cell.has_spread = true;
  }
  return cell;
}

// One row of the table: its runs' values per column (into *values) and its cells.
RowResult BuildRow(const TableRow& row,
                   const TableSpec& spec,
                   const Suite& suite,
                   const Index& ix,
                   const Table& t,
                   RowValues* values) {
  RowResult rr{row.label, row.method, row.supervision};
  rr.is_reference = row.label == spec.reference;
  const std::vector<std::int64_t> seeds = RowSeeds(suite, ix, row.method);
  rr.expected = static_cast<int>(t.scenes.size() * seeds.size());
  if (auto f = ix.failed.find({row.method, row.supervision}); f != ix.failed.end())
    rr.failed = f->second;
  rr.external = ix.submitted.count({row.method, row.supervision}) > 0;
  RowValues& row_values = *values;
  row_values.resize(t.columns.size());
  std::set<std::int64_t> seeds_seen;
  for (const std::string& scene : t.scenes) {
    bool scene_seen = false;
    for (std::int64_t seed : seeds) {
      const auto it = ix.ok.find({row.method, row.supervision, scene, seed});
      if (it == ix.ok.end()) continue;
      ++rr.runs;
      scene_seen = true;
      seeds_seen.insert(seed);
      for (std::size_t c = 0; c < t.columns.size(); ++c) {
        if (!t.columns[c].computable) continue;
        if (const auto v = ValueOf(*it->second, t.columns[c])) row_values[c][{scene, seed}] = *v;
        const auto& identical = it->second->identical_frames;
        if (auto n = identical.find(t.columns[c].key); n != identical.end())
          rr.identical_frames += n->second;
      }
    }
    rr.scenes_with_runs += scene_seen;
  }
  rr.seeds_with_runs.assign(seeds_seen.begin(), seeds_seen.end());
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    rr.cells.push_back(SummariseCell(row_values[c], seeds, t.scenes, rr.expected));
  return rr;
}

// A (method, supervision) of the store fits a table when it has a finished run on one of the
// table's scenes with a value in one of its quality columns, under a supervision the table's
// rows use (the ablation tables are LDR-only; Table 1 takes every supervision).
bool FitsTable(const MethodSup& ms, const TableSpec& spec, const Index& ix,
               const std::vector<std::string>& scenes, const std::vector<Column>& columns) {
  if (spec.layout != "main") {
    bool supervision_used = spec.rows.empty();
    for (const TableRow& r : spec.rows) supervision_used |= r.supervision == ms.second;
    if (!supervision_used) return false;
  }
  const std::set<std::string> in_table(scenes.begin(), scenes.end());
  for (const auto& [key, run] : ix.ok) {
    if (std::get<0>(key) != ms.first || std::get<1>(key) != ms.second) continue;
    if (!in_table.count(std::get<2>(key))) continue;
    for (const Column& c : columns)
      if (c.quality && c.computable && ValueOf(*run, c)) return true;
  }
  return false;
}

struct PlannedRow {
  TableRow row;
  bool added = false;
};

// The table's own rows, then every method of the store that no table of the suite names and
// that fits this one (sorted by name), then options.methods' selection (the reference stays).
std::vector<PlannedRow> PlanRows(const TableSpec& spec, const Suite& suite, const Index& ix,
                                 const std::vector<std::string>& scenes,
                                 const std::vector<Column>& columns, const TableOptions& options) {
  std::vector<PlannedRow> rows;
  for (const TableRow& r : spec.rows) rows.push_back({r, false});
  std::set<std::string> named;  // methods some table of the suite places
  for (const TableSpec& t : suite.tables)
    for (const TableRow& r : t.rows) named.insert(r.method);
  std::set<MethodSup> candidates;
  for (const auto& [key, run] : ix.ok)
    if (!named.count(std::get<0>(key))) candidates.insert({std::get<0>(key), std::get<1>(key)});
  std::vector<MethodSup> fitting;
  for (const MethodSup& ms : candidates)
    if (FitsTable(ms, spec, ix, scenes, columns)) fitting.push_back(ms);
  for (const MethodSup& ms : fitting) {
    const MethodSpec* m = suite.FindMethod(ms.first);
    std::string label = m && !m->label.empty() ? m->label : ms.first;
    const auto same_method = std::count_if(fitting.begin(), fitting.end(),
                                           [&](const MethodSup& o) { return o.first == ms.first; });
    if (same_method > 1) label += " (" + SupervisionLabel(ms.second) + ")";
    rows.push_back({{label, ms.first, ms.second}, true});
  }
  if (options.methods.empty()) return rows;
  const std::set<std::string> keep(options.methods.begin(), options.methods.end());
  std::erase_if(rows, [&](const PlannedRow& p) {
    return p.row.label != spec.reference && !keep.count(p.row.method) && !keep.count(p.row.label);
  });
  return rows;
}

// Best per column, in the column's direction.
void MarkBest(Table* t) {
  for (std::size_t c = 0; c < t->columns.size(); ++c) {
    const int dir = t->columns[c].direction;
    if (dir == 0) continue;
    double best = dir > 0 ? -INFINITY : INFINITY;
    for (const RowResult& r : t->rows)
      if (r.cells[c].has_value) best = dir > 0 ? std::max(best, r.cells[c].mean) : std::min(best, r.cells[c].mean);
    for (RowResult& r : t->rows)
      if (r.cells[c].has_value && std::isfinite(best) && r.cells[c].mean == best)
        r.cells[c].best = true;
  }
}

using CellValues = std::map<std::pair<std::string, std::int64_t>, double>;

// Where matched seeds cannot decide (one seed per scene, as a submission usually has): the
// pairs are scenes, each row's mean over the seeds it has there, tested over scenes.
PairedTest OverScenes(const CellValues& row, const CellValues& ref, double alpha) {
  std::map<std::string, std::vector<double>> a, b;
  for (const auto& [k, v] : row) a[k.first].push_back(v);
  for (const auto& [k, v] : ref) b[k.first].push_back(v);
  std::vector<PairedValue> pairs;
  for (const auto& [scene, v] : a)
    if (auto it = b.find(scene); it != b.end()) pairs.push_back({"", Mean(v), Mean(it->second)});
  PairedTest t = PairedSeedTest(pairs, alpha);  // one block: a paired t-test over scenes
  t.over_scenes = true;
  t.scenes = static_cast<int>(pairs.size());
  return t;
}

// Paired tests of every row's quality columns against the reference row, scene by scene.
void PairedTests(const std::vector<RowValues>& values, double alpha, Table* t) {
  std::size_t ref = 0;
  for (std::size_t i = 0; i < t->rows.size(); ++i)
    if (t->rows[i].is_reference) ref = i;
  for (std::size_t i = 0; i < t->rows.size(); ++i) {
    for (std::size_t c = 0; c < t->columns.size(); ++c) {
      std::vector<PairedValue> pairs;
      const bool tested = i != ref && t->columns[c].quality && t->columns[c].computable;
      if (tested) {
        for (const auto& [k, v] : values[i][c]) {
          if (auto it = values[ref][c].find(k); it != values[ref][c].end())
            pairs.push_back({k.first, v, it->second});
        }
      }
      PairedTest test = PairedSeedTest(pairs, alpha);
      if (tested && !test.testable) {
        if (PairedTest s = OverScenes(values[i][c], values[ref][c], alpha); s.testable) test = s;
      }
      t->rows[i].tests.push_back(test);
    }
  }
}

// What the reader needs to know: missing and failed runs, methods to submit, partial cells,
// LPIPS, an empty scene group.
void AddFootnotes(const TableSpec& spec, const Suite& suite, Table* t) {
  bool any_incomplete = false, has_lpips = false;
  std::vector<std::string> external;  // rows of methods this suite cannot run
  for (const RowResult& r : t->rows) {
    for (const Cell& c : r.cells) any_incomplete |= c.has_value && !c.complete();
    if (r.runs == 0 && !suite.FindMethod(r.method)) {
      external.push_back(r.label);
    } else if (r.runs == 0) {
      t->footnotes.push_back(fmt::format("{}: no runs in the store{}.", r.label,
                                         r.failed ? fmt::format(" ({} failed)", r.failed) : ""));
    } else if (r.failed) {
      t->footnotes.push_back(fmt::format("{}: {} failed run(s) left out.", r.label, r.failed));
    }
  }
  if (!external.empty()) {
    t->footnotes.push_back(fmt::format(
        "{}: no runs in the store; not methods of this suite: score their renders with `hdr4d "
        "bench submit --suite {} --method NAME --supervision ldr|hdr|ldr+hdr`.",
        fmt::format("{}", fmt::join(external, ", ")), suite.name));
  }
  std::vector<std::string> added;
  for (const RowResult& r : t->rows)
    if (r.added) added.push_back(r.label);
  if (!added.empty()) {
    t->footnotes.push_back(fmt::format(
        "{}: not rows of this suite's tables; added from the store because they fit this "
        "table's layout (external: scored with `hdr4d bench submit`). Their coverage is the "
        "scenes of this table and the seeds they have; where one seed per scene leaves the seed "
        "test undecided, the paired test is over scenes.",
        fmt::join(added, ", ")));
  }
  for (const RowResult& r : t->rows) {
    if (r.identical_frames == 0) continue;
    t->footnotes.push_back(fmt::format(
        "{}: {} frame value(s) of images identical to the ground truth (PSNR +inf) left out of "
        "its means, as `hdr4d eval` does; a cell with no other value is -.",
        r.label, r.identical_frames));
  }
  for (const Column& c : t->columns) has_lpips |= !c.computable;
  if (any_incomplete)
    t->footnotes.push_back(
        "[k/n]: only k of the n scene x seed runs are in the store; the cell is "
        "the mean of those k.");
  if (has_lpips) t->footnotes.push_back(kLpipsNote);
  if (t->scenes.empty())
    t->footnotes.push_back(
        fmt::format("No scene of group '{}' in this suite: add dataset folders "
                    "with \"group\": \"{}\" to its scenes.",
                    spec.scene_group, spec.scene_group));
}

Table Build(const TableSpec& spec,
            const Suite& suite,
            const std::vector<RunSummary>& runs,
            const TableOptions& options,
            std::vector<Column> columns) {
  Table t;
  t.id = spec.id;
  t.title = spec.title;
  t.note = spec.note;
  t.reference = spec.reference;
  t.columns = std::move(columns);
  t.scenes = GroupScenes(suite, spec.scene_group);
  t.seeds = suite.seeds;
  t.budget = TableBudget(suite, options.budget);
  t.variant = TableVariant(suite, options.variant);
  t.protocol = options.hdr_psnr_key.empty()
                   ? HdrProtocolDescription(options.protocol)
                   : "the metric keys " + options.hdr_psnr_key + " and " + options.hdr_ssim_key;
  const Index ix = BuildIndex(runs, t.budget, t.variant);
  std::vector<RowValues> values;  // values[row][column][(scene, seed)]
  for (const PlannedRow& p : PlanRows(spec, suite, ix, t.scenes, t.columns, options)) {
    t.rows.push_back(BuildRow(p.row, spec, suite, ix, t, &values.emplace_back()));
    t.rows.back().added = p.added;
  }
  MarkBest(&t);
  PairedTests(values, options.alpha, &t);
  AddFootnotes(spec, suite, &t);
  return t;
}
}  // namespace

std::string CoverageText(const RowResult& r, std::size_t table_scenes) {
  const std::size_t seeds = r.seeds_with_runs.size();
  return fmt::format("{}/{} scenes, {} seed{}", r.scenes_with_runs, table_scenes, seeds,
                     seeds == 1 ? "" : "s");
}

std::string RowName(const RowResult& r, std::size_t table_scenes) {
  if (r.external) return fmt::format("{} (external; {})", r.label, CoverageText(r, table_scenes));
  if (r.added) return fmt::format("{} ({})", r.label, CoverageText(r, table_scenes));
  return r.label;
}

std::vector<std::string> KnownRowNames(const Suite& suite, const std::vector<RunSummary>& runs,
                                       const TableOptions& options) {
  TableOptions all = options;
  all.methods.clear();
  std::set<std::string> names;
  for (const TableSpec& spec : suite.tables) {
    for (const RowResult& r : BuildTable(spec, suite, runs, all).rows) {
      names.insert(r.label);
      names.insert(r.method);
    }
  }
  return {names.begin(), names.end()};
}

void CheckRowNames(const Suite& suite, const std::vector<RunSummary>& runs,
                   const TableOptions& options) {
  if (options.methods.empty()) return;
  const std::vector<std::string> known = KnownRowNames(suite, runs, options);
  for (const std::string& name : options.methods) {
    if (std::find(known.begin(), known.end(), name) == known.end())
      Fail("--methods {}: no row or method of that name in the tables of suite '{}' (known: {})",
           name, suite.name, fmt::join(known, ", "));
  }
}

bool HasSelectedRows(const Table& t, const TableOptions& options) {
  if (options.methods.empty()) return true;
  for (const RowResult& r : t.rows)
    if (!r.is_reference) return true;
  return false;
}

std::string SupervisionLabel(const std::string& s) {
  if (s == "ldr") return "LDR";
  if (s == "hdr") return "HDR";
  if (s == "ldr+hdr") return "LDR+HDR";
  return s;
}

// Direction of a metric key not known in advance (keys added to `hdr4d eval` later).
std::string ArrowOf(const Column& c) { return c.direction > 0 ? "↑" : c.direction < 0 ? "↓" : ""; }

std::string FormatValue(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";  // never "inf": the means are over finite values
  return fmt::format("{:.{}f}", v, digits);
}

std::string TableBudget(const Suite& suite, const std::string& budget) {
  if (budget.empty()) return suite.budgets.back().Label();
  std::vector<std::string> known;
  for (const auto& b : suite.budgets) known.push_back(b.Label());
  if (std::find(known.begin(), known.end(), budget) == known.end())
    Fail("--budget {}: not a budget of suite '{}' (known: {})", budget, suite.name,
         fmt::join(known, ", "));
  return budget;
}

std::string TableVariant(const Suite& suite, const std::string& variant) {
  if (variant.empty()) return suite.variants.front().name;
  std::vector<std::string> known;
  for (const auto& v : suite.variants) known.push_back(v.name.empty() ? "\"\"" : v.name);
  for (const auto& v : suite.variants)
    if (v.name == variant) return variant;
  Fail("--variant {}: not a variant of suite '{}' (known: {})", variant, suite.name,
       fmt::join(known, ", "));
}

HdrProtocol ParseHdrProtocol(const std::string& name) {
  if (name == "own_max") return HdrProtocol::kOwnMax;
  if (name == "gt_max") return HdrProtocol::kGtMax;
  if (name == "pu21") return HdrProtocol::kPu21;
  Fail("--protocol {}: not one of own_max, gt_max, pu21", name);
}

std::string HdrProtocolDescription(HdrProtocol p) {
  switch (p) {
    case HdrProtocol::kOwnMax:
      return "mu-law PSNR/SSIM, each image divided by its own maximum (HDR-4DGS protocol)";
    case HdrProtocol::kGtMax:
      return "mu-law PSNR/SSIM, both images divided by the ground truth's maximum (HDR-NeRF "
             "protocol)";
    case HdrProtocol::kPu21:
      return "PU21 PSNR/SSIM of absolute luminance (4000 / ground-truth maximum)";
  }
  return "";
}

std::vector<RunSummary> SuiteRuns(const ResultsStore& store, const Suite& suite) {
  std::map<std::string, std::string> checksum;  // scene -> the suite's data
  std::vector<RunSummary> all = store.Summaries(), out;
  for (const RunSummary& r : all)
    if (r.label.suite == suite.name) checksum[r.label.scene] = r.data_checksum;
  for (RunSummary& r : all) {
    if (r.label.suite == suite.name) {
      out.push_back(std::move(r));
    } else if (r.label.suite == "external" && suite.FindScene(r.label.scene)) {
      // Comparable only on the same data.
      const auto it = checksum.find(r.label.scene);
      if (it == checksum.end() || it->second == r.data_checksum) out.push_back(std::move(r));
    }
  }
  return out;
}

Table BuildTable(const TableSpec& spec, const Suite& suite, const std::vector<RunSummary>& runs,
                 const TableOptions& options) {
  if (options.hdr_psnr_key.empty() != options.hdr_ssim_key.empty())
    Fail("tables: give both HDR keys (PSNR and SSIM) or neither");
  if (!options.hdr_psnr_key.empty()) {
    const std::set<std::string> known = MetricKeys(runs);
    for (const std::string& key : {options.hdr_psnr_key, options.hdr_ssim_key})
      RequireMetricKey("--hdr-keys", key, known, "runs of suite '" + suite.name + "'");
  }
  return Build(spec, suite, runs, options,
               spec.layout == "main" ? MainColumns(options) : HdrColumns(options, true));
}

Table BuildAllMetricsTable(const TableSpec& spec, const Suite& suite,
                           const std::vector<RunSummary>& runs, const TableOptions& options) {
  std::set<std::string> keys;
  std::set<std::pair<std::string, std::string>> rows;
  for (const TableRow& r : spec.rows) rows.insert({r.method, r.supervision});
  std::set<std::string> named;  // methods some table places; the others may be added rows
  for (const TableSpec& t : suite.tables)
    for (const TableRow& r : t.rows) named.insert(r.method);
  for (const RunSummary& r : runs)
    if (rows.count({r.label.method, r.label.supervision}) || !named.count(r.label.method))
      for (const auto& [k, v] : r.metrics) keys.insert(k);
  // LDR keys first, then the HDR protocols, then anything newer, alphabetically.
  const std::vector<std::string> order = {"psnr", "psnr_channel_mean", "ssim", "flip", "mu_psnr",
                                          "mu_ssim", "mu_psnr_gt_max", "mu_ssim_gt_max",
                                          "pu21_psnr", "pu21_ssim", "hdr_flip", "hdr_flip_aligned"};
  std::vector<Column> columns;
  auto digits = [](const std::string& k) {
    return k.find("ssim") != std::string::npos || k.find("flip") != std::string::npos ? 3 : 2;
  };
  for (const std::string& k : order)
    if (keys.erase(k)) columns.push_back({k, "", k, GuessDirection(k), digits(k)});
  for (const std::string& k : keys)
    columns.push_back({k, "", k, GuessDirection(k), k.find("psnr") != std::string::npos ? 2 : 3});
  columns.push_back({"gaussians", "", "Gaussians", 0, 0, true, false});
  columns.push_back({"peak_rss_mb", "", "Peak memory (MB)", -1, 0, true, false});
  TableSpec all = spec;
  all.id = spec.id + "-all";
  all.title = spec.title + ": every metric";
  Table t = Build(all, suite, runs, options, std::move(columns));
  t.footnotes.push_back("Columns without an arrow have no single better direction; none is marked best.");
  return t;
}

std::string PerSceneMarkdown(const TableSpec& spec, const Suite& suite,
                             const std::vector<RunSummary>& runs, const TableOptions& options,
                             const Column& column) {
  const std::string budget = TableBudget(suite, options.budget);
  const std::string variant = TableVariant(suite, options.variant);
  const Index ix = BuildIndex(runs, budget, variant);
  const std::vector<std::string> scenes = GroupScenes(suite, spec.scene_group);
  std::vector<TableRow> rows;
  for (const PlannedRow& p : PlanRows(spec, suite, ix, scenes,
                                      spec.layout == "main" ? MainColumns(options)
                                                            : HdrColumns(options, true),
                                      options))
    rows.push_back(p.row);
  std::string md = fmt::format("{} {}, mean over seeds (best per scene in bold):\n\n", spec.id, column.key);
  md += "| scene (seeds) |";
  for (const TableRow& r : rows) md += fmt::format(" {} |", r.label);
  md += "\n|---|";
  for (std::size_t i = 0; i < rows.size(); ++i) md += "---|";
  md += "\n";
  std::vector<std::vector<double>> scene_means(rows.size());
  auto line = [&](const std::string& label, const std::vector<std::optional<double>>& v) {
    double best = column.direction >= 0 ? -INFINITY : INFINITY;
    for (const auto& x : v)
      if (x) best = column.direction >= 0 ? std::max(best, *x) : std::min(best, *x);
    md += fmt::format("| {} |", label);
    for (const auto& x : v) {
      if (!x) {
        md += " - |";
        continue;
      }
      const std::string s = FormatValue(*x, column.digits);
      md += fmt::format(" {} |", (column.direction != 0 && *x == best ? "**" + s + "**" : s));
    }
    md += "\n";
  };
  for (const std::string& scene : scenes) {
    std::vector<std::optional<double>> row;
    int seeds_seen = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      std::vector<double> v;
      for (std::int64_t seed : RowSeeds(suite, ix, rows[i].method)) {
        const auto it = ix.ok.find({rows[i].method, rows[i].supervision, scene, seed});
        if (it == ix.ok.end()) continue;
        if (auto x = ValueOf(*it->second, column)) v.push_back(*x);
      }
      seeds_seen = std::max<int>(seeds_seen, static_cast<int>(v.size()));
      if (v.empty()) {
        row.push_back(std::nullopt);
      } else {
        row.push_back(Mean(v));
        scene_means[i].push_back(Mean(v));
      }
    }
    line(fmt::format("{} ({})", scene, seeds_seen), row);
  }
  std::vector<std::optional<double>> mean_row;
  for (const auto& m : scene_means)
    mean_row.push_back(m.size() == scenes.size() && !m.empty() ? std::optional<double>(Mean(m))
                                                                : std::nullopt);
  line("mean over scenes", mean_row);
  return md;
}

}  // namespace hdr4d::bench
