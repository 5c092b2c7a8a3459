#include "core/viz/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/viz/text.h"

namespace hdr4d {
namespace {

using Rgb = std::array<float, 3>;
using Point = std::array<double, 2>;

constexpr Rgb kTextColor = {0.1f, 0.1f, 0.1f};
constexpr Rgb kFrameColor = {0.25f, 0.25f, 0.25f};
constexpr Rgb kGridColor = {0.88f, 0.88f, 0.88f};
constexpr Rgb kMinorGridColor = {0.95f, 0.95f, 0.95f};
constexpr Rgb kMutedColor = {0.55f, 0.55f, 0.55f};
constexpr Rgb kLegendBorderColor = {0.7f, 0.7f, 0.7f};
constexpr Rgb kWhite = {1.0f, 1.0f, 1.0f};

constexpr int kMinSize = 100;
constexpr int kMaxSize = 16384;
constexpr int kMaxFontScale = 8;
constexpr int kMaxTicks = 100;  // guards tick loops against precision loss at huge magnitudes
constexpr double kRangeMargin = 0.04;  // of the data span, so no point sits on the frame
constexpr double kEps = 1e-9;
constexpr double kMax = std::numeric_limits<double>::max();

// ---------------------------------------------------------------------------------------------
// Ticks and ranges.

double NiceStep(double raw) {
  const double exponent = std::floor(std::log10(raw));
  const double base = std::pow(10.0, exponent);
  const double fraction = raw / base;
  const double nice = fraction <= 1.0 + kEps   ? 1.0
                      : fraction <= 2.0 + kEps ? 2.0
                      : fraction <= 5.0 + kEps ? 5.0
                                               : 10.0;
  return nice * base;
}

// Removes the trailing zeros of a fixed-point mantissa ("2.50" -> "2.5", "3.0" -> "3").
std::string TrimZeros(std::string text) {
  if (text.find('.') == std::string::npos) return text;
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text;
}

// Compact scientific notation: 2e-5, 1.5e6.
std::string FormatScientific(double value, int decimals) {
  if (value == 0.0) return "0";
  int exponent = static_cast<int>(std::floor(std::log10(std::abs(value)) + kEps));
  std::string mantissa =
      fmt::format("{:.{}f}", value / std::pow(10.0, exponent), std::max(decimals, 0));
  if (mantissa == "10" || mantissa.rfind("10.", 0) == 0 || mantissa.rfind("-10", 0) == 0) {
    ++exponent;  // rounding carried into the next power of ten
    mantissa = fmt::format("{:.{}f}", value / std::pow(10.0, exponent), std::max(decimals, 0));
  }
  return fmt::format("{}e{}", TrimZeros(mantissa), exponent);
}

std::string FormatLinearTick(double value, double step, double max_abs) {
  if (std::abs(value) < step * 1e-6) value = 0.0;  // no "-0" or "1e-17" for zero
  const int step_exponent = static_cast<int>(std::floor(std::log10(step) + kEps));
  if (max_abs >= 1e6 || step_exponent < -4) {
    if (value == 0.0) return "0";
    const int value_exponent = static_cast<int>(std::floor(std::log10(std::abs(value)) + kEps));
    return FormatScientific(value, value_exponent - step_exponent);
  }
  return fmt::format("{:.{}f}", value, std::max(0, -step_exponent));
}

std::string FormatLogTick(double value) {
  const int exponent = static_cast<int>(std::floor(std::log10(value) + kEps));
  if (exponent >= -3 && exponent <= 4) return TrimZeros(fmt::format("{:.{}f}", value, 6));
  return FormatScientific(value, 2);
}

std::vector<AxisTick> LinearTicks(double lo, double hi, int max_ticks) {
  const double raw = hi / (max_ticks - 1) - lo / (max_ticks - 1);  // no overflow near kMax
  const double step = NiceStep(raw);
  std::vector<AxisTick> ticks;
  if (!(step > 0.0) || !std::isfinite(step)) {
    ticks.push_back({lo, FormatScientific(lo, 3)});
    ticks.push_back({hi, FormatScientific(hi, 3)});
    return ticks;
  }
  const double max_abs = std::max(std::abs(lo), std::abs(hi));
  const double first = std::ceil(lo / step - kEps);
  for (int i = 0; i < kMaxTicks; ++i) {
    const double value = (first + i) * step;
    if (value > hi + step * kEps) break;
    if (!ticks.empty() && value <= ticks.back().value) continue;  // precision exhausted
    ticks.push_back({value, FormatLinearTick(value, step, max_abs)});
  }
  // A coarse step can leave one multiple in range; a finer one gives the axis a scale.
  if (ticks.size() < 2 && max_ticks < 20) return LinearTicks(lo, hi, max_ticks + 1);
  return ticks;
}

std::vector<AxisTick> LogTicks(double lo, double hi, int max_ticks) {
  const double a = std::log10(lo);
  const double b = std::log10(hi);
  const int first_decade = static_cast<int>(std::ceil(a - kEps));
  const int last_decade = static_cast<int>(std::floor(b + kEps));
  std::vector<AxisTick> ticks;
  if (last_decade - first_decade + 1 >= 2) {
    // Every stride-th decade, the stride from 1, 2, 5, 10, 20, ... so at most max_ticks remain.
    long stride = 1;
    auto count = [&](long s) {
      long n = 0;
      for (long k = first_decade; k <= last_decade; ++k) n += (k % s == 0);
      return n;
    };
    for (int i = 0; count(stride) > max_ticks; ++i)
      stride = (i % 3 == 1) ? stride * 5 / 2 : stride * 2;
    for (long k = first_decade; k <= last_decade; ++k) {
      if (k % stride != 0) continue;
      const double value = std::pow(10.0, static_cast<double>(k));
      ticks.push_back({value, FormatLogTick(value)});
    }
    if (ticks.size() >= 2) return ticks;
    ticks.clear();
    for (int k : {first_decade, last_decade}) {
      const double value = std::pow(10.0, static_cast<double>(k));
      ticks.push_back({value, FormatLogTick(value)});
    }
    return ticks;
  }
  // Less than two decades: 1-2-5 multiples of the decades around the range.
  for (int k = static_cast<int>(std::floor(a)) - 1; k <= static_cast<int>(std::ceil(b)); ++k) {
    for (double mantissa : {1.0, 2.0, 5.0}) {
      const double value = mantissa * std::pow(10.0, static_cast<double>(k));
      if (value >= lo * (1 - kEps) && value <= hi * (1 + kEps)) {
        ticks.push_back({value, FormatLogTick(value)});
      }
    }
  }
  if (ticks.size() >= 2 && static_cast<int>(ticks.size()) <= max_ticks) return ticks;
  return LinearTicks(lo, hi, max_ticks);
}

// Unlabelled ticks at 2..9 x each decade, when decades are labelled one by one.
std::vector<double> LogMinorTicks(double lo, double hi, const std::vector<AxisTick>& ticks) {
  std::vector<double> minor;
  const double a = std::log10(lo);
  const double b = std::log10(hi);
  if (b - a > 12) return minor;  // too dense to help
  for (int k = static_cast<int>(std::floor(a)); k <= static_cast<int>(std::ceil(b)); ++k) {
    for (int m = 2; m <= 9; ++m) {
      const double value = m * std::pow(10.0, static_cast<double>(k));
      if (value < lo || value > hi) continue;
      const bool labelled = std::any_of(ticks.begin(), ticks.end(), [&](const AxisTick& t) {
        return std::abs(t.value - value) <= value * 1e-9;
      });
      if (!labelled) minor.push_back(value);
    }
  }
  return minor;
}

// The shown range of one axis: the fixed range, or the data span with a margin.
AxisRange AutoRange(double lo, double hi, bool have_data, bool log) {
  if (!have_data) return log ? AxisRange{1.0, 10.0} : AxisRange{0.0, 1.0};
  if (log) {
    double a = std::log10(lo);
    double b = std::log10(hi);
    if (b - a < kEps) {
      a -= 0.5;  // a single value: show the decade around it
      b += 0.5;
    } else {
      const double margin = kRangeMargin * (b - a);
      a -= margin;
      b += margin;
    }
    return {std::pow(10.0, std::max(a, -307.0)), std::pow(10.0, std::min(b, 308.0))};
  }
  if (hi - lo <= std::max(std::abs(lo), std::abs(hi)) * 1e-12) {
    const double center = 0.5 * lo + 0.5 * hi;
    const double pad = center != 0.0 ? 0.1 * std::abs(center) : 1.0;
    return {std::max(center - pad, -kMax), std::min(center + pad, kMax)};
  }
  const double margin = kRangeMargin * hi - kRangeMargin * lo;
  return {std::max(lo - margin, -kMax), std::min(hi + margin, kMax)};
}

std::string SeriesName(const PlotSeries& series, std::size_t index) {
  return series.name.empty() ? fmt::format("#{}", index) : fmt::format("'{}'", series.name);
}

void ValidateSeries(const std::vector<PlotSeries>& series) {
  for (std::size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    if (s.x.size() != s.y.size()) {
      Fail("plot series {}: x has {} values but y has {}", SeriesName(s, i), s.x.size(),
           s.y.size());
    }
    if (!s.point_labels.empty() && s.point_labels.size() != s.x.size()) {
      Fail("plot series {}: {} point_labels for {} points", SeriesName(s, i), s.point_labels.size(),
           s.x.size());
    }
    for (float c : s.color) {
      if (!(c >= 0.0f && c <= 1.0f)) {
        Fail("plot series {}: color components must be in [0,1], got ({}, {}, {})",
             SeriesName(s, i), s.color[0], s.color[1], s.color[2]);
      }
    }
    if (s.style != PlotSeries::kLine && s.style != PlotSeries::kMarkers &&
        s.style != PlotSeries::kLineMarkers) {
      Fail("plot series {}: unknown style {}", SeriesName(s, i), static_cast<int>(s.style));
    }
    if (s.marker != PlotSeries::kCircle && s.marker != PlotSeries::kSquare &&
        s.marker != PlotSeries::kDiamond) {
      Fail("plot series {}: unknown marker {}", SeriesName(s, i), static_cast<int>(s.marker));
    }
  }
}

void ValidateRange(const std::optional<AxisRange>& range, bool log, const char* axis) {
  if (!range) return;
  if (!std::isfinite(range->min) || !std::isfinite(range->max) || !(range->min < range->max)) {
    Fail("plot options: {}_range [{}, {}] must be finite with min < max", axis, range->min,
         range->max);
  }
  if (log && range->min <= 0.0) {
    Fail("plot options: {}_range [{}, {}] must be positive on a log axis (log_{})", axis,
         range->min, range->max, axis);
  }
}

// ---------------------------------------------------------------------------------------------
// A chart as a list of drawing items, so the raster and the SVG back ends share one layout.

struct Rect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool Contains(const Point& p) const {
    return p[0] >= x0 && p[0] <= x1 && p[1] >= y0 && p[1] <= y1;
  }
  Rect Expanded(double d) const { return {x0 - d, y0 - d, x1 + d, y1 + d}; }
  bool operator==(const Rect&) const = default;
};

struct BoxItem {
  Rect rect;
  std::optional<Rgb> fill;
  std::optional<Rgb> stroke;  // 1 pixel, inside the rect
};

// One series' lines and markers, drawn as one layer so overlapping strokes do not darken.
struct MarkItem {
  std::string title;
  std::vector<std::vector<Point>> runs;  // polylines
  std::vector<Point> markers;
  Rgb color{};
  double line_width = 2.0;
  double marker_radius = 4.0;
  PlotSeries::Marker marker = PlotSeries::kCircle;
  std::optional<Rect> clip;
};

// Half the side of a square marker of radius r, per unit r: sqrt(pi) / 2, the circle's area.
constexpr double kMarkerHalfSide = 0.886;

// Distance from p to the edge of a marker of radius r centred at m (negative inside). The
// square and diamond have the circle's area, so no shape dominates the eye.
double MarkerEdgeDistance(PlotSeries::Marker shape, Point m, double r, double px, double py) {
  const double dx = std::abs(px - m[0]), dy = std::abs(py - m[1]);
  switch (shape) {
    case PlotSeries::kSquare:
      return std::max(dx, dy) - kMarkerHalfSide * r;
    case PlotSeries::kDiamond:
      return (dx + dy) / std::sqrt(2.0) - kMarkerHalfSide * r;  // the square turned 45 degrees
    case PlotSeries::kCircle:
      break;
  }
  return std::hypot(dx, dy) - r;
}

struct LabelItem {
  double x = 0, y = 0;  // top-left of the text box (of the turned box when `up`)
  std::string text;
  Rgb color{};
  int scale = 1;
  bool up = false;
};

using Item = std::variant<BoxItem, MarkItem, LabelItem>;

struct Scene {
  int width = 0;
  int height = 0;
  std::vector<Item> items;
};

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

struct Layout {
  int font_scale = 2;
  int text_height = 16;
  int pad = 8;
  int tick_length = 5;
};

Layout LayoutFor(const PlotOptions& o) {
  Layout l;
  l.font_scale = o.font_scale;
  l.text_height = TextHeight(o.font_scale);
  l.pad = 4 * o.font_scale;
  l.tick_length = 2 + 2 * o.font_scale;
  return l;
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

// ---------------------------------------------------------------------------------------------
// Raster back end.

void Blend(Image* image, int x, int y, const Rgb& color, float alpha) {
  for (int c = 0; c < 3; ++c) {
    float& v = image->at(x, y, c);
    v += alpha * (color[c] - v);
  }
}

struct PixelRect {
  int x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
};

PixelRect ToPixels(const Rect& r, int width, int height) {
  return {std::clamp(static_cast<int>(std::lround(r.x0)), 0, width),
          std::clamp(static_cast<int>(std::lround(r.y0)), 0, height),
          std::clamp(static_cast<int>(std::lround(r.x1)), 0, width),
          std::clamp(static_cast<int>(std::lround(r.y1)), 0, height)};
}

void RasterBox(const BoxItem& box, Image* image) {
  const PixelRect r = ToPixels(box.rect, image->width(), image->height());
  if (box.fill) {
    for (int y = r.y0; y < r.y1; ++y) {
      for (int x = r.x0; x < r.x1; ++x) Blend(image, x, y, *box.fill, 1.0f);
    }
  }
  if (box.stroke && r.x1 > r.x0 && r.y1 > r.y0) {
    for (int x = r.x0; x < r.x1; ++x) {
      Blend(image, x, r.y0, *box.stroke, 1.0f);
      Blend(image, x, r.y1 - 1, *box.stroke, 1.0f);
    }
    for (int y = r.y0; y < r.y1; ++y) {
      Blend(image, r.x0, y, *box.stroke, 1.0f);
      Blend(image, r.x1 - 1, y, *box.stroke, 1.0f);
    }
  }
}

// Anti-aliasing by distance: a pixel centre at distance d from the shape's edge is covered by
// about clamp(0.5 - d); the coverage of one series is the maximum over its strokes and markers,
// so joints and overlaps of one colour do not darken.
void RasterMark(const MarkItem& mark, Image* image) {
  Rect clip_rect = {0, 0, static_cast<double>(image->width()),
                    static_cast<double>(image->height())};
  if (mark.clip) {
    clip_rect = {std::max(clip_rect.x0, mark.clip->x0), std::max(clip_rect.y0, mark.clip->y0),
                 std::min(clip_rect.x1, mark.clip->x1), std::min(clip_rect.y1, mark.clip->y1)};
  }
  const PixelRect clip = ToPixels(clip_rect, image->width(), image->height());
  const int cw = clip.x1 - clip.x0;
  const int ch = clip.y1 - clip.y0;
  if (cw <= 0 || ch <= 0) return;
  std::vector<float> coverage(static_cast<std::size_t>(cw) * ch, 0.0f);
  auto cover = [&](double x0, double y0, double x1, double y1, auto&& coverage_at) {
    const int px0 = std::max(clip.x0, static_cast<int>(std::floor(x0)));
    const int py0 = std::max(clip.y0, static_cast<int>(std::floor(y0)));
    const int px1 = std::min(clip.x1, static_cast<int>(std::ceil(x1)));
    const int py1 = std::min(clip.y1, static_cast<int>(std::ceil(y1)));
    for (int y = py0; y < py1; ++y) {
      for (int x = px0; x < px1; ++x) {
        const float c = static_cast<float>(coverage_at(x + 0.5, y + 0.5));
        float& slot = coverage[static_cast<std::size_t>(y - clip.y0) * cw + (x - clip.x0)];
        slot = std::max(slot, c);
      }
    }
  };
  const double half = 0.5 * mark.line_width;
  for (const auto& run : mark.runs) {
    for (std::size_t i = 0; i + 1 < run.size(); ++i) {
      const Point a = run[i];
      const Point b = run[i + 1];
      const double dx = b[0] - a[0];
      const double dy = b[1] - a[1];
      const double length2 = dx * dx + dy * dy;
      const double reach = half + 1.0;
      cover(std::min(a[0], b[0]) - reach, std::min(a[1], b[1]) - reach,
            std::max(a[0], b[0]) + reach, std::max(a[1], b[1]) + reach, [&](double x, double y) {
              double t = length2 > 0 ? ((x - a[0]) * dx + (y - a[1]) * dy) / length2 : 0.0;
              t = std::clamp(t, 0.0, 1.0);
              const double d = std::hypot(x - a[0] - t * dx, y - a[1] - t * dy);
              return std::clamp(half + 0.5 - d, 0.0, 1.0);
            });
    }
  }
  const double r = mark.marker_radius;
  for (const Point& m : mark.markers) {
    cover(m[0] - r - 1, m[1] - r - 1, m[0] + r + 1, m[1] + r + 1, [&](double x, double y) {
      return std::clamp(0.5 - MarkerEdgeDistance(mark.marker, m, r, x, y), 0.0, 1.0);
    });
  }
  for (int y = 0; y < ch; ++y) {
    for (int x = 0; x < cw; ++x) {
      const float c = coverage[static_cast<std::size_t>(y) * cw + x];
      if (c > 0.0f) Blend(image, clip.x0 + x, clip.y0 + y, mark.color, c);
    }
  }
}

void RasterLabel(const LabelItem& label, Image* image) {
  const int x = static_cast<int>(std::lround(label.x));
  const int y = static_cast<int>(std::lround(label.y));
  if (label.up) {
    DrawTextUp(image, x, y, label.text, label.color, label.scale);
  } else {
    DrawText(image, x, y, label.text, label.color, label.scale);
  }
}

Image Rasterize(const Scene& scene) {
  Image image(scene.width, scene.height, 3, Encoding::kSrgb, 1.0f);
  for (const Item& item : scene.items) {
    if (const auto* box = std::get_if<BoxItem>(&item)) RasterBox(*box, &image);
    if (const auto* mark = std::get_if<MarkItem>(&item)) RasterMark(*mark, &image);
    if (const auto* label = std::get_if<LabelItem>(&item)) RasterLabel(*label, &image);
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// SVG back end.

std::string Num(double v) { return TrimZeros(fmt::format("{:.2f}", v)); }

std::string Hex(const Rgb& c) {
  auto byte = [](float v) {
    return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255));
  };
  return fmt::format("#{:02x}{:02x}{:02x}", byte(c[0]), byte(c[1]), byte(c[2]));
}

// XML text: markup characters escaped; characters the bitmap font draws as a box (control bytes,
// each non-ASCII code point) become a white square, so both versions say the same.
std::string EscapeXml(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto u = static_cast<unsigned char>(c);
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        if (HasGlyph(c)) {
          out += c;
        } else if ((u & 0xC0) == 0x80 && i > 0 && static_cast<unsigned char>(text[i - 1]) >= 0x80) {
          // continuation of a code point already boxed
        } else {
          out += "&#x25A1;";
        }
    }
  }
  return out;
}

std::string SvgText(const LabelItem& label) {
  const int width = TextWidth(label.text, label.scale);
  // A monospace font at font-size 10*s advances ~6*s per glyph with caps ~7*s high, like the
  // bitmap font; textLength pins the width exactly.
  std::string attributes = fmt::format(
      "font-family=\"DejaVu Sans Mono, monospace\" font-size=\"{}\" textLength=\"{}\" "
      "lengthAdjust=\"spacingAndGlyphs\" fill=\"{}\" xml:space=\"preserve\"",
      10 * label.scale, width, Hex(label.color));
  const int baseline = kGlyphBaseline * label.scale;
  if (label.up) {
    return fmt::format(
        "<text transform=\"translate({} {}) rotate(-90)\" x=\"0\" y=\"{}\" {}>{}</text>\n",
        Num(label.x), Num(label.y + width), baseline, attributes, EscapeXml(label.text));
  }
  return fmt::format("<text x=\"{}\" y=\"{}\" {}>{}</text>\n", Num(label.x),
                     Num(label.y + baseline), attributes, EscapeXml(label.text));
}

// The clip rectangles of the marks, each once, in order of first use.
std::vector<Rect> ClipsOf(const Scene& scene) {
  std::vector<Rect> clips;
  for (const Item& item : scene.items) {
    const auto* mark = std::get_if<MarkItem>(&item);
    if (mark && mark->clip && std::find(clips.begin(), clips.end(), *mark->clip) == clips.end()) {
      clips.push_back(*mark->clip);
    }
  }
  return clips;
}

std::string SvgClipDefs(const std::vector<Rect>& clips, const std::string& id_prefix) {
  if (clips.empty()) return "";
  std::string out = "<defs>\n";
  for (std::size_t i = 0; i < clips.size(); ++i) {
    const Rect& r = clips[i];
    out += fmt::format(
        "<clipPath id=\"{}clip{}\"><rect x=\"{}\" y=\"{}\" width=\"{}\" "
        "height=\"{}\"/></clipPath>\n",
        id_prefix, i, Num(r.x0), Num(r.y0), Num(r.x1 - r.x0), Num(r.y1 - r.y0));
  }
  return out + "</defs>\n";
}

std::string SvgBox(const BoxItem& box) {
  std::string out;
  const Rect& r = box.rect;
  if (box.fill) {
    out += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\"/>\n",
                       Num(r.x0), Num(r.y0), Num(r.x1 - r.x0), Num(r.y1 - r.y0), Hex(*box.fill));
  }
  if (box.stroke) {  // the raster strokes the outermost pixel ring: centre the line on it
    out += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"{}\" "
        "stroke-width=\"1\"/>\n",
        Num(r.x0 + 0.5), Num(r.y0 + 0.5), Num(r.x1 - r.x0 - 1), Num(r.y1 - r.y0 - 1),
        Hex(*box.stroke));
  }
  return out;
}

std::string SvgMarker(const MarkItem& mark, const Point& m) {
  const double h = kMarkerHalfSide * mark.marker_radius;  // as MarkerEdgeDistance
  const double d = h * std::sqrt(2.0);
  switch (mark.marker) {
    case PlotSeries::kSquare:
      return fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{}\"/>\n",
                         Num(m[0] - h), Num(m[1] - h), Num(2 * h), Num(2 * h), Hex(mark.color));
    case PlotSeries::kDiamond:
      return fmt::format("<polygon points=\"{},{} {},{} {},{} {},{}\" fill=\"{}\"/>\n", Num(m[0]),
                         Num(m[1] - d), Num(m[0] + d), Num(m[1]), Num(m[0]), Num(m[1] + d),
                         Num(m[0] - d), Num(m[1]), Hex(mark.color));
    case PlotSeries::kCircle:
      return fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\"/>\n", Num(m[0]),
                         Num(m[1]), Num(mark.marker_radius), Hex(mark.color));
  }
  return "";
}

// One series: a group (clipped to the plot area) of polylines and markers, titled by its name.
std::string SvgMark(const MarkItem& mark,
                    const std::vector<Rect>& clips,
                    const std::string& id_prefix) {
  std::string clip;
  if (mark.clip) {
    const auto index = std::find(clips.begin(), clips.end(), *mark.clip) - clips.begin();
    clip = fmt::format(" clip-path=\"url(#{}clip{})\"", id_prefix, index);
  }
  std::string out = fmt::format("<g{}>\n", clip);
  if (!mark.title.empty()) out += fmt::format("<title>{}</title>\n", EscapeXml(mark.title));
  for (const auto& run : mark.runs) {
    std::string points;
    for (const Point& p : run) {
      if (!points.empty()) points += ' ';
      points += Num(p[0]) + ',' + Num(p[1]);
    }
    out += fmt::format(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" "
        "stroke-linejoin=\"round\" stroke-linecap=\"round\"/>\n",
        points, Hex(mark.color), Num(mark.line_width));
  }
  for (const Point& m : mark.markers) out += SvgMarker(mark, m);
  return out + "</g>\n";
}

std::string SvgBody(const Scene& scene, const std::string& id_prefix) {
  const std::vector<Rect> clips = ClipsOf(scene);
  std::string out = SvgClipDefs(clips, id_prefix);
  out += fmt::format("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n",
                     scene.width, scene.height);
  for (const Item& item : scene.items) {
    if (const auto* box = std::get_if<BoxItem>(&item)) {
      out += SvgBox(*box);
    } else if (const auto* mark = std::get_if<MarkItem>(&item)) {
      out += SvgMark(*mark, clips, id_prefix);
    } else if (const auto* label = std::get_if<LabelItem>(&item)) {
      out += SvgText(*label);
    }
  }
  return out;
}

std::string SvgDocument(int width, int height, const std::string& body) {
  return fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" "
      "viewBox=\"0 0 {0} {1}\">\n{2}</svg>\n",
      width, height, body);
}

// Grid geometry shared by both back ends.
struct GridShape {
  int columns = 1, rows = 1, cell_width = 0, cell_height = 0;
};

GridShape ShapeOfGrid(const std::vector<PlotPanel>& panels, int columns) {
  if (panels.empty()) Fail("plot grid: no panels to draw");
  if (columns < 1) Fail("plot grid: columns must be >= 1, got {}", columns);
  GridShape g;
  g.columns = std::min<int>(columns, static_cast<int>(panels.size()));
  g.rows = (static_cast<int>(panels.size()) + g.columns - 1) / g.columns;
  for (const PlotPanel& p : panels) {
    p.second.Validate();
    g.cell_width = std::max(g.cell_width, p.second.width);
    g.cell_height = std::max(g.cell_height, p.second.height);
  }
  if (static_cast<long>(g.cell_width) * g.columns > kMaxSize ||
      static_cast<long>(g.cell_height) * g.rows > kMaxSize) {
    Fail("plot grid: {} panels of up to {}x{} in {} columns exceed {} pixels", panels.size(),
         g.cell_width, g.cell_height, g.columns, kMaxSize);
  }
  return g;
}

std::string LowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

template <typename RenderPng, typename RenderSvg>
void WriteByExtension(const std::filesystem::path& path, RenderPng&& png, RenderSvg&& svg) {
  const std::string ext = LowerExtension(path);
  if (ext == ".png") {
    WriteImage(path, png());
  } else if (ext == ".svg") {
    WriteTextFileAtomic(path, svg());
  } else {
    Fail("{}: a plot is written as .png or .svg, not '{}'", path.string(), ext);
  }
}

}  // namespace

// -----------------------------------------------------------------------------------------------
// Public API.

void PlotOptions::Validate() const {
  if (width < kMinSize || width > kMaxSize) {
    Fail("plot options: width must be in [{}, {}], got {}", kMinSize, kMaxSize, width);
  }
  if (height < kMinSize || height > kMaxSize) {
    Fail("plot options: height must be in [{}, {}], got {}", kMinSize, kMaxSize, height);
  }
  if (font_scale < 1 || font_scale > kMaxFontScale) {
    Fail("plot options: font_scale must be in [1, {}], got {}", kMaxFontScale, font_scale);
  }
  if (!(line_width > 0.0 && line_width <= 50.0)) {
    Fail("plot options: line_width must be in (0, 50], got {}", line_width);
  }
  if (!(marker_radius > 0.0 && marker_radius <= 100.0)) {
    Fail("plot options: marker_radius must be in (0, 100], got {}", marker_radius);
  }
  ValidateRange(x_range, log_x, "x");
  ValidateRange(y_range, log_y, "y");
}

std::vector<AxisTick> ComputeAxisTicks(double lo, double hi, bool log, int max_ticks) {
  HDR4D_CHECK(std::isfinite(lo) && std::isfinite(hi) && lo < hi);
  HDR4D_CHECK(!log || lo > 0.0);
  max_ticks = std::max(max_ticks, 2);
  return log ? LogTicks(lo, hi, max_ticks) : LinearTicks(lo, hi, max_ticks);
}

double PlotFrame::PixelX(double x) const {
  double t;
  if (log_x) {
    if (!(x > 0.0) || !std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
    t = (std::log10(x) - std::log10(x_min)) / (std::log10(x_max) - std::log10(x_min));
  } else {
    if (!std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
    t = (0.5 * x - 0.5 * x_min) / (0.5 * x_max - 0.5 * x_min);  // halves: no overflow
  }
  return left + t * (right - left);
}

double PlotFrame::PixelY(double y) const {
  double t;
  if (log_y) {
    if (!(y > 0.0) || !std::isfinite(y)) return std::numeric_limits<double>::quiet_NaN();
    t = (std::log10(y) - std::log10(y_min)) / (std::log10(y_max) - std::log10(y_min));
  } else {
    if (!std::isfinite(y)) return std::numeric_limits<double>::quiet_NaN();
    t = (0.5 * y - 0.5 * y_min) / (0.5 * y_max - 0.5 * y_min);
  }
  return bottom - t * (bottom - top);
}

namespace {

// The axis ranges: given, or from the data's extents over drawable points; with one axis fixed,
// the other follows the points inside it. Sets has_data.
void SetRanges(const std::vector<PlotSeries>& series, const PlotOptions& o, PlotFrame* f) {
  auto usable = [](double v, bool log) { return std::isfinite(v) && (!log || v > 0.0); };
  auto inside = [](double v, const std::optional<AxisRange>& r) {
    return !r || (v >= r->min && v <= r->max);
  };
  double x_lo = kMax, x_hi = -kMax, y_lo = kMax, y_hi = -kMax;
  bool have_x = false, have_y = false;
  for (const PlotSeries& s : series) {
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const double x = s.x[i], y = s.y[i];
      if (!usable(x, o.log_x) || !usable(y, o.log_y)) continue;
      f->has_data = true;
      if (inside(y, o.y_range)) {
        x_lo = std::min(x_lo, x);
        x_hi = std::max(x_hi, x);
        have_x = true;
      }
      if (inside(x, o.x_range)) {
        y_lo = std::min(y_lo, y);
        y_hi = std::max(y_hi, y);
        have_y = true;
      }
    }
  }
  const AxisRange xr = o.x_range ? *o.x_range : AutoRange(x_lo, x_hi, have_x, o.log_x);
  const AxisRange yr = o.y_range ? *o.y_range : AutoRange(y_lo, y_hi, have_y, o.log_y);
  f->x_min = xr.min;
  f->x_max = xr.max;
  f->y_min = yr.min;
  f->y_max = yr.max;
}

[[noreturn]] void NoRoom(const char* option, int size, int font_scale) {
  Fail("plot options: {} {} leaves no room for the plot area at font_scale {}", option, size,
       font_scale);
}

// x ticks for the current left and right: fewer until neighbouring labels keep two glyphs apart.
void FitXTicks(const PlotOptions& o, int fs, PlotFrame* f) {
  const int min_gap = 2 * kGlyphAdvance * fs;
  for (int max_x_ticks = std::clamp((f->right - f->left) / (6 * kGlyphAdvance * fs) + 1, 2, 11);;
       --max_x_ticks) {
    f->x_ticks = ComputeAxisTicks(f->x_min, f->x_max, o.log_x, max_x_ticks);
    bool fits = true;
    for (std::size_t i = 1; i < f->x_ticks.size(); ++i) {
      const double distance = f->PixelX(f->x_ticks[i].value) - f->PixelX(f->x_ticks[i - 1].value);
      const double needed =
          0.5 * (TextWidth(f->x_ticks[i].label, fs) + TextWidth(f->x_ticks[i - 1].label, fs)) +
          min_gap;
      fits = fits && distance >= needed;
    }
    if (fits || max_x_ticks <= 2) break;
  }
}

// The right edge and the x ticks: fit the ticks, then make room on the right for the last
// label and repeat once, as the room changes the spacing.
void PlaceXTicks(const PlotOptions& o, const Layout& l, PlotFrame* f) {
  const int fs = l.font_scale;
  int right_margin = 2 * l.pad;
  for (int pass = 0; pass < 3; ++pass) {
    f->right = o.width - right_margin;
    if (f->right - f->left < 4 * l.text_height) NoRoom("width", o.width, fs);
    FitXTicks(o, fs, f);
    int needed_right = 2 * l.pad;
    for (const AxisTick& t : f->x_ticks) {
      const double overhang = f->PixelX(t.value) + 0.5 * TextWidth(t.label, fs) - f->right;
      needed_right = std::max(needed_right, static_cast<int>(std::ceil(overhang)) + l.pad);
    }
    if (needed_right <= right_margin) break;
    right_margin = needed_right;
  }
}

}  // namespace

PlotFrame ComputePlotFrame(const std::vector<PlotSeries>& series, const PlotOptions& o) {
  o.Validate();
  ValidateSeries(series);
  PlotFrame f;
  f.log_x = o.log_x;
  f.log_y = o.log_y;
  SetRanges(series, o, &f);

  // Margins: title above; tick labels and the x label below; the turned y label and the y tick
  // labels on the left; room for half of the last x tick label on the right.
  const Layout l = LayoutFor(o);
  const int fs = l.font_scale;
  f.top = o.title.empty() ? l.pad + l.text_height / 2 : 2 * l.pad + TextHeight(fs + 1);
  const int below = 1 + l.tick_length + l.pad / 2 + l.text_height +
                    (o.x_label.empty() ? 0 : l.pad + l.text_height) + l.pad;
  f.bottom = o.height - below;
  if (f.bottom - f.top < 2 * l.text_height) NoRoom("height", o.height, fs);

  const int max_y_ticks = std::clamp((f.bottom - f.top) / (3 * l.text_height) + 1, 2, 11);
  f.y_ticks = ComputeAxisTicks(f.y_min, f.y_max, o.log_y, max_y_ticks);
  int y_label_width = 0;
  for (const AxisTick& t : f.y_ticks)
    y_label_width = std::max(y_label_width, TextWidth(t.label, fs));
  f.left = l.pad + (o.y_label.empty() ? 0 : l.text_height + l.pad) + y_label_width + l.pad / 2 +
           l.tick_length + 1;
  PlaceXTicks(o, l, &f);

  if (o.log_x) f.x_minor_ticks = LogMinorTicks(f.x_min, f.x_max, f.x_ticks);
  if (o.log_y) f.y_minor_ticks = LogMinorTicks(f.y_min, f.y_max, f.y_ticks);
  return f;
}

Image RenderPlot(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  return Rasterize(BuildScene(series, options));
}

std::string RenderPlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  const Scene scene = BuildScene(series, options);
  return SvgDocument(scene.width, scene.height, SvgBody(scene, ""));
}

Image RenderPlotGrid(const std::vector<PlotPanel>& panels, int columns) {
  const GridShape g = ShapeOfGrid(panels, columns);
  Image grid(g.columns * g.cell_width, g.rows * g.cell_height, 3, Encoding::kSrgb, 1.0f);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const Image panel = RenderPlot(panels[i].first, panels[i].second);
    const int x0 = static_cast<int>(i % g.columns) * g.cell_width;
    const int y0 = static_cast<int>(i / g.columns) * g.cell_height;
    for (int y = 0; y < panel.height(); ++y) {
      for (int x = 0; x < panel.width(); ++x) {
        for (int c = 0; c < 3; ++c) grid.at(x0 + x, y0 + y, c) = panel.at(x, y, c);
      }
    }
  }
  return grid;
}

std::string RenderPlotGridSvg(const std::vector<PlotPanel>& panels, int columns) {
  const GridShape g = ShapeOfGrid(panels, columns);
  const int width = g.columns * g.cell_width;
  const int height = g.rows * g.cell_height;
  std::string body = fmt::format(
      "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>\n", width, height);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const Scene scene = BuildScene(panels[i].first, panels[i].second);
    body +=
        fmt::format("<svg x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\">\n",
                    static_cast<int>(i % g.columns) * g.cell_width,
                    static_cast<int>(i / g.columns) * g.cell_height, scene.width, scene.height,
                    scene.width, scene.height);
    body += SvgBody(scene, fmt::format("p{}-", i));  // ids stay unique across panels
    body += "</svg>\n";
  }
  return SvgDocument(width, height, body);
}

void WritePlot(const std::filesystem::path& path,
               const std::vector<PlotSeries>& series,
               const PlotOptions& options) {
  WriteByExtension(
      path, [&] { return RenderPlot(series, options); },
      [&] { return RenderPlotSvg(series, options); });
}

void WritePlotGrid(const std::filesystem::path& path,
                   const std::vector<PlotPanel>& panels,
                   int columns) {
  WriteByExtension(
      path, [&] { return RenderPlotGrid(panels, columns); },
      [&] { return RenderPlotGridSvg(panels, columns); });
}

PlotSeries::Marker PaletteMarker(int index) {
  constexpr int kColours = 10;  // PaletteColor's cycle
  const int cycle = (index < 0 ? -index : index) / kColours;
  return static_cast<PlotSeries::Marker>(cycle % 3);
}

std::array<float, 3> PaletteColor(int index) {
  // Ten hues that stay apart on white and for common colour-vision deficiencies.
  static constexpr std::array<Rgb, 10> kPalette = {{
      {0.00f, 0.45f, 0.70f},  // blue
      {0.90f, 0.45f, 0.00f},  // orange
      {0.00f, 0.60f, 0.45f},  // green
      {0.80f, 0.20f, 0.25f},  // red
      {0.50f, 0.35f, 0.75f},  // purple
      {0.55f, 0.35f, 0.20f},  // brown
      {0.85f, 0.40f, 0.70f},  // pink
      {0.40f, 0.40f, 0.40f},  // grey
      {0.65f, 0.65f, 0.05f},  // olive
      {0.05f, 0.70f, 0.80f},  // cyan
  }};
  const int n = static_cast<int>(kPalette.size());
  return kPalette[((index % n) + n) % n];
}

std::array<float, 3> SequentialColor(double t) {
  // Dark violet through blue and teal to amber: ordered by lightness, all visible on white.
  static constexpr std::array<Rgb, 5> kStops = {{
      {0.25f, 0.05f, 0.45f},
      {0.15f, 0.35f, 0.70f},
      {0.05f, 0.60f, 0.60f},
      {0.45f, 0.75f, 0.25f},
      {0.95f, 0.65f, 0.05f},
  }};
  if (!(t >= 0.0)) t = 0.0;  // NaN too
  t = std::min(t, 1.0);
  const double position = t * (kStops.size() - 1);
  const std::size_t i =
      std::min<std::size_t>(static_cast<std::size_t>(position), kStops.size() - 2);
  const float w = static_cast<float>(position - i);
  Rgb out;
  for (int c = 0; c < 3; ++c) out[c] = kStops[i][c] + w * (kStops[i + 1][c] - kStops[i][c]);
  return out;
}

}  // namespace hdr4d
