#include "benchmark/findings.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "benchmark/tables.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace {

// A row's metric values by (scene, seed), from the runs the tables read.
using SeedValues = std::map<std::pair<std::string, std::int64_t>, double>;

SeedValues FindingRowValues(const std::vector<RunSummary>& runs, const TableRow& row,
                            const std::vector<std::string>& scenes, const std::string& metric,
                            const std::string& budget, const std::string& variant) {
  const std::set<std::string> wanted(scenes.begin(), scenes.end());
  SeedValues out;
  for (const RunSummary& r : runs) {
    const RunLabel& l = r.label;
    if (r.status != "ok" || l.method != row.method || l.supervision != row.supervision) continue;
    if (!wanted.count(l.scene)) continue;
    if (r.source != "submit" && (l.budget != budget || l.variant != variant)) continue;
    if (auto it = r.metrics.find(metric); it != r.metrics.end() && std::isfinite(it->second))
      out[{l.scene, l.seed}] = it->second;
  }
  return out;
}

std::string BudgetOf(const Suite& suite, const FindingsOptions& o) {
  return TableBudget(suite, o.budget);
}
std::string VariantOf(const Suite& suite, const FindingsOptions& o) {
  return TableVariant(suite, o.variant);
}

std::string OutcomeOf(const PairedTest& t, int direction) {
  if (!t.testable) return "not testable";
  if (t.mean_difference == 0 && t.seed_sd == 0) return "identical";
  if (!t.significant || t.mean_difference == 0) return "within noise";
  return t.mean_difference * direction > 0 ? "row better" : "reference better";
}

// The verdict from the comparisons, and the ones that decide it in words.
void Decide(Finding* f) {
  std::vector<std::string> better, within, identical, untested;
  for (const FindingComparison& c : f->against) {
    if (c.outcome == "row better") better.push_back(c.label);
    else if (c.outcome == "within noise") within.push_back(c.label);
    else if (c.outcome == "identical") identical.push_back(c.label);
    else if (c.outcome == "not testable") untested.push_back(c.label);
  }
  if (f->against.empty()) {
    f->verdict = "undecided";
    f->why = "no other row to compare with";
  } else if (!better.empty()) {
    f->verdict = "does not hold";
    f->why = fmt::format("{} beat{} {} beyond the seed noise", fmt::join(better, ", "),
                         better.size() == 1 ? "s" : "", f->reference);
  } else if (within.empty() && identical.empty() && untested.empty()) {
    f->verdict = "holds";
    f->why = fmt::format("{} beats each other row beyond the seed noise", f->reference);
  } else {
    f->verdict = "undecided";
    std::vector<std::string> parts;
    if (!within.empty()) parts.push_back(fmt::format("{}: within the seed noise", fmt::join(within, ", ")));
    if (!identical.empty())
      parts.push_back(fmt::format("{}: identical results (the setting changes nothing here)", fmt::join(identical, ", ")));
    if (!untested.empty()) parts.push_back(fmt::format("{}: no pairs with two seeds", fmt::join(untested, ", ")));
    f->why = fmt::format("{}", fmt::join(parts, "; "));
  }
}

// Scenes where the reference and every compared row have a value, and the seeds every row has
// on every such scene.
void Coverage(const std::vector<SeedValues>& rows, const std::vector<std::string>& scenes,
              Finding* f) {
  std::optional<std::set<std::int64_t>> shared;
  for (const std::string& scene : scenes) {
    std::optional<std::set<std::int64_t>> here;  // seeds every row has on this scene
    for (const SeedValues& v : rows) {
      std::set<std::int64_t> seeds;
      for (const auto& [k, x] : v)
        if (k.first == scene && (!here || here->count(k.second))) seeds.insert(k.second);
      here = seeds;
    }
    if (!here || here->empty()) continue;
    f->scenes_covered.push_back(scene);
    if (!shared) shared = *here;
    std::set<std::int64_t> both;
    for (std::int64_t s : *shared)
      if (here->count(s)) both.insert(s);
    shared = both;
  }
  if (shared) f->seeds.assign(shared->begin(), shared->end());
}

// One row over the covered scenes and the shared seeds: the mean over seeds of its mean over
// those scenes, and from two seeds their sample sd. Used where the table is not complete (its
// cells then average whatever runs there are), so that every mean a finding shows is over what
// its paired tests compare.
struct CoveredMean {
  bool has = false, has_sd = false;
  double mean = 0, sd = 0;
};

CoveredMean OverCoverage(const SeedValues& row, const Finding& f) {
  CoveredMean out;
  if (f.seeds.empty() || f.scenes_covered.empty()) return out;
  std::vector<double> seed_means;
  for (std::int64_t seed : f.seeds) {
    std::vector<double> per_scene;
    for (const std::string& scene : f.scenes_covered)
      if (auto it = row.find({scene, seed}); it != row.end()) per_scene.push_back(it->second);
    if (per_scene.size() != f.scenes_covered.size()) return out;
    seed_means.push_back(Mean(per_scene));
  }
  out.has = true;
  out.mean = Mean(seed_means);
  out.has_sd = seed_means.size() >= 2;
  out.sd = out.has_sd ? SampleStdDev(seed_means) : 0;
  return out;
}

Finding OneFinding(const TableSpec& spec, const Suite& suite, const std::vector<RunSummary>& runs,
                   const std::string& metric, const FindingsOptions& o) {
  TableOptions to;
  to.budget = o.budget;
  to.variant = o.variant;
  to.alpha = o.alpha;
  const Table t = BuildAllMetricsTable(spec, suite, runs, to);
  Finding f{spec.id, FindingClaim(spec), spec.scene_group, metric};
  f.reference = spec.reference;
  f.table_scenes = t.scenes.size();
  std::size_t col = t.columns.size();
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].key == metric) col = c;
  f.direction = col < t.columns.size() && t.columns[col].direction < 0 ? -1 : 1;
  std::vector<SeedValues> values;
  std::optional<std::size_t> reference_values;
  std::vector<std::size_t> against_values;  // values' row of each comparison
  bool reference_has_spread = false;
  for (const RowResult& r : t.rows) {
    if (r.added) continue;
    const bool has = col < t.columns.size() && r.cells[col].has_value;
    if (!r.is_reference && !spec.finding_rows.empty() &&
        std::find(spec.finding_rows.begin(), spec.finding_rows.end(), r.label) == spec.finding_rows.end())
      continue;
    if (!r.is_reference && !has && spec.layout == "main") {
      f.left_out.push_back(r.label);
      continue;
    }
    const TableRow row{r.label, r.method, r.supervision};
    values.push_back(FindingRowValues(runs, row, t.scenes, metric, BudgetOf(suite, o), VariantOf(suite, o)));
    if (r.is_reference) {
      f.reference_has_value = has;
      f.reference_mean = has ? r.cells[col].mean : 0;
      f.reference_spread = has ? r.cells[col].spread : 0;
      reference_has_spread = has && r.cells[col].has_spread;
      reference_values = values.size() - 1;
      continue;
    }
    FindingComparison c{r.label, r.method, has ? r.cells[col].mean : 0, has};
    if (col < t.columns.size()) c.test = r.tests[col];
    c.outcome = OutcomeOf(c.test, f.direction);
    f.against.push_back(std::move(c));
    against_values.push_back(values.size() - 1);
  }
  Coverage(values, t.scenes, &f);
  f.reference_spread_scope = reference_has_spread ? "all" : "none";
  const bool partial = f.scenes_covered.size() < f.table_scenes || !reference_has_spread;
  if (partial && reference_values) {
    // Not every scene of the table has runs of every row yet: show the means over the covered
    // scenes, where the pairs are.
    f.reference_spread_scope = "none";
    const CoveredMean ref = OverCoverage(values[*reference_values], f);
    if (ref.has) f.reference_mean = ref.mean;
    if (ref.has_sd) {
      f.reference_spread = ref.sd;
      f.reference_spread_scope = "covered";
    }
    for (std::size_t k = 0; k < f.against.size(); ++k)
      if (const CoveredMean m = OverCoverage(values[against_values[k]], f); m.has)
        f.against[k].mean = m.mean;
  }
  Decide(&f);
  if (!f.left_out.empty())
    f.why += fmt::format("; left out, no runs with this metric: {}", fmt::join(f.left_out, ", "));
  if (col == t.columns.size())  // a key no run of the table has (mistyped, or not computed)
    f.why = fmt::format("no run of the table has the metric '{}'", metric);
  return f;
}

std::string SeedsText(const std::vector<std::int64_t>& seeds) {
  if (seeds.empty()) return "no seed";
  return fmt::format("seed{} {}", seeds.size() == 1 ? "" : "s", fmt::join(seeds, ","));
}

std::string CoverageLine(const Finding& f) {
  return fmt::format("{}/{} scenes ({}), {}", f.scenes_covered.size(), f.table_scenes,
                     f.scenes_covered.empty() ? "none" : fmt::format("{}", fmt::join(f.scenes_covered, ", ")),
                     SeedsText(f.seeds));
}

}  // namespace

std::string ReferenceText(const Finding& f) {
  if (!f.reference_has_value) return f.reference + " (no runs)";
  if (f.reference_spread_scope == "none") return fmt::format("{} {:.3f}", f.reference, f.reference_mean);
  return fmt::format("{} {:.3f} ± {:.3f}{}", f.reference, f.reference_mean, f.reference_spread,
                     f.reference_spread_scope == "covered" ? " (mean and seed sd over the covered scenes)" : "");
}

std::string FindingClaim(const TableSpec& spec) {
  return spec.finding.empty() ? spec.reference + " beats each other row" : spec.finding;
}

std::vector<Finding> BuildFindings(const Suite& suite, const std::vector<RunSummary>& runs,
                                   const FindingsOptions& options) {
  if (options.metrics.empty()) Fail("bench findings: no metric given");
  std::vector<Finding> out;
  bool found = false;
  for (const TableSpec& spec : suite.tables) {
    if (!options.table.empty() && spec.id != options.table) continue;
    found = true;
    if (spec.layout != "ablation" && spec.finding.empty()) {
      if (!options.table.empty())
        Fail("bench findings: table '{}' of suite '{}' is a main table that words no finding (its "
             "\"finding\" key; ablation tables state theirs by their reference row)", spec.id, suite.name);
      continue;
    }
    for (const std::string& metric : options.metrics)
      out.push_back(OneFinding(spec, suite, runs, metric, options));
  }
  if (!options.table.empty() && !found)
    Fail("bench findings: suite '{}' ({}) has no table '{}'", suite.name, suite.file.string(), options.table);
  return out;
}

std::string FindingsMarkdown(const std::vector<Finding>& findings) {
  std::string md =
      "| finding | pipeline | metric | verdict | reference | each other row: mean, row - reference, p | why | covers |\n"
      "|---|---|---|---|---|---|---|---|\n";
  for (const Finding& f : findings) {
    std::vector<std::string> rows;
    for (const FindingComparison& c : f.against) {
      if (!c.has_value) {
        rows.push_back(fmt::format("{}: no runs", c.label));
      } else if (!c.test.testable) {
        rows.push_back(fmt::format("{} {:.3f}, not testable", c.label, c.mean));
      } else {
        rows.push_back(fmt::format("{} {:.3f}, {:+.3f}, p = {:.2g}{}", c.label, c.mean,
                                   c.test.mean_difference, c.test.p,
                                   c.test.over_scenes ? " (over scenes)" : ""));
      }
    }
    const std::string ref = ReferenceText(f);
    md += fmt::format("| {} | {} | {} | **{}** | {} | {} | {} | {} |\n", f.claim, f.pipeline, f.metric,
                      f.verdict, ref, fmt::join(rows, "; "), f.why, CoverageLine(f));
  }
  return md;
}

std::string FindingsCsv(const std::vector<Finding>& findings) {
  std::string csv =
      "table,claim,pipeline,metric,verdict,reference,reference_mean,row,row_mean,difference,"
      "seed_sd,p,pairs,testable,over_scenes,outcome,scenes_covered,table_scenes,seeds\n";
  auto quote = [](const std::string& s) {
    std::string q = "\"";
    for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return q + "\"";
  };
  for (const Finding& f : findings) {
    for (const FindingComparison& c : f.against) {
      csv += fmt::format("{},{},{},{},{},{},{:.6f},{},{:.6f},{:.6f},{:.6f},{:.6g},{},{},{},{},{},{},{}\n",
                         f.table_id, quote(f.claim), f.pipeline, f.metric, quote(f.verdict),
                         quote(f.reference), f.reference_mean, quote(c.label), c.mean,
                         c.test.mean_difference, c.test.seed_sd, c.test.p, c.test.pairs,
                         c.test.testable, c.test.over_scenes, quote(c.outcome),
                         quote(fmt::format("{}", fmt::join(f.scenes_covered, " "))), f.table_scenes,
                         quote(fmt::format("{}", fmt::join(f.seeds, " "))));
    }
  }
  return csv;
}

namespace {

// A row label in ASCII for the PNG's bitmap font: the paper's daggers become + and ++ (HDR-GS+ is
// HDR-GS†), any other non-ASCII character '?'.
std::string AsciiLabel(const std::string& label) {
  std::string out;
  for (std::size_t i = 0; i < label.size();) {
    if (label.compare(i, 3, "\u2020") == 0) {
      out += "+";
      i += 3;
    } else if (label.compare(i, 3, "\u2021") == 0) {
      out += "++";
      i += 3;
    } else if (static_cast<unsigned char>(label[i]) < 0x80) {
      out += label[i++];
    } else {
      out += '?';
      for (++i; i < label.size() && (static_cast<unsigned char>(label[i]) & 0xC0) == 0x80;) ++i;
    }
  }
  return out;
}

}  // namespace

PlotPanel FindingChart(const Suite& suite, const std::vector<RunSummary>& runs,
                       const Finding& finding, const FindingsOptions& options) {
  const TableSpec* spec = nullptr;
  for (const TableSpec& t : suite.tables)
    if (t.id == finding.table_id) spec = &t;
  if (!spec) Fail("bench findings: suite '{}' has no table '{}'", suite.name, finding.table_id);
  PlotPanel panel;
  PlotOptions& o = panel.second;
  o.title = fmt::format("{}: {} ({})", finding.table_id, finding.verdict, finding.metric);
  o.y_label = finding.metric == "psnr" ? "held-out LDR PSNR (dB)" : finding.metric;
  o.width = 640;
  o.height = 400;
  o.font_scale = 1;
  PlotSeries dots{"seed means over scenes"}, bars{"mean +- seed sd"}, means{"mean"};
  dots.style = PlotSeries::kMarkers;
  dots.color = {0.55f, 0.55f, 0.55f};
  bars.style = PlotSeries::kLine;
  bars.color = {0.10f, 0.10f, 0.10f};
  means.style = PlotSeries::kMarkers;
  means.marker = PlotSeries::kSquare;
  PlotSeries ref{"reference"};
  ref.style = PlotSeries::kMarkers;
  ref.marker = PlotSeries::kDiamond;
  ref.color = {0.80f, 0.15f, 0.10f};
  std::vector<std::string> names;
  const std::string budget = BudgetOf(suite, options), variant = VariantOf(suite, options);
  for (std::size_t i = 0; i < spec->rows.size(); ++i) {
    const TableRow& row = spec->rows[i];
    const double x = static_cast<double>(i + 1);
    names.push_back(fmt::format("{} {}", i + 1, AsciiLabel(row.label)));
    const SeedValues v = FindingRowValues(runs, row, finding.scenes_covered, finding.metric, budget, variant);
    std::vector<double> seed_means;
    for (std::int64_t seed : finding.seeds) {
      std::vector<double> per_scene;
      for (const std::string& scene : finding.scenes_covered)
        if (auto it = v.find({scene, seed}); it != v.end()) per_scene.push_back(it->second);
      if (per_scene.size() == finding.scenes_covered.size() && !per_scene.empty()) {
        seed_means.push_back(Mean(per_scene));
        dots.x.push_back(x + 0.12);
        dots.y.push_back(seed_means.back());
      }
    }
    if (seed_means.empty()) continue;
    const double m = Mean(seed_means), sd = SampleStdDev(seed_means);
    PlotSeries& target = row.label == spec->reference ? ref : means;
    target.x.push_back(x);
    target.y.push_back(m);
    target.point_labels.push_back(AsciiLabel(row.label));
    bars.x.insert(bars.x.end(), {x, x, NAN});
    bars.y.insert(bars.y.end(), {m - sd, m + sd, NAN});
  }
  o.x_label = fmt::format("{}", fmt::join(names, ", "));  // ASCII: the PNG's bitmap font
  o.x_range = AxisRange{0.4, static_cast<double>(spec->rows.size()) + 0.8};
  for (PlotSeries* s : {&bars, &dots, &means, &ref})
    if (!s->x.empty()) panel.first.push_back(*s);
  return panel;
}

}  // namespace hdr4d::bench
