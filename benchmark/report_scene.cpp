#include "benchmark/report_scene.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "benchmark/pareto.h"
#include "benchmark/report_flip.h"
#include "benchmark/report_images.h"
#include "benchmark/run_pipeline.h"
#include "benchmark/scoring.h"
#include "benchmark/stats.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::string Name(const RunSummary& r) {
  return r.label.method + " (" + r.label.supervision + (r.source == "submit" ? ", external" : "") + ")";
}

}  // namespace

std::string HtmlEscape(const std::string& s) {
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

std::string HtmlImg(const std::string& uri, const std::string& alt, int width) {
  return fmt::format("<img src=\"{}\" alt=\"{}\"{}>", uri, HtmlEscape(alt),
                     width > 0 ? fmt::format(" width=\"{}\"", width) : "");
}

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

namespace {

// The test view shown: the region camera's middle time, the exposure nearest the median; null
// when the camera has no test view.
const Frame* ShownView(const Dataset& dataset, int camera) {
  std::vector<const Frame*> views;
  for (const Frame& f : dataset.test)
    if (f.camera_id == camera) views.push_back(&f);
  if (views.empty()) return nullptr;
  std::sort(views.begin(), views.end(), [](const Frame* a, const Frame* b) {
    return std::tie(a->time, a->exposure) < std::tie(b->time, b->exposure);
  });
  std::vector<double> times;
  for (const Frame* f : views) times.push_back(f->time);
  const double mid_time = times[times.size() / 2];
  std::vector<const Frame*> at_time;
  for (const Frame* f : views)
    if (f->time == mid_time) at_time.push_back(f);
  return at_time[at_time.size() / 2];
}

// The shown view's ground truth and every run's renders, LDR and HDR, each with its error map.
std::string PicturesHtml(const Frame& view,
                         const std::vector<const RunSummary*>& runs,
                         const std::array<double, 4>& region,
                         int camera,
                         int* images) {
  std::string h = fmt::format(
      "<p>Test view {} (camera {}, t = {:.3f}, exposure {} s). LDR as rendered; HDR "
      "through the mu-law of the metrics (each image over its own maximum). Error "
      "maps: mean absolute difference over RGB, white = 0.5 or more. The box is the "
      "region of the luminance curves below.</p>\n",
      HtmlEscape(view.file_path), camera, view.time, view.exposure);
  h += "<table class=\"pics\"><thead><tr><th></th><th>LDR</th><th>LDR error</th><th>HDR (mu-law)</th><th>HDR error</th></tr></thead><tbody>\n";
  std::optional<Image> gt_ldr, gt_hdr_mu;
  if (fs::exists(view.image_path)) gt_ldr = ReadImage(view.image_path);
  if (view.hdr_path && fs::exists(*view.hdr_path))
    gt_hdr_mu = MuLawDisplay(ReadImage(*view.hdr_path));
  auto pic = [&](const Image& image, const std::string& alt) {
    ++*images;
    return "<td>" + HtmlImg(PngDataUri(image), alt, std::min(256, std::max(160, image.width()))) + "</td>";
  };
  const std::array<float, 3> box_colour = {0.1f, 0.9f, 0.2f};
  h += "<tr><th>ground truth</th>";
  h += gt_ldr ? pic(WithBox(*gt_ldr, region, box_colour), "ground truth LDR") : "<td>-</td>";
  h += "<td></td>";
  h += gt_hdr_mu ? pic(WithBox(*gt_hdr_mu, region, box_colour), "ground truth HDR") : "<td>-</td>";
  h += "<td></td></tr>\n";
  for (const RunSummary* r : runs) {
    const fs::path renders = r->source == "submit" ? fs::path(r->run_dir) : fs::path(r->run_dir) / "renders";
    h += "<tr><th>" + HtmlEscape(Name(*r)) + "</th>";
    const fs::path ldr = renders / LdrRenderName(view), hdr = renders / HdrRenderName(view);
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
  return h + "</tbody></table>\n";
}

// A curve over its own mean (NaN where the mean is not positive), so shapes compare.
PlotSeries OverItsMean(const std::map<double, double>& points,
                       std::string name,
                       const std::array<float, 3>& color) {
  PlotSeries s;
  s.name = std::move(name);
  s.style = PlotSeries::kLineMarkers;
  s.color = color;
  std::vector<double> v;
  for (const auto& [t, y] : points) v.push_back(y);
  const double m = Mean(v);
  for (const auto& [t, y] : points) {
    s.x.push_back(t);
    s.y.push_back(m > 0 ? y / m : NAN);
  }
  return s;
}

// The runs' curves of one per-frame statistic of the region (`kind`) that have two points or
// more, each over its own mean; *gt gets the ground truth's points (`kind`_gt).
std::vector<PlotSeries> RunCurves(const char* kind,
                                  const std::vector<const RunSummary*>& runs,
                                  const ResultsStore& store,
                                  int camera,
                                  std::map<double, double>* gt) {
  std::vector<PlotSeries> lum;
  int colour = 0;
  for (const RunSummary* r : runs) {
    std::map<double, double> points;
    for (const FrameResult& f : store.Frames(r->run_id)) {
      if (f.camera_id != camera) continue;
      if (auto it = f.stats.find(kind); it != f.stats.end()) points[f.time] = it->second;
      if (auto it = f.stats.find(std::string(kind) + "_gt"); it != f.stats.end())
        (*gt)[f.time] = it->second;
    }
    if (points.size() < 2) {
      ++colour;
      continue;
    }
    lum.push_back(OverItsMean(points, Name(*r), PaletteColor(colour++)));
  }
  return lum;
}

// Temporal luminance of the region: each curve over its own mean, so shapes compare (the
// absolute level of an HDR render learned from LDR images is arbitrary). HDR luminance where
// the runs and the ground truth have it, else LDR luma (drawn even without its ground truth).
std::string RegionLuminanceHtml(const std::string& scene,
                                const std::vector<const RunSummary*>& runs,
                                const ResultsStore& store,
                                int camera,
                                int* images) {
  std::vector<PlotSeries> lum;
  bool hdr_curves = false;
  for (const char* kind : {"region_luminance", "region_ldr"}) {
    std::map<double, double> gt;
    lum = RunCurves(kind, runs, store, camera, &gt);
    if (lum.empty() || gt.size() < 2) continue;
    lum.insert(lum.begin(), OverItsMean(gt, "ground truth", {0, 0, 0}));
    hdr_curves = std::string(kind) == "region_luminance";
    break;
  }
  if (lum.empty()) return "";
  PlotOptions o;
  o.title = fmt::format("{}: region {} over time, camera {}", scene,
                        hdr_curves ? "luminance" : "LDR luma", camera);
  o.x_label = "normalised time";
  o.y_label = "region mean / its mean over time (log)";
  o.log_y = true;
  o.width = 900;
  o.height = 480;
  ++*images;
  return "<h4>Temporal luminance of a region (Figs. 4-5)</h4>\n" +
         HtmlImg(PlotDataUri(lum, o), scene + " temporal luminance") + "\n";
}

// One run's learned tone curves (green channel), one line per time, coloured by time.
std::vector<PlotSeries> ToneCurveLines(const std::map<std::string, Series>& series) {
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
  return lines;
}

// Learned tone curves over time (green channel), one panel per method that has them.
std::string ToneCurvesHtml(const std::string& scene,
                           const std::vector<const RunSummary*>& runs,
                           const ResultsStore& store,
                           int* images) {
  std::vector<PlotPanel> panels;
  for (const RunSummary* r : runs) {
    std::vector<PlotSeries> lines = ToneCurveLines(store.AllSeries(r->run_id));
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
  if (panels.empty()) return "";
  ++*images;
  return "<h4>Learned tone curves over time (green channel)</h4>\n" +
         HtmlImg(PlotGridDataUri(panels, std::min<int>(3, static_cast<int>(panels.size()))),
                 scene + " tone curves") +
         "\n";
}

// Training-view PSNR against iteration, one line per run.
std::string TrainingCurvesHtml(const std::string& scene,
                               const std::vector<const RunSummary*>& runs,
                               const ResultsStore& store,
                               int* images) {
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
  if (train.empty()) return "";
  PlotOptions o;
  o.title = scene + ": training-view PSNR";
  o.x_label = "iteration";
  o.y_label = "PSNR (dB)";
  o.width = 900;
  o.height = 420;
  ++*images;
  return "<h4>Training curves</h4>\n" + HtmlImg(PlotDataUri(train, o), scene + " training curves") +
         "\n";
}

}  // namespace

std::string SceneHtml(const std::string& scene,
                      const std::vector<const RunSummary*>& runs,
                      const ResultsStore& store,
                      int* images) {
  std::string h =
      fmt::format("<h3 id=\"scene-{}\">{}</h3>\n", HtmlEscape(scene), HtmlEscape(scene));
  if (runs.empty()) return h + "<p>No finished runs.</p>\n";
  const nlohmann::json scoring =
      store.Config(runs.front()->run_id).value("scoring", nlohmann::json::object());
  std::array<double, 4> region = {0.4375, 0.4375, 0.125, 0.125};
  if (scoring.contains("region")) region = scoring["region"].get<std::array<double, 4>>();
  const int camera = scoring.value("region_camera", -1);
  const fs::path scene_dir = runs.front()->scene_dir;
  if (!fs::exists(scene_dir / "transforms_test.json"))
    return h + "<p>The scene folder " + HtmlEscape(scene_dir.string()) +
           " is not on this machine; pictures left out.</p>\n";
  const Dataset dataset = LoadDataset(scene_dir, {.image_check = ImageCheck::kNone});
  const Frame* view = ShownView(dataset, camera);
  if (!view) return h + "<p>No test view of the region camera.</p>\n";
  h += PicturesHtml(*view, runs, region, camera, images);
  h += FlipMapsHtml(*view, runs, images);
  h += RegionLuminanceHtml(scene, runs, store, camera, images);
  h += ToneCurvesHtml(scene, runs, store, images);
  h += TrainingCurvesHtml(scene, runs, store, images);
  return h;
}

}  // namespace hdr4d::bench
