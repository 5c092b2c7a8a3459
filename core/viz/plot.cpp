#include "core/viz/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/viz/plot_scene.h"

// Charts as PNG or SVG, one or a grid of them, and the palettes. The layout is in
// plot_axes.cpp (frame and ticks) and plot_scene.cpp (items), the back ends in plot_raster.cpp
// and plot_svg.cpp.

namespace hdr4d::plot_internal {
namespace {

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
}  // namespace hdr4d::plot_internal

namespace hdr4d {

// The public functions below use the parts of plot_scene.h through function-scope using-directives,
// which stay out of the other files of a unity build.

Image RenderPlot(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  using namespace plot_internal;
  return Rasterize(BuildScene(series, options));
}

std::string RenderPlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  using namespace plot_internal;
  const Scene scene = BuildScene(series, options);
  return SvgDocument(scene.width, scene.height, SvgBody(scene, ""));
}

Image RenderPlotGrid(const std::vector<PlotPanel>& panels, int columns) {
  using namespace plot_internal;
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
  using namespace plot_internal;
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
  using namespace plot_internal;
  WriteByExtension(
      path, [&] { return RenderPlot(series, options); },
      [&] { return RenderPlotSvg(series, options); });
}

void WritePlotGrid(const std::filesystem::path& path,
                   const std::vector<PlotPanel>& panels,
                   int columns) {
  using namespace plot_internal;
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
  static constexpr std::array<plot_internal::Rgb, 10> kPalette = {{
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
  static constexpr std::array<plot_internal::Rgb, 5> kStops = {{
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
  std::array<float, 3> out;
  for (int c = 0; c < 3; ++c) out[c] = kStops[i][c] + w * (kStops[i + 1][c] - kStops[i][c]);
  return out;
}

}  // namespace hdr4d
