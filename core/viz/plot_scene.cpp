// A chart laid out as drawing items: grid, series marks (clipped), frame, ticks, labels, title,
// point labels and the legend, placed where it covers the fewest data samples.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/util/error.h"
#include "core/viz/plot.h"
#include "core/viz/plot_scene.h"
#include "core/viz/text.h"

namespace hdr4d::plot_internal {
namespace {

constexpr Rgb kTextColor = {0.1f, 0.1f, 0.1f};
constexpr Rgb kFrameColor = {0.25f, 0.25f, 0.25f};
constexpr Rgb kGridColor = {0.88f, 0.88f, 0.88f};
constexpr Rgb kMinorGridColor = {0.95f, 0.95f, 0.95f};
constexpr Rgb kMutedColor = {0.55f, 0.55f, 0.55f};
constexpr Rgb kLegendBorderColor = {0.7f, 0.7f, 0.7f};
constexpr Rgb kWhite = {1.0f, 1.0f, 1.0f};

// Liang-Barsky: clips segment a-b to `r`; false when nothing is left.
bool ClipSegment(const Rect& r, Point* a, Point* b) {
  const double dx = (*b)[0] - (*a)[0];
  const double dy = (*b)[1] - (*a)[1];
  double t0 = 0.0, t1 = 1.0;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {(*a)[0] - r.x0, r.x1 - (*a)[0], (*a)[1] - r.y0, r.y1 - (*a)[1]};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const Point start = *a;
  *a = {start[0] + t0 * dx, start[1] + t0 * dy};
  *b = {start[0] + t1 * dx, start[1] + t1 * dy};
  return true;
}

// Splits the series into drawable runs (broken at skipped points) clipped near the plot area.
MarkItem SeriesMark(const PlotSeries& s, const PlotFrame& f, const PlotOptions& o, Rect area) {
  MarkItem mark;
  mark.title = s.name;
  mark.color = s.color;
  mark.line_width = o.line_width;
  mark.marker_radius = o.marker_radius;
  mark.marker = s.marker;
  mark.clip = area;
  const bool lines = s.style != PlotSeries::kMarkers;
  const bool markers = s.style != PlotSeries::kLine;
  const Rect line_bounds = area.Expanded(o.line_width + 2.0);
  const Rect marker_bounds = area.Expanded(o.marker_radius + 2.0);
  std::vector<Point> run;
  auto flush = [&] {
    if (run.size() >= 2) mark.runs.push_back(run);
    run.clear();
  };
  Point previous{};
  bool have_previous = false;  // a plain flag: GCC misreads std::optional<array> here
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    const Point p = {f.PixelX(s.x[i]), f.PixelY(s.y[i])};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1])) {
      flush();
      have_previous = false;
      continue;
    }
    if (markers && marker_bounds.Contains(p)) mark.markers.push_back(p);
    if (lines && have_previous) {
      Point a = previous, b = p;
      if (ClipSegment(line_bounds, &a, &b)) {
        if (run.empty() || run.back() != a) {
          flush();
          run.push_back(a);
        }
        run.push_back(b);
      } else {
        flush();
      }
    }
    previous = p;
    have_previous = true;
  }
  flush();
  return mark;
}

int TickColumn(const PlotFrame& f, double value) {
  return std::clamp(static_cast<int>(std::floor(f.PixelX(value))), f.left, f.right - 1);
}
int TickRow(const PlotFrame& f, double value) {
  return std::clamp(static_cast<int>(std::floor(f.PixelY(value))), f.top, f.bottom - 1);
}

// Where the legend goes: the requested corner, or the corner covering the fewest data samples.
Rect PlaceLegend(const PlotOptions& o,
                 const PlotFrame& f,
                 double w,
                 double h,
                 int pad,
                 const std::vector<Point>& samples) {
  const Rect top_left = {f.left + pad + 0.0, f.top + pad + 0.0, f.left + pad + w, f.top + pad + h};
  const Rect top_right = {f.right - pad - w, f.top + pad + 0.0, f.right - pad + 0.0,
                          f.top + pad + h};
  const Rect bottom_left = {top_left.x0, f.bottom - pad - h, top_left.x1, f.bottom - pad + 0.0};
  const Rect bottom_right = {top_right.x0, bottom_left.y0, top_right.x1, bottom_left.y1};
  switch (o.legend_placement) {
    case LegendPlacement::kTopLeft:
      return top_left;
    case LegendPlacement::kTopRight:
      return top_right;
    case LegendPlacement::kBottomLeft:
      return bottom_left;
    case LegendPlacement::kBottomRight:
      return bottom_right;
    case LegendPlacement::kAuto:
      break;
  }
  Rect best = top_right;
  long best_count = std::numeric_limits<long>::max();
  for (const Rect& r : {top_right, top_left, bottom_right, bottom_left}) {
    const Rect padded = r.Expanded(pad);
    const long count = std::count_if(samples.begin(), samples.end(),
                                     [&](const Point& p) { return padded.Contains(p); });
    if (count < best_count) {
      best = r;
      best_count = count;
    }
  }
  return best;
}

void AddLegend(const std::vector<PlotSeries>& series,
               const PlotOptions& o,
               const PlotFrame& f,
               const Layout& l,
               const std::vector<Point>& samples,
               Scene* scene) {
  std::vector<const PlotSeries*> entries;
  for (const PlotSeries& s : series) {
    if (!s.name.empty()) entries.push_back(&s);
  }
  if (!o.legend || entries.empty()) return;
  const int gap = l.pad / 2;
  const int sample_width = 3 * kGlyphAdvance * l.font_scale;
  // As many entries as fit in the plot area.
  const int max_rows = (f.bottom - f.top - 4 * l.pad + gap) / (l.text_height + gap);
  if (max_rows < 1) return;
  if (static_cast<int>(entries.size()) > max_rows) entries.resize(max_rows);
  int name_width = 0;
  for (const PlotSeries* s : entries)
    name_width = std::max(name_width, TextWidth(s->name, l.font_scale));
  const int n = static_cast<int>(entries.size());
  const double w = 3 * l.pad + sample_width + name_width;
  const double h = 2 * l.pad + n * l.text_height + (n - 1) * gap;
  if (w > f.right - f.left - 2 * l.pad) return;
  const Rect box = PlaceLegend(o, f, w, h, l.pad, samples);
  scene->items.push_back(BoxItem{box, kWhite, kLegendBorderColor});
  for (int i = 0; i < n; ++i) {
    const PlotSeries& s = *entries[i];
    const double top = box.y0 + l.pad + i * (l.text_height + gap);
    const double center_y = std::floor(top + 0.5 * kGlyphBaseline * l.font_scale) + 0.5;
    const double x0 = box.x0 + l.pad;
    MarkItem mark;
    mark.color = s.color;
    mark.line_width = o.line_width;
    mark.marker_radius = std::min(o.marker_radius, 0.5 * l.text_height);
    mark.marker = s.marker;
    if (s.style != PlotSeries::kMarkers) {
      mark.runs.push_back({{x0, center_y}, {x0 + sample_width, center_y}});
    }
    if (s.style != PlotSeries::kLine) mark.markers.push_back({x0 + 0.5 * sample_width, center_y});
    scene->items.push_back(std::move(mark));
    scene->items.push_back(
        LabelItem{x0 + sample_width + l.pad, top, s.name, kTextColor, l.font_scale, false});
  }
}

void AddPointLabels(const std::vector<PlotSeries>& series,
                    const PlotOptions& o,
                    const PlotFrame& f,
                    const Layout& l,
                    Scene* scene) {
  for (const PlotSeries& s : series) {
    const double offset = (s.style == PlotSeries::kLine ? o.line_width : o.marker_radius) + 2.0;
    for (std::size_t i = 0; i < s.point_labels.size(); ++i) {
      const std::string& text = s.point_labels[i];
      if (text.empty()) continue;
      const double px = f.PixelX(s.x[i]);
      const double py = f.PixelY(s.y[i]);
      if (!(px >= f.left && px <= f.right && py >= f.top && py <= f.bottom)) continue;
      const int w = TextWidth(text, l.font_scale);
      if (w + 4 > f.right - f.left || l.text_height + 4 > f.bottom - f.top) continue;
      double x = px + offset;  // right of the point, or left of it near the right edge
      if (x + w > f.right - 2) x = px - offset - w;
      double y = py - offset - 0.5 * l.text_height;
      x = std::clamp(x, f.left + 2.0, f.right - 2.0 - w);
      y = std::clamp(y, f.top + 2.0, f.bottom - 2.0 - l.text_height);
      scene->items.push_back(LabelItem{x, y, text, kTextColor, l.font_scale, false});
    }
  }
}

// Grid lines at every tick, the minor ones first (lighter), under everything else.
void AddGrid(const PlotFrame& f, const Rect& area, std::vector<Item>* items) {
  auto vertical = [&](double v, const Rgb& c) {
    const int x = TickColumn(f, v);
    items->push_back(BoxItem{{x + 0.0, area.y0, x + 1.0, area.y1}, c, std::nullopt});
  };
  auto horizontal = [&](double v, const Rgb& c) {
    const int y = TickRow(f, v);
    items->push_back(BoxItem{{area.x0, y + 0.0, area.x1, y + 1.0}, c, std::nullopt});
  };
  for (double v : f.x_minor_ticks) vertical(v, kMinorGridColor);
  for (double v : f.y_minor_ticks) horizontal(v, kMinorGridColor);
  for (const AxisTick& t : f.x_ticks) vertical(t.value, kGridColor);
  for (const AxisTick& t : f.y_ticks) horizontal(t.value, kGridColor);
}

// The series' lines and markers; returns where the data is drawn, to keep the legend off it.
std::vector<Point> AddSeriesMarks(const std::vector<PlotSeries>& series,
                                  const PlotFrame& f,
                                  const PlotOptions& o,
                                  const Rect& area,
                                  std::vector<Item>* items) {
  std::vector<Point> samples;
  for (const PlotSeries& s : series) {
    MarkItem mark = SeriesMark(s, f, o, area);
    for (const auto& run : mark.runs) {
      for (std::size_t i = 0; i + 1 < run.size(); ++i) {
        for (int k = 0; k < 8; ++k) {
          const double t = k / 8.0;
          samples.push_back({run[i][0] + t * (run[i + 1][0] - run[i][0]),
                             run[i][1] + t * (run[i + 1][1] - run[i][1])});
        }
      }
      samples.push_back(run.back());
    }
    samples.insert(samples.end(), mark.markers.begin(), mark.markers.end());
    items->push_back(std::move(mark));
  }
  return samples;
}

// Frame, ticks (minor ones half as long) and tick labels.
void AddFrameAndTicks(const PlotFrame& f,
                      const PlotOptions& o,
                      const Layout& l,
                      const Rect& area,
                      std::vector<Item>* items) {
  items->push_back(BoxItem{area.Expanded(1.0), std::nullopt, kFrameColor});
  const int fs = l.font_scale;
  for (double v : f.x_minor_ticks) {
    const int x = TickColumn(f, v);
    items->push_back(BoxItem{{x + 0.0, area.y1 + 1, x + 1.0, area.y1 + 1 + l.tick_length / 2},
                             kFrameColor,
                             std::nullopt});
  }
  for (double v : f.y_minor_ticks) {
    const int y = TickRow(f, v);
    items->push_back(BoxItem{{area.x0 - 1 - l.tick_length / 2, y + 0.0, area.x0 - 1, y + 1.0},
                             kFrameColor,
                             std::nullopt});
  }
  for (const AxisTick& t : f.x_ticks) {
    const int x = TickColumn(f, t.value);
    items->push_back(BoxItem{
        {x + 0.0, area.y1 + 1, x + 1.0, area.y1 + 1 + l.tick_length}, kFrameColor, std::nullopt});
    const int w = TextWidth(t.label, fs);
    const double lx = std::clamp(x + 0.5 - 0.5 * w, 0.0, static_cast<double>(o.width - w));
    items->push_back(LabelItem{std::round(lx), area.y1 + 1 + l.tick_length + l.pad / 2, t.label,
                               kTextColor, fs, false});
  }
  for (const AxisTick& t : f.y_ticks) {
    const int y = TickRow(f, t.value);
    items->push_back(BoxItem{
        {area.x0 - 1 - l.tick_length, y + 0.0, area.x0 - 1, y + 1.0}, kFrameColor, std::nullopt});
    const int w = TextWidth(t.label, fs);
    const double ly = std::clamp(y + 0.5 - 0.5 * kGlyphBaseline * fs, 0.0,
                                 static_cast<double>(o.height - l.text_height));
    items->push_back(LabelItem{area.x0 - 1 - l.tick_length - l.pad / 2 - w, std::round(ly), t.label,
                               kTextColor, fs, false});
  }
}

// Axis labels (the y label turned up) and the title, one size larger.
void AddAxisLabelsAndTitle(const PlotOptions& o,
                           const Layout& l,
                           const Rect& area,
                           std::vector<Item>* items) {
  const int fs = l.font_scale;
  if (!o.x_label.empty()) {
    const int w = TextWidth(o.x_label, fs);
    items->push_back(LabelItem{std::round(std::max(0.0, 0.5 * (area.x0 + area.x1 - w))),
                               o.height - l.pad - l.text_height + 0.0, o.x_label, kTextColor, fs,
                               false});
  }
  if (!o.y_label.empty()) {
    const int w = TextWidth(o.y_label, fs);
    items->push_back(LabelItem{static_cast<double>(l.pad),
                               std::round(std::max(0.0, 0.5 * (area.y0 + area.y1 - w))), o.y_label,
                               kTextColor, fs, true});
  }
  if (!o.title.empty()) {
    const int w = TextWidth(o.title, fs + 1);
    const double x =
        std::clamp(0.5 * (area.x0 + area.x1 - w), 0.0, std::max(0.0, o.width - w + 0.0));
    items->push_back(
        LabelItem{std::round(x), static_cast<double>(l.pad), o.title, kTextColor, fs + 1, false});
  }
}

}  // namespace

Scene BuildScene(const std::vector<PlotSeries>& series, const PlotOptions& o) {
  const PlotFrame f = ComputePlotFrame(series, o);
  const Layout l = LayoutFor(o);
  Scene scene{o.width, o.height, {}};
  const Rect area = {static_cast<double>(f.left), static_cast<double>(f.top),
                     static_cast<double>(f.right), static_cast<double>(f.bottom)};
  if (o.grid) AddGrid(f, area, &scene.items);
  const std::vector<Point> samples = AddSeriesMarks(series, f, o, area, &scene.items);
  AddFrameAndTicks(f, o, l, area, &scene.items);
  AddAxisLabelsAndTitle(o, l, area, &scene.items);
  if (!f.has_data) {
    const std::string text = "no data";
    const int w = TextWidth(text, l.font_scale);
    scene.items.push_back(LabelItem{std::round(0.5 * (area.x0 + area.x1 - w)),
                                    std::round(0.5 * (area.y0 + area.y1 - l.text_height)), text,
                                    kMutedColor, l.font_scale, false});
  }
  AddPointLabels(series, o, f, l, &scene);
  AddLegend(series, o, f, l, samples, &scene);
  return scene;
}

}  // namespace hdr4d::plot_internal
