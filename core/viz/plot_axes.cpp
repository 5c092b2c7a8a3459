// Axes: tick positions and labels, the shown ranges, the checks of options and series, and the
// plot frame (where the data area sits and which ticks fit).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"
#include "core/viz/plot.h"
#include "core/viz/plot_scene.h"
#include "core/viz/text.h"

namespace hdr4d::plot_internal {
namespace {

constexpr int kMaxTicks = 100;  // guards tick loops against precision loss at huge magnitudes
constexpr double kRangeMargin = 0.04;  // of the data span, so no point sits on the frame
constexpr double kEps = 1e-9;
constexpr double kMax = std::numeric_limits<double>::max();

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

// Removes the trailing zeros of a fixed-point mantissa ("2.50" -> "2.5", "3.0" -> "3").
std::string TrimZeros(std::string text) {
  if (text.find('.') == std::string::npos) return text;
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text;
}

}  // namespace hdr4d::plot_internal

namespace hdr4d {

// The public functions below use the parts of plot_scene.h through function-scope using-directives,
// which stay out of the other files of a unity build.

void PlotOptions::Validate() const {
  using namespace plot_internal;
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
  using namespace plot_internal;
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

PlotFrame ComputePlotFrame(const std::vector<PlotSeries>& series, const PlotOptions& o) {
  using namespace plot_internal;
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
}  // namespace hdr4d
