#include "benchmark/report.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "benchmark/pareto.h"
#include "benchmark/report_findings.h"
#include "benchmark/report_images.h"
#include "benchmark/run_pipeline.h"
#include "benchmark/scoring.h"
#include "benchmark/stats.h"
#include "core/dataset/dataset.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"

#include "benchmark/report_scene.h"
namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {


std::string CellHtml(const Cell& c, const Column& col) {
  if (!col.computable) return "<td class=\"na\" title=\"LPIPS needs network weights that cannot be obtained here\">n/a</td>";
  if (!c.has_value) return "<td class=\"na\">-</td>";
  std::string v = fmt::format("{:.{}f}", c.mean, col.digits);
  if (c.best) v = "<b>" + v + "</b>";
  if (c.has_spread) v += fmt::format(" <span class=\"sd\">± {:.{}f}</span>", c.spread, col.digits);
  if (!c.complete()) v += fmt::format(" <span class=\"warn\">[{}/{}]</span>", c.runs, c.expected);
  return "<td>" + v + "</td>";
}

std::string TableHtml(const Table& t) {
  std::string h = fmt::format("<h3 id=\"{}\">{}: {}</h3>\n<p class=\"intro\">Scenes: {}; budget {}{}. "
                              "HDR: {}. Mean over scenes ± standard deviation over seeds; best in bold.</p>\n",
                              HtmlEscape(t.id), HtmlEscape(t.id), HtmlEscape(t.title),
                              t.scenes.empty() ? "none" : HtmlEscape(fmt::format("{}", fmt::join(t.scenes, ", "))),
                              HtmlEscape(t.budget), t.variant.empty() ? "" : ", variant " + HtmlEscape(t.variant),
                              HtmlEscape(t.protocol));
  if (!t.note.empty()) h += "<p>" + HtmlEscape(t.note) + "</p>\n";
  h += "<table class=\"results\"><thead><tr><th>Row</th><th>Method</th><th>Supervision</th>";
  for (const Column& c : t.columns) {
    h += fmt::format("<th>{}{}{}</th>", c.group.empty() ? "" : HtmlEscape(c.group) + "<br>", HtmlEscape(c.label),
                     c.direction > 0 ? " ↑" : c.direction < 0 ? " ↓" : "");
  }
  h += "</tr></thead><tbody>\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    h += fmt::format("<tr{}><td>{}</td><td>{}</td><td>{}</td>", r.is_reference ? " class=\"ref\"" : "",
                     i + 1, HtmlEscape(RowName(r, t.scenes.size())), HtmlEscape(r.supervision));
    for (std::size_t c = 0; c < t.columns.size(); ++c) h += CellHtml(r.cells[c], t.columns[c]);
    h += "</tr>\n";
  }
  h += "</tbody></table>\n";
  if (!t.footnotes.empty()) {
    h += "<ul class=\"notes\">";
    for (const std::string& f : t.footnotes) h += "<li>" + HtmlEscape(f) + "</li>";
    h += "</ul>\n";
  }
  // Paired tests.
  std::vector<std::size_t> cols;
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].quality && t.columns[c].computable) cols.push_back(c);
  h += fmt::format("<details><summary>Paired tests against '{}' (pairs by scene and seed; t-test "
                   "against the seed noise of the differences, pooled within scenes; alpha 0.05)"
                   "</summary><table class=\"tests\"><thead><tr><th>Row</th>",
                   HtmlEscape(t.reference));
  for (std::size_t c : cols) h += "<th>" + HtmlEscape(t.columns[c].group + " " + t.columns[c].label) + "</th>";
  h += "</tr></thead><tbody>";
  for (const RowResult& r : t.rows) {
    if (r.is_reference) continue;
    h += "<tr><td>" + HtmlEscape(r.label) + "</td>";
    for (std::size_t c : cols) {
      const PairedTest& p = r.tests[c];
      if (p.pairs == 0) {
        h += "<td class=\"na\">-</td>";
      } else if (!p.testable) {
        h += fmt::format("<td>{:+.{}f}<br><span class=\"sd\">not testable (1 seed)</span></td>",
                         p.mean_difference, t.columns[c].digits);
      } else {
        h += fmt::format("<td class=\"{}\">{:+.{}f}<br><span class=\"sd\">p = {:.2g}{}</span></td>",
                         p.significant ? "sig" : "nsig", p.mean_difference, t.columns[c].digits, p.p,
                         p.over_scenes ? ", over scenes" : "");
      }
    }
    h += "</tr>";
  }
  h += "</tbody></table></details>\n";
  return h;
}

std::string StressHtml(const std::vector<StressOutcome>& outcomes) {
  if (outcomes.empty())
    return "<p>No stress results in this store (run <code>hdr4d bench stress --store STORE</code>).</p>\n";
  std::vector<std::string> names = {"no crash", "no NaN", "clear error", "nothing lost"};
  for (const StressOutcome& o : outcomes)
    for (const auto& [k, v] : o.checks.items())
      if (std::find(names.begin(), names.end(), k) == names.end()) names.push_back(k);
  std::string h = "<table class=\"results\"><thead><tr><th>case</th><th>what</th>";
  for (const std::string& n : names) h += "<th>" + HtmlEscape(n) + "</th>";
  h += "<th>outcome</th><th>detail</th></tr></thead><tbody>\n";
  for (const StressOutcome& o : outcomes) {
    h += fmt::format("<tr><td>{}<br><span class=\"sd\">{}</span></td><td>{}</td>", HtmlEscape(o.name),
                     HtmlEscape(o.category), HtmlEscape(o.description));
    for (const std::string& n : names) {
      const nlohmann::json v = o.checks.value(n, nlohmann::json());
      h += v.is_null() ? "<td class=\"na\">n/a</td>"
                       : (v.get<bool>() ? "<td class=\"nsig\">yes</td>" : "<td class=\"sig\">NO</td>");
    }
    h += fmt::format("<td class=\"{}\">{}</td><td class=\"detail\">{}</td></tr>\n",
                     o.outcome == "held" ? "nsig" : "sig", HtmlEscape(o.outcome), HtmlEscape(o.detail));
  }
  return h + "</tbody></table>\n";
}

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 2em; max-width: 1400px; color: #222; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.6em 0; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: center; font-size: 0.9em; }
td.na { color: #999; } .sd { color: #777; font-size: 0.85em; } .warn { color: #b60; }
tr.ref { background: #eef5ff; } td.sig { background: #fde2e2; } td.nsig { background: #e6f4e6; }
td.detail { text-align: left; max-width: 40em; font-size: 0.8em; }
div.chart { display: inline-block; margin: 4px; vertical-align: top; }
table.pics img { image-rendering: pixelated; display: block; }
ul.notes { font-size: 0.85em; color: #555; } p.intro { font-size: 0.9em; color: #444; }
code { background: #f4f4f4; padding: 0 3px; }
)";

constexpr const char* kSelfCheck = R"(
<script>
window.addEventListener('load', function () {
  var images = document.images, broken = 0;
  for (var i = 0; i < images.length; ++i)
    if (!(images[i].complete && images[i].naturalWidth > 0)) broken++;
  var tables = document.querySelectorAll('table').length;
  document.body.setAttribute('data-tables', tables);
  document.body.setAttribute('data-images', images.length);
  document.body.setAttribute('data-broken-images', broken);
  document.getElementById('selfcheck').textContent =
      'Page check: ' + tables + ' tables, ' + images.length + ' images, ' + broken + ' failed to load.';
  if (broken > 0) console.error('report: ' + broken + ' image(s) failed to load');
});
</script>
)";

// Every table of the suite (with --methods: those with a selected row) and its every-metric
// companion.
std::string TablesHtml(const Suite& suite, const std::vector<RunSummary>& runs,
                       const TableOptions& options, ReportSummary* summary) {
  std::string h;
  for (const TableSpec& spec : suite.tables) {
    const Table table = BuildTable(spec, suite, runs, options);
    if (!HasSelectedRows(table, options)) continue;
    h += TableHtml(table);
    h += "<details><summary>Every metric</summary>" +
         TableHtml(BuildAllMetricsTable(spec, suite, runs, options)) + "</details>\n";
    summary->tables += 2;
  }
  return h;
}

}  // namespace

std::vector<RunSummary> ReportSelectedRuns(const std::vector<RunSummary>& runs, const Suite& suite,
                                           const std::vector<std::string>& methods) {
  if (methods.empty()) return runs;
  const std::set<std::string> keep(methods.begin(), methods.end());
  std::set<std::pair<std::string, std::string>> by_row;  // (method, supervision) of named rows
  for (const TableSpec& t : suite.tables)
    for (const TableRow& r : t.rows)
      if (keep.count(r.label)) by_row.insert({r.method, r.supervision});
  std::vector<RunSummary> selected;
  for (const RunSummary& r : runs) {
    if (keep.count(r.label.method) || by_row.count({r.label.method, r.label.supervision}))
      selected.push_back(r);
  }
  return selected;
}

ReportSummary WriteReport(const Suite& suite, const ResultsStore& store, const ReportOptions& options) {
  // Before any work: the page goes neither over an input (the store, the suite: registered
  // where they are opened) nor among a dataset's images (issue 51, cases 1 and 10).
  CheckOutput(options.out);
  CheckOutputFolder(options.out.has_parent_path() ? options.out.parent_path() : ".");
  ReportSummary summary;
  const std::vector<RunSummary> runs = SuiteRuns(store, suite);
  CheckRowNames(suite, runs, options.tables);
  const std::string budget = TableBudget(suite, options.tables.budget);
  const std::string variant = TableVariant(suite, options.tables.variant);
  std::set<std::string> versions, machines;
  int ok = 0, failed = 0;
  for (const RunSummary& r : runs) {
    (r.status == "ok" ? ok : failed)++;
    if (r.source != "submit") {
      versions.insert(r.code_version);
      machines.insert(fmt::format("{} ({} cores, {})", r.machine.value("cpu_model", "?"),
                                  r.machine.value("cores", 0), r.machine.value("simd_target", "?")));
    }
  }
  std::string body;
  body += fmt::format("<h1>hdr4d benchmark report: suite '{}'</h1>\n", HtmlEscape(suite.name));
  if (!suite.description.empty()) body += "<p>" + HtmlEscape(suite.description) + "</p>\n";
  body += fmt::format(
      "<p>Store <code>{}</code>; generated {}. {} run labels ({} finished, {} failed); code "
      "versions: {}; machines: {}.</p>\n<p id=\"selfcheck\">Page check: not run (JavaScript off).</p>\n",
      HtmlEscape(fs::absolute(store.path()).string()), UtcNow(), runs.size(), ok, failed,
      HtmlEscape(fmt::format("{}", fmt::join(versions, ", "))),
      HtmlEscape(fmt::format("{}", fmt::join(machines, "; "))));
  body += "<nav><b>Contents:</b> <a href=\"#tables\">tables</a> · <a href=\"#findings\">findings</a> · <a href=\"#pareto\">time against error</a> · <a href=\"#scenes\">scenes</a> · <a href=\"#stress\">stress</a></nav>\n";

  body += "<h2 id=\"tables\">Tables</h2>\n" + TablesHtml(suite, runs, options.tables, &summary);
  const std::string findings =
      FindingsHtml(suite, runs, options.tables, &summary.images, &summary.tables);
  body += "<h2 id=\"findings\">Findings</h2>\n" +
          (findings.empty() ? std::string("<p>No table of the suite states a finding (no ablation table, no main table with a finding).</p>\n") : findings);

  body += "<h2 id=\"pareto\">Run time against error</h2>\n";
  // The charts and the renders show the rows --methods selects, as the tables do.
  const std::vector<RunSummary> selected = ReportSelectedRuns(runs, suite, options.tables.methods);
  bool any_pareto = false;
  for (const ParetoTime time : {ParetoTime::kTraining, ParetoTime::kRender}) {
    std::vector<std::string> scenes = {""};
    for (const SceneSpec& s : suite.scenes) scenes.push_back(s.name);
    for (const std::string& scene : scenes) {
      std::vector<PlotSeries> series;
      PlotOptions o;
      if (!ParetoChart(selected, suite, options.pareto_metric, time, scene, &series, &o)) continue;
      o.width = scene.empty() ? 900 : 640;
      o.height = scene.empty() ? 560 : 420;
      o.font_scale = scene.empty() ? 2 : 1;
      body += (scene.empty() ? "<div>" : "<div class=\"chart\">") + HtmlImg(PlotDataUri(series, o), o.title) + "</div>\n";
      ++summary.images;
      any_pareto = true;
    }
  }
  if (!any_pareto) body += "<p>No finished runs with a time and " + HtmlEscape(options.pareto_metric) + ".</p>\n";

  body += "<h2 id=\"scenes\">Scenes</h2>\n";
  for (const SceneSpec& s : suite.scenes) {
    const std::vector<const RunSummary*> shown = SceneRuns(selected, suite, s.name, budget, variant);
    body += SceneHtml(s.name, shown, store, &summary.images);
    ++summary.scenes;
  }

  body += "<h2 id=\"stress\">Stress suite</h2>\n";
  const std::vector<StressOutcome> stress = store.StressOutcomes();
  body += StressHtml(stress);
  summary.stress_cases = static_cast<int>(stress.size());

  const std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hdr4d benchmark: "
      "{}</title><style>{}</style></head>\n<body>\n{}{}</body></html>\n",
      HtmlEscape(suite.name), kStyle, body, kSelfCheck);
  WriteTextFileAtomic(options.out, html);
  return summary;
}

}  // namespace hdr4d::bench
