#include "method/run/tone_curve_report.h"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/viz/plot.h"
#include "method/run/render_split.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

std::string ToneCurvesOptions::Validate() const {
  if (run.empty()) return "--run: no run folder given";
  if (times.empty()) return "--times: give at least one time";
  for (double t : times) {
    if (!(t >= 0 && t <= 1)) return fmt::format("--times: {} is outside [0, 1]", t);
  }
  if (!(x_max > x_min) || !std::isfinite(x_min) || !std::isfinite(x_max))
    return "--x-min / --x-max: need finite x-min < x-max";
  if (samples < 2 || samples > 100000) return "--samples: must be within [2, 100000]";
  return "";
}

std::vector<fs::path> WriteToneCurves(const ToneCurvesOptions& options) {
  if (std::string p = options.Validate(); !p.empty()) Fail("tone-curves: {}", p);
  LoadedRun run = LoadRun(options.run);
  if (!run.tone_mapper) {
    Fail("{}: this run ({}) has no tone mapper", options.run.string(),
         run.MethodName());
  }
  const ToneCurveSamples s = SampleToneCurves(run.tone_mapper.get(), options.times, run.num_times,
                                              options.x_min, options.x_max, options.samples);
  const fs::path out = options.out.empty() ? options.run / "tone_curves" : options.out;
  CheckOutputFolder(out);

  std::ostringstream csv;
  csv << "x";
  for (double t : s.times)
    for (const char* c : {"r", "g", "b"}) csv << fmt::format(",{}_t{:.4f}", c, t);
  csv << "\n";
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    csv << fmt::format("{:.6g}", s.x[i]);
    for (const auto& per_channel : s.ldr)
      for (const auto& values : per_channel) csv << fmt::format(",{:.6f}", values[i]);
    csv << "\n";
  }
  const fs::path csv_path = out / "tone_curves.csv";
  WriteTextFileAtomic(csv_path, csv.str());

  std::vector<PlotPanel> panels;
  const char* names[3] = {"red", "green", "blue"};
  for (int c = 0; c < 3; ++c) {
    std::vector<PlotSeries> series;
    for (std::size_t k = 0; k < s.times.size(); ++k) {
      PlotSeries line;
      line.name = fmt::format("t = {:.2f}", s.times[k]);
      line.x = s.x;
      line.y = s.ldr[k][c];
      line.color = SequentialColor(s.times.size() > 1 ? double(k) / (s.times.size() - 1) : 0.0);
      series.push_back(std::move(line));
    }
    PlotOptions o;
    o.title = fmt::format("{} tone curve ({})", names[c], run.tone_mapper->config().kind);
    o.x_label = "log radiance + log exposure";
    o.y_label = "LDR value";
    o.width = 560;
    o.height = 420;
    o.y_range = AxisRange{0.0, 1.0};
    panels.emplace_back(std::move(series), o);
  }
  const fs::path png = out / "tone_curves.png", svg = out / "tone_curves.svg";
  WritePlotGrid(png, panels, 3);
  WritePlotGrid(svg, panels, 3);
  return {csv_path, png, svg};
}

}  // namespace hdr4d::method
