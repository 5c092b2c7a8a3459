// The raster back end: a laid-out chart drawn into an sRGB image, anti-aliased by distance.
#include <algorithm>
#include <cmath>

#include "core/image/image.h"
#include "core/viz/plot_scene.h"
#include "core/viz/text.h"

namespace hdr4d::plot_internal {
namespace {

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

}  // namespace

Image Rasterize(const Scene& scene) {
  Image image(scene.width, scene.height, 3, Encoding::kSrgb, 1.0f);
  for (const Item& item : scene.items) {
    if (const auto* box = std::get_if<BoxItem>(&item)) RasterBox(*box, &image);
    if (const auto* mark = std::get_if<MarkItem>(&item)) RasterMark(*mark, &image);
    if (const auto* label = std::get_if<LabelItem>(&item)) RasterLabel(*label, &image);
  }
  return image;
}

}  // namespace hdr4d::plot_internal
