// The parts of core/viz/plot.cpp's charts that its files share: a chart as a list of drawing
// items (boxes, series marks, labels), laid out once and drawn by the raster and the SVG back
// ends, and the sizes both the options and the grids check. Not part of the public API.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/image/image.h"
#include "core/viz/plot.h"
#include "core/viz/text.h"

namespace hdr4d::plot_internal {

using Rgb = std::array<float, 3>;
using Point = std::array<double, 2>;

// A chart's side in pixels (and a grid's), and its largest font scale.
constexpr int kMinSize = 100;
constexpr int kMaxSize = 16384;
constexpr int kMaxFontScale = 8;

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

struct Layout {
  int font_scale = 2;
  int text_height = 16;
  int pad = 8;
  int tick_length = 5;
};

inline Layout LayoutFor(const PlotOptions& o) {
  Layout l;
  l.font_scale = o.font_scale;
  l.text_height = TextHeight(o.font_scale);
  l.pad = 4 * o.font_scale;
  l.tick_length = 2 + 2 * o.font_scale;
  return l;
}

// Tick labels' numbers without trailing zeros (plot_axes.cpp).
std::string TrimZeros(std::string text);

// The chart's layout as items (plot_scene.cpp).
Scene BuildScene(const std::vector<PlotSeries>& series, const PlotOptions& o);

// The raster back end (plot_raster.cpp).
Image Rasterize(const Scene& scene);

// The SVG back end (plot_svg.cpp): a scene's elements (ids prefixed, so that panels of a grid
// keep them unique) and the document around them.
std::string SvgBody(const Scene& scene, const std::string& id_prefix);
std::string SvgDocument(int width, int height, const std::string& body);

}  // namespace hdr4d::plot_internal
