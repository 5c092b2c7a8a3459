#include "benchmark/tables.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "core/error.h"

namespace hdr4d::bench {
namespace {

using Key = std::tuple<std::string, std::string, std::string, std::int64_t>;  // method, sup, scene, seed

const char* kLpipsNote =
    "LPIPS: not computed. It needs the LPIPS network weights, which cannot be obtained on these "
    "machines; no substitute is reported.";

std::vector<Column> HdrColumns(const TableOptions& o, bool with_lpips) {
  std::string psnr = "mu_psnr", ssim = "mu_ssim";
  if (o.protocol == HdrProtocol::kGtMax) psnr = "mu_psnr_gt_max", ssim = "mu_ssim_gt_max";
  if (o.protocol == HdrProtocol::kPu21) psnr = "pu21_psnr", ssim = "pu21_ssim";
  if (!o.hdr_psnr_key.empty()) psnr = o.hdr_psnr_key, ssim = o.hdr_ssim_key;
  std::vector<Column> c = {{psnr, "HDR", "PSNR", 1, 2}, {ssim, "HDR", "SSIM", 1, 3}};
  if (with_lpips) c.push_back({"lpips_hdr", "HDR", "LPIPS", -1, 3, false});
  return c;
}

std::vector<Column> MainColumns(const TableOptions& o) {
  std::vector<Column> c = HdrColumns(o, true);
  c.push_back({"psnr", "LDR", "PSNR", 1, 2});
  c.push_back({"ssim", "LDR", "SSIM", 1, 3});
  c.push_back({"lpips", "LDR", "LPIPS", -1, 3, false});
  c.push_back({"train_minutes", "", "Training time (min)", -1, 2, true, false});
  c.push_back({"fps", "", "Inference (fps)", 1, 1, true, false});
  return c;
}

std::string SupervisionLabel(const std::string& s) {
  if (s == "ldr") return "LDR";
  if (s == "hdr") return "HDR";
  if (s == "ldr+hdr") return "LDR+HDR";
  return s;
}

// Direction of a metric key not known in advance (keys added to `hdr4d eval` later).
int GuessDirection(const std::string& key) {
  for (const char* up : {"psnr", "ssim", "corr"})
    if (key.find(up) != std::string::npos) return 1;
  for (const char* down : {"lpips", "mse", "error", "rmse"})
    if (key.find(down) != std::string::npos) return -1;
  return 0;  // e.g. a slope, where the best is 1, not the largest
}

std::string ArrowOf(const Column& c) { return c.direction > 0 ? "↑" : c.direction < 0 ? "↓" : ""; }

std::string Format(double v, int digits) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:.{}f}", v, digits);
}

struct Index {
  std::map<Key, const RunSummary*> ok;
  std::map<std::pair<std::string, std::string>, int> failed;  // (method, sup) -> count
  std::map<std::string, std::set<std::int64_t>> seeds_of_method;
};

Index BuildIndex(const std::vector<RunSummary>& runs, const std::string& budget,
                 const std::string& variant) {
  Index ix;
  for (const RunSummary& r : runs) {
    const RunLabel& l = r.label;
    const bool external = r.source == "submit";
    if (!external && (l.budget != budget || l.variant != variant)) continue;
    if (r.status != "ok") {
      ++ix.failed[{l.method, l.supervision}];
      continue;
    }
    ix.ok[{l.method, l.supervision, l.scene, l.seed}] = &r;
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
  if (std::isnan(v)) return std::nullopt;
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

Table Build(const TableSpec& spec, const Suite& suite, const std::vector<RunSummary>& runs,
            const TableOptions& options, std::vector<Column> columns) {
  Table t;
  t.id = spec.id;
  t.title = spec.title;
  t.note = spec.note;
  t.reference = spec.reference;
  t.columns = std::move(columns);
  t.scenes = GroupScenes(suite, spec.scene_group);
  t.seeds = suite.seeds;
  t.budget = options.budget.empty() ? suite.budgets.back().Label() : options.budget;
  t.variant = options.variant.empty() ? suite.variants.front().name : options.variant;
  t.protocol = options.hdr_psnr_key.empty()
                   ? HdrProtocolDescription(options.protocol)
                   : "the metric keys " + options.hdr_psnr_key + " and " + options.hdr_ssim_key;
  const Index ix = BuildIndex(runs, t.budget, t.variant);

  // values[row][column][(scene, seed)]
  std::vector<std::vector<std::map<std::pair<std::string, std::int64_t>, double>>> values;
  for (const TableRow& row : spec.rows) {
    RowResult rr{row.label, row.method, row.supervision};
    rr.is_reference = row.label == spec.reference;
    const std::vector<std::int64_t> seeds = RowSeeds(suite, ix, row.method);
    rr.expected = static_cast<int>(t.scenes.size() * seeds.size());
    if (auto f = ix.failed.find({row.method, row.supervision}); f != ix.failed.end())
      rr.failed = f->second;
    auto& row_values = values.emplace_back(t.columns.size());
    for (const std::string& scene : t.scenes) {
      for (std::int64_t seed : seeds) {
        const auto it = ix.ok.find({row.method, row.supervision, scene, seed});
        if (it == ix.ok.end()) continue;
        ++rr.runs;
        for (std::size_t c = 0; c < t.columns.size(); ++c) {
          if (!t.columns[c].computable) continue;
          if (const auto v = ValueOf(*it->second, t.columns[c])) row_values[c][{scene, seed}] = *v;
        }
      }
    }
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      Cell cell;
      cell.expected = rr.expected;
      const auto& vals = row_values[c];
      cell.runs = static_cast<int>(vals.size());
      if (!vals.empty()) {
        cell.has_value = true;
        std::vector<double> all, complete_seed_means;
        for (const auto& [k, v] : vals) all.push_back(v);
        for (std::int64_t seed : seeds) {
          std::vector<double> per_seed;
          for (const std::string& scene : t.scenes)
            if (auto it = vals.find({scene, seed}); it != vals.end()) per_seed.push_back(it->second);
          if (per_seed.size() == t.scenes.size()) complete_seed_means.push_back(Mean(per_seed));
        }
        cell.mean = cell.complete() ? Mean(complete_seed_means) : Mean(all);
        if (complete_seed_means.size() >= 2) {
          cell.spread = SampleStdDev(complete_seed_means);
          cell.has_spread = true;
        }
      }
      rr.cells.push_back(cell);
    }
    t.rows.push_back(std::move(rr));
  }
  // Best per column.
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    const int dir = t.columns[c].direction;
    if (dir == 0) continue;
    double best = dir > 0 ? -INFINITY : INFINITY;
    for (const RowResult& r : t.rows)
      if (r.cells[c].has_value) best = dir > 0 ? std::max(best, r.cells[c].mean) : std::min(best, r.cells[c].mean);
    for (RowResult& r : t.rows)
      if (r.cells[c].has_value && r.cells[c].mean == best) r.cells[c].best = true;
  }
  // Paired tests against the reference row.
  std::size_t ref = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.rows[i].is_reference) ref = i;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      std::vector<PairedValue> pairs;
      if (i != ref && t.columns[c].quality && t.columns[c].computable) {
        for (const auto& [k, v] : values[i][c]) {
          if (auto it = values[ref][c].find(k); it != values[ref][c].end())
            pairs.push_back({k.first, v, it->second});
        }
      }
      t.rows[i].tests.push_back(PairedSeedTest(pairs, options.alpha));
    }
  }
  // What the reader needs to know.
  bool any_incomplete = false, has_lpips = false;
  std::vector<std::string> external;  // rows of methods this suite cannot run
  for (const RowResult& r : t.rows) {
    for (const Cell& c : r.cells) any_incomplete |= c.has_value && !c.complete();
    if (r.runs == 0 && !suite.FindMethod(r.method)) {
      external.push_back(r.label);
    } else if (r.runs == 0) {
      t.footnotes.push_back(fmt::format("{}: no runs in the store{}.", r.label,
                                        r.failed ? fmt::format(" ({} failed)", r.failed) : ""));
    } else if (r.failed) {
      t.footnotes.push_back(fmt::format("{}: {} failed run(s) left out.", r.label, r.failed));
    }
  }
  if (!external.empty()) {
    t.footnotes.push_back(fmt::format(
        "{}: no runs in the store; not methods of this suite: score their renders with `hdr4d "
        "bench submit --suite {} --method NAME --supervision ldr|hdr|ldr+hdr`.",
        fmt::format("{}", fmt::join(external, ", ")), suite.name));
  }
  for (const Column& c : t.columns) has_lpips |= !c.computable;
  if (any_incomplete)
    t.footnotes.push_back("[k/n]: only k of the n scene x seed runs are in the store; the cell is "
                          "the mean of those k.");
  if (has_lpips) t.footnotes.push_back(kLpipsNote);
  if (t.scenes.empty())
    t.footnotes.push_back(fmt::format("No scene of group '{}' in this suite: add dataset folders "
                                      "with \"group\": \"{}\" to its scenes.",
                                      spec.scene_group, spec.scene_group));
  return t;
}

std::string CellText(const Cell& c, const Column& col, bool markdown) {
  if (!col.computable) return "n/a";
  if (!c.has_value) return "-";
  std::string v = Format(c.mean, col.digits);
  if (c.best) v = markdown ? "**" + v + "**" : "\\textbf{" + v + "}";
  if (c.has_spread) v += (markdown ? " ± " : " $\\pm$ ") + Format(c.spread, col.digits);
  if (!c.complete()) v += fmt::format(" [{}/{}]", c.runs, c.expected);
  return v;
}

std::string HeaderOf(const Column& c) {
  return (c.group.empty() ? "" : c.group + " ") + c.label + ArrowOf(c);
}

std::string Join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

std::string Intro(const Table& t) {
  std::vector<std::string> seeds;
  for (auto s : t.seeds) seeds.push_back(std::to_string(s));
  return fmt::format(
      "Scenes ({}): {}; seeds {}; budget {}{}. HDR columns: {}. Each cell: mean over scenes "
      "(averaged over seeds) ± sample standard deviation over seeds of the mean over scenes; best "
      "per column in bold.",
      t.scenes.size(), t.scenes.empty() ? "none" : Join(t.scenes, ", "), Join(seeds, ", "),
      t.budget, t.variant.empty() ? "" : ", variant " + t.variant, t.protocol);
}

std::string LatexEscape(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (s.compare(i, 3, "†") == 0) {
      out += "$^\\dagger$";
      i += 2;
    } else if (s.compare(i, 2, "±") == 0) {
      out += "$\\pm$";
      i += 1;
    } else if (s.compare(i, 3, "↑") == 0) {
      out += "$\\uparrow$";
      i += 2;
    } else if (s.compare(i, 3, "↓") == 0) {
      out += "$\\downarrow$";
      i += 2;
    } else if (std::string("&%$#_{}").find(c) != std::string::npos) {
      out.push_back('\\');
      out.push_back(c);
    } else if (c == '~') {
      out += "\\textasciitilde{}";
    } else if (c == '^') {
      out += "\\textasciicircum{}";
    } else if (c == '\\') {
      out += "\\textbackslash{}";
    } else {
      out += c;
    }
  }
  return out;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q.push_back('"');
    q.push_back(c);
  }
  q.push_back('"');
  return q;
}

}  // namespace

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
  return Build(spec, suite, runs, options,
               spec.layout == "main" ? MainColumns(options) : HdrColumns(options, true));
}

Table BuildAllMetricsTable(const TableSpec& spec, const Suite& suite,
                           const std::vector<RunSummary>& runs, const TableOptions& options) {
  std::set<std::string> keys;
  std::set<std::pair<std::string, std::string>> rows;
  for (const TableRow& r : spec.rows) rows.insert({r.method, r.supervision});
  for (const RunSummary& r : runs)
    if (rows.count({r.label.method, r.label.supervision}))
      for (const auto& [k, v] : r.metrics) keys.insert(k);
  // LDR keys first, then the HDR protocols, then anything newer, alphabetically.
  const std::vector<std::string> order = {"psnr", "psnr_channel_mean", "ssim", "mu_psnr",
                                          "mu_ssim", "mu_psnr_gt_max", "mu_ssim_gt_max",
                                          "pu21_psnr", "pu21_ssim"};
  std::vector<Column> columns;
  for (const std::string& k : order)
    if (keys.erase(k)) columns.push_back({k, "", k, GuessDirection(k), k.find("ssim") != std::string::npos ? 3 : 2});
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
  const std::string budget = options.budget.empty() ? suite.budgets.back().Label() : options.budget;
  const std::string variant = options.variant.empty() ? suite.variants.front().name : options.variant;
  const Index ix = BuildIndex(runs, budget, variant);
  const std::vector<std::string> scenes = GroupScenes(suite, spec.scene_group);
  std::string md = fmt::format("{} {}, mean over seeds (best per scene in bold):\n\n", spec.id, column.key);
  md += "| scene (seeds) |";
  for (const TableRow& r : spec.rows) md += fmt::format(" {} |", r.label);
  md += "\n|---|";
  for (std::size_t i = 0; i < spec.rows.size(); ++i) md += "---|";
  md += "\n";
  std::vector<std::vector<double>> scene_means(spec.rows.size());
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
      const std::string s = Format(*x, column.digits);
      md += fmt::format(" {} |", (column.direction != 0 && *x == best ? "**" + s + "**" : s));
    }
    md += "\n";
  };
  for (const std::string& scene : scenes) {
    std::vector<std::optional<double>> row;
    int seeds_seen = 0;
    for (std::size_t i = 0; i < spec.rows.size(); ++i) {
      std::vector<double> v;
      for (std::int64_t seed : RowSeeds(suite, ix, spec.rows[i].method)) {
        const auto it = ix.ok.find({spec.rows[i].method, spec.rows[i].supervision, scene, seed});
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

std::string ToMarkdown(const Table& t) {
  std::string md = fmt::format("### {}: {}\n\n{}\n\n", t.id, t.title, Intro(t));
  if (!t.note.empty()) md += t.note + "\n\n";
  md += "| Row | Method | Supervision |";
  for (const Column& c : t.columns) md += fmt::format(" {} |", HeaderOf(c));
  md += "\n|---|---|---|";
  for (std::size_t i = 0; i < t.columns.size(); ++i) md += "---|";
  md += "\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    md += fmt::format("| {} | {} | {} |", i + 1, r.label, SupervisionLabel(r.supervision));
    for (std::size_t c = 0; c < t.columns.size(); ++c)
      md += fmt::format(" {} |", CellText(r.cells[c], t.columns[c], true));
    md += "\n";
  }
  if (!t.footnotes.empty()) {
    md += "\n";
    for (const std::string& f : t.footnotes) md += fmt::format("- {}\n", f);
  }
  return md;
}

std::string PairedTestsMarkdown(const Table& t) {
  std::vector<std::size_t> cols;
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].quality && t.columns[c].computable) cols.push_back(c);
  std::string md = fmt::format(
      "Paired tests of {} against '{}': mean difference (row - reference) over the (scene, "
      "seed) pairs both have, two-sided t-test against the seed-to-seed variance of the "
      "differences pooled within scenes (n - scenes degrees of freedom), alpha 0.05.\n\n",
      t.id, t.reference);
  md += "| Row |";
  for (std::size_t c : cols) md += fmt::format(" {} |", HeaderOf(t.columns[c]));
  md += "\n|---|";
  for (std::size_t i = 0; i < cols.size(); ++i) md += "---|";
  md += "\n";
  for (const RowResult& r : t.rows) {
    if (r.is_reference) continue;
    md += fmt::format("| {} |", r.label);
    for (std::size_t c : cols) {
      const PairedTest& p = r.tests[c];
      if (p.pairs == 0) {
        md += " - |";
      } else if (!p.testable) {
        md += fmt::format(" {:+.{}f}, n/a (1 seed) |", p.mean_difference, t.columns[c].digits);
      } else {
        md += fmt::format(" {:+.{}f}, p = {:.2g}: {} |", p.mean_difference, t.columns[c].digits,
                          p.p, p.significant ? "**exceeds seed noise**" : "within seed noise");
      }
    }
    md += "\n";
  }
  return md;
}

std::string ToLatex(const Table& t) {
  std::string spec = "c|l|l";
  std::string prev = "\x01";
  for (const Column& c : t.columns) {
    spec += (c.group != prev || c.group.empty()) ? "|c" : "c";
    prev = c.group;
  }
  std::string tex = "% " + t.id + ": generated by hdr4d bench table\n";
  tex += "\\begin{table}[t]\n\\centering\n";
  std::string caption = LatexEscape(t.title + ". " + Intro(t));
  for (const std::string& f : t.footnotes) caption += " " + LatexEscape(f);
  tex += "\\caption{" + caption + "}\n\\label{tab:" + t.id + "}\n";
  tex += "\\begin{tabular}{" + spec + "}\n\\toprule\n";
  // Group header (HDR / LDR) over the metric columns, then the column names.
  std::string groups = "\\multirow{2}{*}{Row} & \\multirow{2}{*}{Method} & \\multirow{2}{*}{Supervision}";
  std::string names = " & &";
  for (std::size_t c = 0; c < t.columns.size();) {
    std::size_t e = c + 1;
    while (e < t.columns.size() && !t.columns[c].group.empty() && t.columns[e].group == t.columns[c].group) ++e;
    if (t.columns[c].group.empty()) {
      groups += " & " + LatexEscape(t.columns[c].label);
      names += " & " + LatexEscape(ArrowOf(t.columns[c]));
    } else {
      groups += fmt::format(" & \\multicolumn{{{}}}{{c|}}{{{}}}", e - c, t.columns[c].group);
      for (std::size_t k = c; k < e; ++k)
        names += " & " + LatexEscape(t.columns[k].label + ArrowOf(t.columns[k]));
    }
    c = e;
  }
  tex += groups + " \\\\\n" + names + " \\\\\n\\midrule\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    tex += fmt::format("{} & {} & {}", i + 1, LatexEscape(r.label),
                       LatexEscape(SupervisionLabel(r.supervision)));
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      std::string cell = CellText(r.cells[c], t.columns[c], false);
      if (cell.find('[') != std::string::npos) cell = cell.substr(0, cell.find(" [")) + "$^\\ast$";
      tex += " & " + cell;
    }
    tex += " \\\\\n";
  }
  tex += "\\bottomrule\n\\end{tabular}\n\\end{table}\n";
  return tex;
}

std::string ToCsv(const Table& t) {
  std::string csv =
      "table,row,label,method,supervision,column,key,mean,sd_over_seeds,runs,expected_runs,best,"
      "diff_vs_reference,p_vs_reference,exceeds_seed_noise,protocol,budget\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      const Cell& cell = r.cells[c];
      const PairedTest& p = r.tests[c];
      const Column& col = t.columns[c];
      csv += fmt::format(
          "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", t.id, i + 1, CsvField(r.label),
          CsvField(r.method), r.supervision, CsvField(HeaderOf(col)), col.key,
          !col.computable ? "not computable" : cell.has_value ? Format(cell.mean, 6) : "",
          cell.has_spread ? Format(cell.spread, 6) : "", cell.runs, cell.expected,
          cell.best ? 1 : 0, p.pairs ? Format(p.mean_difference, 6) : "",
          p.testable ? fmt::format("{:.6g}", p.p) : "",
          p.testable ? (p.significant ? "yes" : "no") : "", CsvField(t.protocol), t.budget);
    }
  }
  return csv;
}

}  // namespace hdr4d::bench
