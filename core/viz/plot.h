// Charts without a plotting library: line and scatter plots as PNG-ready images (built-in bitmap
// font, anti-aliased lines) and as SVG text with the same layout. Used by `hdr4d tone-curves`
// (tone curves per channel and time) and the benchmark harness (time against error, log x).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/image/image.h"

namespace hdr4d {

struct PlotSeries {
  enum Style { kLine, kMarkers, kLineMarkers };
  // Of the markers: with more series than palette colours, a shape tells two of one colour apart.
  enum Marker { kCircle, kSquare, kDiamond };

  std::string name;  // legend entry; unnamed series are left out of the legend
  std::vector<double> x, y;
  std::array<float, 3> color = {0.12f, 0.35f, 0.70f};  // display (sRGB) values in [0,1]
  Style style = kLine;
  Marker marker = kCircle;
  // Empty, or one label per point, drawn beside the point ("" draws none).
  std::vector<std::string> point_labels;
};

enum class LegendPlacement { kAuto, kTopLeft, kTopRight, kBottomLeft, kBottomRight };

struct AxisRange {
  double min = 0.0;
  double max = 1.0;
};

struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 800;  // pixels (SVG: user units)
  int height = 500;
  bool log_x = false;
  bool log_y = false;
  // Fixed ranges; unset ranges follow the data with a small margin.
  std::optional<AxisRange> x_range;
  std::optional<AxisRange> y_range;
  bool legend = true;
  LegendPlacement legend_placement = LegendPlacement::kAuto;  // kAuto: the emptiest corner
  bool grid = true;                                           // light lines at the ticks
  int font_scale = 2;          // glyph pixel size of labels; the title is one step larger
  double line_width = 2.0;     // pixels
  double marker_radius = 4.0;  // pixels

  // Throws hdr4d::Error naming the offending option.
  void Validate() const;
};

struct AxisTick {
  double value = 0.0;
  std::string label;
};

// Ticks of an axis showing [lo, hi] with at most about `max_ticks` labels: multiples of a
// 1-2-5 step on a linear axis; decades on a log axis (every k-th decade when there are many,
// 1-2-5 multiples or linear steps when the range holds fewer than two decades).
std::vector<AxisTick> ComputeAxisTicks(double lo, double hi, bool log, int max_ticks);

// Where a chart puts things: the plot area in pixels and the data range it shows.
struct PlotFrame {
  int left = 0, top = 0, right = 0, bottom = 0;  // plot area [left, right) x [top, bottom)
  double x_min = 0.0, x_max = 1.0, y_min = 0.0, y_max = 1.0;  // shown range (values, not logs)
  bool log_x = false, log_y = false;
  std::vector<AxisTick> x_ticks, y_ticks;
  std::vector<double> x_minor_ticks, y_minor_ticks;  // unlabelled (between decades)
  bool has_data = false;  // false when no point can be drawn: the chart says "no data"

  // Continuous pixel coordinates (pixel i spans [i, i + 1)); NaN for values that cannot be
  // shown (non-finite, or <= 0 on a log axis).
  double PixelX(double x) const;
  double PixelY(double y) const;
};

// Validates the options and series (x/y lengths, label counts, colours) and lays the chart out.
PlotFrame ComputePlotFrame(const std::vector<PlotSeries>& series, const PlotOptions& options);

// An RGB chart (Encoding::kSrgb, values in [0,1], white background): ready for WriteImage to
// PNG. Points with a NaN/Inf coordinate, or <= 0 on a log axis, are skipped and break lines.
Image RenderPlot(const std::vector<PlotSeries>& series, const PlotOptions& options);
// The same chart as a standalone SVG document.
std::string RenderPlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options);

// Several charts tiled left to right, top to bottom, `columns` per row; every cell is as large
// as the largest panel. Throws hdr4d::Error for no panels or columns < 1.
using PlotPanel = std::pair<std::vector<PlotSeries>, PlotOptions>;
Image RenderPlotGrid(const std::vector<PlotPanel>& panels, int columns);
std::string RenderPlotGridSvg(const std::vector<PlotPanel>& panels, int columns);

// Writes the chart by extension: .png (RenderPlot + WriteImage) or .svg (atomic text write).
// Throws hdr4d::Error naming the path for any other extension or a failed write.
void WritePlot(const std::filesystem::path& path,
               const std::vector<PlotSeries>& series,
               const PlotOptions& options);
void WritePlotGrid(const std::filesystem::path& path,
                   const std::vector<PlotPanel>& panels,
                   int columns);

// Distinct colours for categories (cycles after 10) and a dark-to-light ramp for ordered ones
// such as times (t in [0,1], clamped). PaletteMarker: the marker shape of category `index`,
// the next shape each time the colours cycle, so the first 30 categories differ in one or both.
std::array<float, 3> PaletteColor(int index);
PlotSeries::Marker PaletteMarker(int index);
std::array<float, 3> SequentialColor(double t);

}  // namespace hdr4d
