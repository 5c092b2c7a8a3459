// The SVG back end: a laid-out chart as SVG elements, with the same layout as the raster one.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>

#include "core/viz/plot_scene.h"

namespace hdr4d::plot_internal {
namespace {

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

}  // namespace

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

}  // namespace hdr4d::plot_internal
