#include "benchmark/report.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "benchmark/pareto.h"
#include "benchmark/report_images.h"
#include "benchmark/run_pipeline.h"
#include "benchmark/scoring.h"
#include "benchmark/stats.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_util.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out.push_back(c);
    }
  }
  return out;
}

std::string Img(const std::string& uri, const std::string& alt, int width = 0) {
  return fmt::format("<img src=\"{}\" alt=\"{}\"{}>", uri, Escape(alt),
                     width > 0 ? fmt::format(" width=\"{}\"", width) : "");
}

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
                              Escape(t.id), Escape(t.id), Escape(t.title),
                              t.scenes.empty() ? "none" : Escape(fmt::format("{}", fmt::join(t.scenes, ", "))),
                              Escape(t.budget), t.variant.empty() ? "" : ", variant " + Escape(t.variant),
                              Escape(t.protocol));
  if (!t.note.empty()) h += "<p>" + Escape(t.note) + "</p>\n";
  h += "<table class=\"results\"><thead><tr><th>Row</th><th>Method</th><th>Supervision</th>";
  for (const Column& c : t.columns) {
    h += fmt::format("<th>{}{}{}</th>", c.group.empty() ? "" : Escape(c.group) + "<br>", Escape(c.label),
                     c.direction > 0 ? " ↑" : c.direction < 0 ? " ↓" : "");
  }
  h += "</tr></thead><tbody>\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    h += fmt::format("<tr{}><td>{}</td><td>{}</td><td>{}</td>", r.is_reference ? " class=\"ref\"" : "",
                     i + 1, Escape(r.label), Escape(r.supervision));
    for (std::size_t c = 0; c < t.columns.size(); ++c) h += CellHtml(r.cells[c], t.columns[c]);
    h += "</tr>\n";
  }
  h += "</tbody></table>\n";
  if (!t.footnotes.empty()) {
    h += "<ul class=\"notes\">";
    for (const std::string& f : t.footnotes) h += "<li>" + Escape(f) + "</li>";
    h += "</ul>\n";
  }
  // Paired tests.
  std::vector<std::size_t> cols;
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].quality && t.columns[c].computable) cols.push_back(c);
  h += fmt::format("<details><summary>Paired tests against '{}' (pairs by scene and seed; t-test "
                   "against the seed noise of the differences, pooled within scenes; alpha 0.05)"
                   "</summary><table class=\"tests\"><thead><tr><th>Row</th>",
                   Escape(t.reference));
  for (std::size_t c : cols) h += "<th>" + Escape(t.columns[c].group + " " + t.columns[c].label) + "</th>";
  h += "</tr></thead><tbody>";
  for (const RowResult& r : t.rows) {
    if (r.is_reference) continue;
    h += "<tr><td>" + Escape(r.label) + "</td>";
    for (std::size_t c : cols) {
      const PairedTest& p = r.tests[c];
      if (p.pairs == 0) {
        h += "<td class=\"na\">-</td>";
      } else if (!p.testable) {
        h += fmt::format("<td>{:+.{}f}<br><span class=\"sd\">not testable (1 seed)</span></td>",
                         p.mean_difference, t.columns[c].digits);
      } else {
        h += fmt::format("<td class=\"{}\">{:+.{}f}<br><span class=\"sd\">p = {:.2g}</span></td>",
                         p.significant ? "sig" : "nsig", p.mean_difference, t.columns[c].digits, p.p);
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
  for (const std::string& n : names) h += "<th>" + Escape(n) + "</th>";
  h += "<th>outcome</th><th>detail</th></tr></thead><tbody>\n";
  for (const StressOutcome& o : outcomes) {
    h += fmt::format("<tr><td>{}<br><span class=\"sd\">{}</span></td><td>{}</td>", Escape(o.name),
                     Escape(o.category), Escape(o.description));
    for (const std::string& n : names) {
      const nlohmann::json v = o.checks.value(n, nlohmann::json());
      h += v.is_null() ? "<td class=\"na\">n/a</td>"
                       : (v.get<bool>() ? "<td class=\"nsig\">yes</td>" : "<td class=\"sig\">NO</td>");
    }
    h += fmt::format("<td class=\"{}\">{}</td><td class=\"detail\">{}</td></tr>\n",
                     o.outcome == "held" ? "nsig" : "sig", Escape(o.outcome), Escape(o.detail));
  }
  return h + "</tbody></table>\n";
}

// The runs shown for a scene: one per (method, supervision) in table-row order, lowest seed.
std::vector<const RunSummary*> SceneRuns(const std::vector<RunSummary>& runs, const Suite& suite,
                                         const std::string& scene, const std::string& budget,
                                         const std::string& variant) {
  std::vector<std::pair<std::string, std::string>> order;
  for (const TableSpec& t : suite.tables)
    for (const TableRow& r : t.rows)
      if (std::find(order.begin(), order.end(), std::pair{r.method, r.supervision}) == order.end())
        order.emplace_back(r.method, r.supervision);
  std::map<std::pair<std::string, std::string>, const RunSummary*> best;
  for (const RunSummary& r : runs) {
    if (r.status != "ok" || r.label.scene != scene) continue;
    if (r.source != "submit" && (r.label.budget != budget || r.label.variant != variant)) continue;
    const std::pair key{r.label.method, r.label.supervision};
    if (std::find(order.begin(), order.end(), key) == order.end()) order.push_back(key);
    auto& slot = best[key];
    if (!slot || r.label.seed < slot->label.seed) slot = &r;
  }
  std::vector<const RunSummary*> out;
  for (const auto& key : order)
    if (auto it = best.find(key); it != best.end()) out.push_back(it->second);
  return out;
}

std::string Name(const RunSummary& r) {
  return r.label.method + " (" + r.label.supervision + ")";
}

std::string SceneHtml(const std::string& scene, const std::vector<const RunSummary*>& runs,
                      const ResultsStore& store, int* images) {
  std::string h = fmt::format("<h3 id=\"scene-{}\">{}</h3>\n", Escape(scene), Escape(scene));
  if (runs.empty()) return h + "<p>No finished runs.</p>\n";
  const nlohmann::json scoring = store.Config(runs.front()->run_id).value("scoring", nlohmann::json::object());
  std::array<double, 4> region = {0.4375, 0.4375, 0.125, 0.125};
  if (scoring.contains("region")) region = scoring["region"].get<std::array<double, 4>>();
  const int camera = scoring.value("region_camera", -1);
  const fs::path scene_dir = runs.front()->scene_dir;
  if (!fs::exists(scene_dir / "transforms_test.json"))
    return h + "<p>The scene folder " + Escape(scene_dir.string()) + " is not on this machine; pictures left out.</p>\n";
  const Dataset dataset = LoadDataset(scene_dir, {.image_check = ImageCheck::kNone});

  // The test view shown: the region camera's middle time, the exposure nearest the median.
  std::vector<const Frame*> views;
  for (const Frame& f : dataset.test)
    if (f.camera_id == camera) views.push_back(&f);
  if (views.empty()) return h + "<p>No test view of the region camera.</p>\n";
  std::sort(views.begin(), views.end(), [](const Frame* a, const Frame* b) {
    return std::tie(a->time, a->exposure) < std::tie(b->time, b->exposure);
  });
  std::vector<double> times;
  for (const Frame* f : views) times.push_back(f->time);
  const double mid_time = times[times.size() / 2];
  const Frame* view = nullptr;
  std::vector<const Frame*> at_time;
  for (const Frame* f : views)
    if (f->time == mid_time) at_time.push_back(f);
  view = at_time[at_time.size() / 2];

  h += fmt::format("<p>Test view {} (camera {}, t = {:.3f}, exposure {} s). LDR as rendered; HDR "
                   "through the mu-law of the metrics (each image over its own maximum). Error "
                   "maps: mean absolute difference over RGB, white = 0.5 or more. The box is the "
                   "region of the luminance curves below.</p>\n",
                   Escape(view->file_path), camera, view->time, view->exposure);
  h += "<table class=\"pics\"><thead><tr><th></th><th>LDR</th><th>LDR error</th><th>HDR (mu-law)</th><th>HDR error</th></tr></thead><tbody>\n";
  std::optional<Image> gt_ldr, gt_hdr_mu;
  if (fs::exists(view->image_path)) gt_ldr = ReadImage(view->image_path);
  if (view->hdr_path && fs::exists(*view->hdr_path)) gt_hdr_mu = MuLawDisplay(ReadImage(*view->hdr_path));
  auto pic = [&](const Image& image, const std::string& alt) {
    ++*images;
    return "<td>" + Img(PngDataUri(image), alt, std::min(256, std::max(160, image.width()))) + "</td>";
  };
  const std::array<float, 3> box_colour = {0.1f, 0.9f, 0.2f};
  h += "<tr><th>ground truth</th>";
  h += gt_ldr ? pic(WithBox(*gt_ldr, region, box_colour), "ground truth LDR") : "<td>-</td>";
  h += "<td></td>";
  h += gt_hdr_mu ? pic(WithBox(*gt_hdr_mu, region, box_colour), "ground truth HDR") : "<td>-</td>";
  h += "<td></td></tr>\n";
  for (const RunSummary* r : runs) {
    const fs::path renders = r->source == "submit" ? fs::path(r->run_dir) : fs::path(r->run_dir) / "renders";
    h += "<tr><th>" + Escape(Name(*r)) + "</th>";
    const fs::path ldr = renders / LdrRenderName(*view), hdr = renders / HdrRenderName(*view);
    if (fs::exists(ldr) && gt_ldr) {
      const Image p = ReadImage(ldr);
      h += pic(p, Name(*r) + " LDR") + pic(ErrorMap(p.Rgb(), gt_ldr->Rgb(), 0.5), Name(*r) + " LDR error");
    } else {
      h += "<td class=\"na\">-</td><td class=\"na\">-</td>";
    }
    if (fs::exists(hdr) && gt_hdr_mu) {
      const Image p = MuLawDisplay(ReadImage(hdr));
      h += pic(p, Name(*r) + " HDR") + pic(ErrorMap(p, *gt_hdr_mu, 0.5), Name(*r) + " HDR error");
    } else {
      h += "<td class=\"na\">-</td><td class=\"na\">-</td>";
    }
    h += "</tr>\n";
  }
  h += "</tbody></table>\n";

  // Temporal luminance of the region: each curve over its own mean, so shapes compare (the
  // absolute level of an HDR render learned from LDR images is arbitrary).
  std::vector<PlotSeries> lum;
  bool hdr_curves = false;
  for (const char* kind : {"region_luminance", "region_ldr"}) {
    lum.clear();
    std::map<double, double> gt;
    int colour = 0;
    for (const RunSummary* r : runs) {
      std::map<double, double> points;
      for (const FrameResult& f : store.Frames(r->run_id)) {
        if (f.camera_id != camera) continue;
        if (auto it = f.stats.find(kind); it != f.stats.end()) points[f.time] = it->second;
        if (auto it = f.stats.find(std::string(kind) + "_gt"); it != f.stats.end()) gt[f.time] = it->second;
      }
      if (points.size() < 2) {
        ++colour;
        continue;
      }
      PlotSeries s;
      s.name = Name(*r);
      s.style = PlotSeries::kLineMarkers;
      s.color = PaletteColor(colour++);
      std::vector<double> v;
      for (const auto& [t, y] : points) v.push_back(y);
      const double m = Mean(v);
      for (const auto& [t, y] : points) {
        s.x.push_back(t);
        s.y.push_back(m > 0 ? y / m : NAN);
      }
      lum.push_back(std::move(s));
    }
    if (lum.empty() || gt.size() < 2) continue;
    PlotSeries g;
    g.name = "ground truth";
    g.style = PlotSeries::kLineMarkers;
    g.color = {0, 0, 0};
    std::vector<double> v;
    for (const auto& [t, y] : gt) v.push_back(y);
    const double m = Mean(v);
    for (const auto& [t, y] : gt) {
      g.x.push_back(t);
      g.y.push_back(m > 0 ? y / m : NAN);
    }
    lum.insert(lum.begin(), g);
    hdr_curves = std::string(kind) == "region_luminance";
    break;
  }
  if (!lum.empty()) {
    PlotOptions o;
    o.title = fmt::format("{}: region {} over time, camera {}", scene,
                          hdr_curves ? "luminance" : "LDR luma", camera);
    o.x_label = "normalised time";
    o.y_label = "region mean / its mean over time (log)";
    o.log_y = true;
    o.width = 900;
    o.height = 480;
    h += "<h4>Temporal luminance of a region (Figs. 4-5)</h4>\n" + Img(PlotDataUri(lum, o), scene + " temporal luminance") + "\n";
    ++*images;
  }

  // Learned tone curves over time (green channel), one panel per method that has them.
  std::vector<PlotPanel> panels;
  for (const RunSummary* r : runs) {
    const std::map<std::string, Series> series = store.AllSeries(r->run_id);
    std::vector<PlotSeries> lines;
    std::vector<std::pair<double, const Series*>> curves;
    for (const auto& [name, points] : series) {
      if (name.rfind("tone:", 0) != 0 || name.substr(name.size() - 2) != ":g") continue;
      curves.emplace_back(std::stod(name.substr(5, name.size() - 7)), &points);
    }
    std::sort(curves.begin(), curves.end());
    for (std::size_t k = 0; k < curves.size(); ++k) {
      PlotSeries s;
      s.name = fmt::format("t = {:.2f}", curves[k].first);
      s.color = SequentialColor(curves.size() > 1 ? double(k) / (curves.size() - 1) : 0.0);
      for (const auto& [x, y] : *curves[k].second) {
        s.x.push_back(x);
        s.y.push_back(y);
      }
      lines.push_back(std::move(s));
    }
    if (lines.empty()) continue;
    PlotOptions o;
    o.title = Name(*r);
    o.x_label = "log radiance + log exposure";
    o.y_label = "LDR (green)";
    o.width = 440;
    o.height = 330;
    o.font_scale = 1;
    o.y_range = AxisRange{0.0, 1.0};
    panels.emplace_back(std::move(lines), o);
  }
  if (!panels.empty()) {
    h += "<h4>Learned tone curves over time (green channel)</h4>\n" +
         Img(PlotGridDataUri(panels, std::min<int>(3, static_cast<int>(panels.size()))), scene + " tone curves") + "\n";
    ++*images;
  }

  // Training curves.
  std::vector<PlotSeries> train;
  int colour = 0;
  for (const RunSummary* r : runs) {
    const std::map<std::string, Series> series = store.AllSeries(r->run_id);
    const auto it = series.find("train_psnr");
    if (it == series.end()) {
      ++colour;
      continue;
    }
    PlotSeries s;
    s.name = Name(*r);
    s.color = PaletteColor(colour++);
    for (const auto& [x, y] : it->second) {
      s.x.push_back(x);
      s.y.push_back(y);
    }
    train.push_back(std::move(s));
  }
  if (!train.empty()) {
    PlotOptions o;
    o.title = scene + ": training-view PSNR";
    o.x_label = "iteration";
    o.y_label = "PSNR (dB)";
    o.width = 900;
    o.height = 420;
    h += "<h4>Training curves</h4>\n" + Img(PlotDataUri(train, o), scene + " training curves") + "\n";
    ++*images;
  }
  return h;
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

}  // namespace

ReportSummary WriteReport(const Suite& suite, const ResultsStore& store, const ReportOptions& options) {
  ReportSummary summary;
  const std::vector<RunSummary> runs = SuiteRuns(store, suite);
  const std::string budget = options.tables.budget.empty() ? suite.budgets.back().Label() : options.tables.budget;
  const std::string variant = options.tables.variant.empty() ? suite.variants.front().name : options.tables.variant;
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
  body += fmt::format("<h1>hdr4d benchmark report: suite '{}'</h1>\n", Escape(suite.name));
  if (!suite.description.empty()) body += "<p>" + Escape(suite.description) + "</p>\n";
  body += fmt::format(
      "<p>Store <code>{}</code>; generated {}. {} run labels ({} finished, {} failed); code "
      "versions: {}; machines: {}.</p>\n<p id=\"selfcheck\">Page check: not run (JavaScript off).</p>\n",
      Escape(fs::absolute(store.path()).string()), UtcNow(), runs.size(), ok, failed,
      Escape(fmt::format("{}", fmt::join(versions, ", "))),
      Escape(fmt::format("{}", fmt::join(machines, "; "))));
  body += "<nav><b>Contents:</b> <a href=\"#tables\">tables</a> · <a href=\"#pareto\">time against error</a> · <a href=\"#scenes\">scenes</a> · <a href=\"#stress\">stress</a></nav>\n";

  body += "<h2 id=\"tables\">Tables</h2>\n";
  for (const TableSpec& spec : suite.tables) {
    body += TableHtml(BuildTable(spec, suite, runs, options.tables));
    body += "<details><summary>Every metric</summary>" +
            TableHtml(BuildAllMetricsTable(spec, suite, runs, options.tables)) + "</details>\n";
    summary.tables += 2;
  }

  body += "<h2 id=\"pareto\">Run time against error</h2>\n";
  bool any_pareto = false;
  for (const ParetoTime time : {ParetoTime::kTraining, ParetoTime::kRender}) {
    std::vector<std::string> scenes = {""};
    for (const SceneSpec& s : suite.scenes) scenes.push_back(s.name);
    for (const std::string& scene : scenes) {
      std::vector<PlotSeries> series;
      PlotOptions o;
      if (!ParetoChart(runs, suite, options.pareto_metric, time, scene, &series, &o)) continue;
      o.width = scene.empty() ? 900 : 640;
      o.height = scene.empty() ? 560 : 420;
      o.font_scale = scene.empty() ? 2 : 1;
      body += (scene.empty() ? "<div>" : "<div class=\"chart\">") + Img(PlotDataUri(series, o), o.title) + "</div>\n";
      ++summary.images;
      any_pareto = true;
    }
  }
  if (!any_pareto) body += "<p>No finished runs with a time and " + Escape(options.pareto_metric) + ".</p>\n";

  body += "<h2 id=\"scenes\">Scenes</h2>\n";
  for (const SceneSpec& s : suite.scenes) {
    body += SceneHtml(s.name, SceneRuns(runs, suite, s.name, budget, variant), store, &summary.images);
    ++summary.scenes;
  }

  body += "<h2 id=\"stress\">Stress suite</h2>\n";
  const std::vector<StressOutcome> stress = store.StressOutcomes();
  body += StressHtml(stress);
  summary.stress_cases = static_cast<int>(stress.size());

  const std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hdr4d benchmark: "
      "{}</title><style>{}</style></head>\n<body>\n{}{}</body></html>\n",
      Escape(suite.name), kStyle, body, kSelfCheck);
  WriteTextFileAtomic(options.out, html);
  return summary;
}

}  // namespace hdr4d::bench
