#include "benchmark/pareto.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "benchmark/stats.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/viz/plot.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

using ConfigKey = std::tuple<std::string, std::string, std::string, std::string>;  // m, s, v, b

std::optional<double> TimeOf(const RunSummary& r, ParetoTime time) {
  const double v = time == ParetoTime::kTraining ? r.train_seconds
                                                 : (r.render_fps > 0 ? 1000.0 / r.render_fps : NAN);
  if (!std::isfinite(v) || v <= 0) return std::nullopt;
  return v;
}

// The front as one black line; with --reference points, each family's front (the default's in
// black, the reference's in grey).
void AddFrontSeries(const std::vector<ParetoPoint>& points, std::vector<PlotSeries>* series) {
  const bool two = std::any_of(points.begin(), points.end(),
                               [](const ParetoPoint& p) { return p.reference; }) &&
                   std::any_of(points.begin(), points.end(),
                               [](const ParetoPoint& p) { return !p.reference; });
  for (const bool reference : two ? std::vector<bool>{false, true} : std::vector<bool>{false}) {
    std::vector<const ParetoPoint*> front;
    for (const ParetoPoint& p : points)
      if (two ? (p.reference == reference && p.family_front) : p.front) front.push_back(&p);
    std::sort(front.begin(), front.end(),
              [](const ParetoPoint* a, const ParetoPoint* b) { return a->seconds < b->seconds; });
    PlotSeries f;
    f.name = !two ? "Pareto front" : reference ? "front: --reference" : "front: default";
    f.style = PlotSeries::kLineMarkers;  // a front of one point still shows
    f.color = reference ? std::array<float, 3>{0.55f, 0.55f, 0.55f} : std::array<float, 3>{0.f, 0.f, 0.f};
    for (const ParetoPoint* p : front) {
      f.x.push_back(p->seconds);
      f.y.push_back(p->quality);
    }
    series->push_back(std::move(f));
  }
}

// Why no point: the metric is not a key of the runs, only submissions (which carry no
// training time) have it, or no finished run has it with a time.
[[noreturn]] void NothingToPlot(const std::vector<RunSummary>& runs, const Suite& suite,
                                const std::string& metric) {
  RequireMetricKey("--metric", metric, MetricKeys(runs), "runs of suite '" + suite.name + "'");
  const auto has = [&](const RunSummary& r) { return r.status == "ok" && r.metrics.count(metric); };
  const bool submitted = std::any_of(runs.begin(), runs.end(), [&](const RunSummary& r) {
    return has(r) && r.source == "submit";
  });
  const bool trained = std::any_of(runs.begin(), runs.end(), [&](const RunSummary& r) {
    return has(r) && r.source != "submit";
  });
  if (submitted && !trained)
    Fail("bench pareto: the only runs of suite '{}' with '{}' are submissions (bench submit), "
         "which carry no training time: run time against error needs runs trained by "
         "`hdr4d bench run`; nothing to plot", suite.name, metric);
  Fail("bench pareto: no finished run of suite '{}' has both '{}' and a time; nothing to plot",
       suite.name, metric);
}

}  // namespace

std::string ParetoPoint::Config() const {
  return method + "/" + supervision + (variant.empty() ? "" : "/" + variant);
}

void MarkFront(std::vector<ParetoPoint>* points) {
  for (ParetoPoint& p : *points) {
    p.front = std::none_of(points->begin(), points->end(), [&](const ParetoPoint& q) {
      return q.seconds <= p.seconds && q.quality >= p.quality &&
             (q.seconds < p.seconds || q.quality > p.quality);
    });
  }
}

void MarkFamilyFronts(std::vector<ParetoPoint>* points) {
  for (const bool family : {false, true}) {
    std::vector<ParetoPoint> members;
    for (const ParetoPoint& p : *points)
      if (p.reference == family) members.push_back(p);
    MarkFront(&members);
    std::size_t k = 0;
    for (ParetoPoint& p : *points)
      if (p.reference == family) p.family_front = members[k++].front;
  }
}

bool ReferenceVariant(const Suite& suite, const std::string& variant) {
  for (const Variant& v : suite.variants) {
    if (v.name != variant) continue;
    const auto it = v.train.find("reference");
    return it != v.train.end() && it->is_boolean() && it->get<bool>();
  }
  return false;
}

std::vector<ParetoPoint> ParetoPoints(const std::vector<RunSummary>& runs, const Suite& suite,
                                      const std::string& metric, ParetoTime time,
                                      const std::string& scene) {
  // (config, scene) -> per-seed values.
  std::map<ConfigKey, std::map<std::string, std::pair<std::vector<double>, std::vector<double>>>> values;
  for (const RunSummary& r : runs) {
    if (r.status != "ok" || r.source == "submit") continue;
    const auto m = r.metrics.find(metric);
    const auto t = TimeOf(r, time);
    if (m == r.metrics.end() || !std::isfinite(m->second) || !t) continue;
    auto& v = values[{r.label.method, r.label.supervision, r.label.variant, r.label.budget}][r.label.scene];
    v.first.push_back(*t);
    v.second.push_back(m->second);
  }
  std::vector<ParetoPoint> points;
  for (const auto& [key, by_scene] : values) {
    ParetoPoint p{std::get<0>(key), std::get<1>(key), std::get<2>(key), std::get<3>(key), scene};
    p.reference = ReferenceVariant(suite, p.variant);
    if (!scene.empty()) {
      const auto it = by_scene.find(scene);
      if (it == by_scene.end()) continue;
      p.seconds = Mean(it->second.first);
      p.quality = Mean(it->second.second);
      p.seeds = static_cast<int>(it->second.first.size());
    } else {
      // Overall: only configurations with runs on every scene of the suite, so means compare.
      if (by_scene.size() != suite.scenes.size()) continue;
      std::vector<double> secs, qual;
      for (const auto& [s, v] : by_scene) {
        secs.push_back(Mean(v.first));
        qual.push_back(Mean(v.second));
        p.seeds = std::max<int>(p.seeds, static_cast<int>(v.first.size()));
      }
      p.seconds = Mean(secs);
      p.quality = Mean(qual);
    }
    points.push_back(p);
  }
  MarkFront(&points);
  MarkFamilyFronts(&points);
  return points;
}

bool ParetoChart(const std::vector<RunSummary>& runs, const Suite& suite, const std::string& metric,
                 ParetoTime time, const std::string& scene, std::vector<PlotSeries>* out,
                 PlotOptions* o) {
  const std::vector<ParetoPoint> points = ParetoPoints(runs, suite, metric, time, scene);
  if (points.empty()) return false;
  const char* time_name = time == ParetoTime::kTraining ? "training" : "render";
  std::vector<PlotSeries>& series = *out;
  series.clear();
  // One line per configuration through its budgets (sorted by time), the front in black.
  std::map<std::string, std::vector<const ParetoPoint*>> by_config;
  for (const ParetoPoint& p : points) by_config[p.Config()].push_back(&p);
  int colour = 0;
  for (auto& [config, list] : by_config) {
    std::sort(list.begin(), list.end(),
              [](const ParetoPoint* a, const ParetoPoint* b) { return a->seconds < b->seconds; });
    PlotSeries s;
    s.name = config;
    s.style = list.size() > 1 ? PlotSeries::kLineMarkers : PlotSeries::kMarkers;
    s.marker = PaletteMarker(colour);
    s.color = PaletteColor(colour++);
    for (const ParetoPoint* p : list) {
      s.x.push_back(p->seconds);
      s.y.push_back(p->quality);
      s.point_labels.push_back(list.size() > 1 ? p->budget : "");
    }
    series.push_back(std::move(s));
  }
  AddFrontSeries(points, &series);
  *o = PlotOptions{};
  o->title = fmt::format("{}: {} vs {} time", scene.empty() ? "mean over scenes" : scene,
                         metric, time_name);
  o->x_label = time == ParetoTime::kTraining ? "training time (s, log)" : "render time per frame (ms, log)";
  o->y_label = metric + " (higher is better)";
  o->log_x = true;
  o->width = 900;
  o->height = 560;
  return true;
}

std::vector<fs::path> WritePareto(const std::vector<RunSummary>& runs, const Suite& suite,
                                  const ParetoOptions& options) {
  CheckOutputFolder(options.out);  // never among a dataset's images (issue 51, case 10)
  std::vector<std::string> scenes;
  for (const SceneSpec& s : suite.scenes) scenes.push_back(s.name);
  scenes.push_back("");  // overall
  // `front` stays the last column (the overall front); family_front: the front of the point's
  // family (reference: a --reference variant) alone.
  std::string csv =
      "scene,time,method,supervision,variant,budget,seeds,time_value,metric,value,family,"
      "family_front,front\n";
  std::vector<fs::path> charts;
  bool any = false;
  for (const ParetoTime time : {ParetoTime::kTraining, ParetoTime::kRender}) {
    const char* time_name = time == ParetoTime::kTraining ? "train" : "render";
    for (const std::string& scene : scenes) {
      std::vector<ParetoPoint> points = ParetoPoints(runs, suite, options.metric, time, scene);
      if (points.empty()) continue;
      any = true;
      for (const ParetoPoint& p : points) {
        csv += fmt::format("{},{},{},{},{},{},{},{:.6g},{},{:.6g},{},{},{}\n",
                           scene.empty() ? "overall" : scene, time_name, p.method, p.supervision,
                           p.variant, p.budget, p.seeds, p.seconds, options.metric, p.quality,
                           p.reference ? "reference" : "default", p.family_front ? 1 : 0,
                           p.front ? 1 : 0);
      }
      std::vector<PlotSeries> series;
      PlotOptions o;
      ParetoChart(runs, suite, options.metric, time, scene, &series, &o);
      const std::string stem = fmt::format("pareto_{}_{}", scene.empty() ? "overall" : scene, time_name);
      WritePlot(options.out / (stem + ".png"), series, o);
      WritePlot(options.out / (stem + ".svg"), series, o);
      charts.push_back(options.out / (stem + ".png"));
    }
  }
  if (!any) NothingToPlot(runs, suite, options.metric);
  WriteTextFileAtomic(options.out / "pareto.csv", csv);
  return charts;
}

}  // namespace hdr4d::bench
