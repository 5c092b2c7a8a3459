#include "core/viz/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/image/image_io.h"
#include "core/viz/text.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using testing::ErrorOf;
using testing::TempDir;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::array<float, 3> kBlue = {0.0f, 0.0f, 1.0f};

float Luminance(const Image& image, int x, int y) {
  return (image.at(x, y, 0) + image.at(x, y, 1) + image.at(x, y, 2)) / 3.0f;
}

bool IsDark(const Image& image, int x, int y) { return Luminance(image, x, y) < 0.5f; }

// Whether any pixel of [x0, x1) x [y0, y1) is dark.
bool AnyDark(const Image& image, int x0, int y0, int x1, int y1) {
  for (int y = std::max(y0, 0); y < std::min(y1, image.height()); ++y) {
    for (int x = std::max(x0, 0); x < std::min(x1, image.width()); ++x) {
      if (IsDark(image, x, y)) return true;
    }
  }
  return false;
}

// Whether the pixel is mostly blue (a kBlue series), unlike black text and grey lines.
bool IsBlue(const Image& image, int x, int y) {
  return image.at(x, y, 2) > 0.6f && image.at(x, y, 0) < 0.4f;
}

bool AnyBlue(const Image& image, int x0, int y0, int x1, int y1) {
  for (int y = std::max(y0, 0); y < std::min(y1, image.height()); ++y) {
    for (int x = std::max(x0, 0); x < std::min(x1, image.width()); ++x) {
      if (IsBlue(image, x, y)) return true;
    }
  }
  return false;
}

PlotSeries Series(std::string name, std::vector<double> x, std::vector<double> y) {
  PlotSeries s;
  s.name = std::move(name);
  s.x = std::move(x);
  s.y = std::move(y);
  s.color = kBlue;
  return s;
}

PlotSeries Diagonal(int n = 50) {
  PlotSeries s = Series("", {}, {});
  for (int i = 0; i < n; ++i) {
    s.x.push_back(i / (n - 1.0));
    s.y.push_back(i / (n - 1.0));
  }
  return s;
}

// Tag balance of an XML document: every opened element closed in order, attributes quoted in
// pairs, every '&' the start of an entity.
::testing::AssertionResult WellFormedXml(const std::string& xml) {
  std::vector<std::string> open;
  std::size_t i = 0;
  while ((i = xml.find_first_of("<&", i)) != std::string::npos) {
    if (xml[i] == '&') {
      const std::size_t semi = xml.find(';', i);
      const std::string entity = xml.substr(i + 1, semi == std::string::npos ? 0 : semi - i - 1);
      if (entity != "amp" && entity != "lt" && entity != "gt" && entity != "quot" &&
          entity != "apos" && entity.rfind("#x", 0) != 0) {
        return ::testing::AssertionFailure() << "bare '&' at " << i;
      }
      i = semi;
      continue;
    }
    const std::size_t end = xml.find('>', i);
    if (end == std::string::npos) return ::testing::AssertionFailure() << "unclosed '<' at " << i;
    const std::string tag = xml.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return ::testing::AssertionFailure() << "empty tag";
    if (tag.find('<') != std::string::npos) return ::testing::AssertionFailure() << "'<' in tag";
    if (std::count(tag.begin(), tag.end(), '"') % 2 != 0) {
      return ::testing::AssertionFailure() << "unbalanced quotes in <" << tag << ">";
    }
    if (tag.front() == '?') continue;  // declaration
    if (tag.front() == '/') {
      const std::string name = tag.substr(1);
      if (open.empty() || open.back() != name) {
        return ::testing::AssertionFailure()
               << "</" << name << "> closes <" << (open.empty() ? "" : open.back()) << ">";
      }
      open.pop_back();
      continue;
    }
    if (tag.back() == '/') continue;  // self-closing
    open.push_back(tag.substr(0, tag.find_first_of(" \n")));
  }
  if (!open.empty()) return ::testing::AssertionFailure() << "<" << open.back() << "> not closed";
  if (xml.find("<svg") == std::string::npos) return ::testing::AssertionFailure() << "no <svg>";
  return ::testing::AssertionSuccess();
}

// ------------------------------------------------------------------------------------------
// Font.

TEST(Text, EveryPrintableAsciiCharacterHasAGlyph) {
  for (int c = 32; c <= 126; ++c) {
    EXPECT_TRUE(HasGlyph(static_cast<char>(c))) << c;
    const GlyphRows glyph = GlyphFor(static_cast<char>(c));
    int ink = 0;
    for (std::uint8_t row : glyph) {
      EXPECT_EQ(row >> kGlyphWidth, 0) << "ink outside the glyph width for " << c;
      ink += __builtin_popcount(row);
    }
    if (c == ' ') {
      EXPECT_EQ(ink, 0);
    } else {
      EXPECT_GT(ink, 0) << "blank glyph for '" << static_cast<char>(c) << "'";
    }
  }
  EXPECT_FALSE(HasGlyph('\t'));
  EXPECT_FALSE(HasGlyph('\x7f'));
  EXPECT_FALSE(HasGlyph('\xc3'));
}

TEST(Text, GlyphsDifferPairwise) {
  auto all_differ = [](const std::string& chars) {
    for (std::size_t i = 0; i < chars.size(); ++i) {
      for (std::size_t j = i + 1; j < chars.size(); ++j) {
        EXPECT_NE(GlyphFor(chars[i]), GlyphFor(chars[j]))
            << "'" << chars[i] << "' and '" << chars[j] << "' look the same";
      }
    }
  };
  all_differ("0123456789");
  all_differ("ABCDEFGHIJKLMNOPQRSTUVWXYZ");
  std::string printable;
  for (int c = 32; c <= 126; ++c) printable += static_cast<char>(c);
  all_differ(printable);
  // The box of unknown characters is told apart from every real glyph.
  for (char c : printable) EXPECT_NE(GlyphFor('\t'), GlyphFor(c)) << c;
}

TEST(Text, WidthAndHeight) {
  EXPECT_EQ(TextWidth(""), 0);
  EXPECT_EQ(TextWidth("A"), kGlyphWidth);
  EXPECT_EQ(TextWidth("AB"), kGlyphAdvance + kGlyphWidth);
  EXPECT_EQ(TextWidth("AB", 3), 3 * (kGlyphAdvance + kGlyphWidth));
  EXPECT_EQ(TextHeight(2), 2 * kGlyphHeight);
  // A non-ASCII code point is one (boxed) character, not one per byte.
  EXPECT_EQ(TextLength("\xc2\xb5s"), 2);  // "µs"
  EXPECT_EQ(TextLength("a\tb"), 3);
}

TEST(Text, DrawTextStaysInsideItsBox) {
  const std::string text = "Hg|(e)_,H";  // ascender, descenders, edges of the box
  for (int scale : {1, 2, 3}) {
    Image image(200, 60, 3, Encoding::kSrgb, 0.0f);
    const int x0 = 7, y0 = 5;
    DrawText(&image, x0, y0, text, {1.0f, 0.5f, 0.25f}, scale);
    const int x1 = x0 + TextWidth(text, scale);
    const int y1 = y0 + TextHeight(scale);
    bool left = false, right = false, top = false, bottom = false;
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        if (image.at(x, y, 0) == 0.0f) continue;
        ASSERT_TRUE(x >= x0 && x < x1 && y >= y0 && y < y1) << x << "," << y << " scale " << scale;
        EXPECT_EQ(image.at(x, y, 1), 0.5f);
        left |= x == x0;
        right |= x == x1 - 1;
        top |= y == y0;
        bottom |= y == y1 - 1;
      }
    }
    // The box is tight: ink touches all four sides.
    EXPECT_TRUE(left && right && top && bottom) << "scale " << scale;
  }
}

TEST(Text, UnknownCharactersDrawABox) {
  Image image(40, 20, 3, Encoding::kSrgb, 0.0f);
  DrawText(&image, 0, 0, "\xc3\xa9", {1, 1, 1});  // "é": one box
  const GlyphRows box = GlyphFor('\x01');
  int inked = 0;
  for (int y = 0; y < kGlyphHeight; ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const bool expected = x < kGlyphWidth && (box[y] >> (kGlyphWidth - 1 - x)) & 1;
      EXPECT_EQ(image.at(x, y, 0) == 1.0f, expected) << x << "," << y;
      inked += expected;
    }
  }
  EXPECT_GT(inked, 10);
}

TEST(Text, DrawTextUpIsTheTextTurnedCounterClockwise) {
  const std::string text = "Ab1_";
  const int w = TextWidth(text, 2);
  const int h = TextHeight(2);
  Image flat(w, h, 3, Encoding::kSrgb, 0.0f);
  DrawText(&flat, 0, 0, text, {1, 1, 1}, 2);
  Image up(h + 10, w + 10, 3, Encoding::kSrgb, 0.0f);
  DrawTextUp(&up, 3, 4, text, {1, 1, 1}, 2);
  int inked = 0;
  for (int y = 0; y < up.height(); ++y) {
    for (int x = 0; x < up.width(); ++x) {
      const int v = x - 3;
      const int u = w - 1 - (y - 4);
      const bool inside = v >= 0 && v < h && u >= 0 && u < w;
      const float expected = inside ? flat.at(u, v, 0) : 0.0f;
      ASSERT_EQ(up.at(x, y, 0), expected) << x << "," << y;
      inked += expected > 0.0f;
    }
  }
  EXPECT_GT(inked, 40);
}

TEST(Text, ClipsAtTheImageEdges) {
  Image image(20, 10, 3, Encoding::kSrgb, 0.0f);
  DrawText(&image, -8, -3, "WWWWWWWW", {1, 1, 1}, 2);
  DrawTextUp(&image, 15, -20, "WWWWWWWW", {1, 1, 1}, 2);
  float sum = 0.0f;
  for (float v : image.values()) sum += v;
  EXPECT_GT(sum, 0.0f);
}

// ------------------------------------------------------------------------------------------
// Axes and ticks.

TEST(Plot, LinearTicksUseOneTwoFiveSteps) {
  const auto ticks = ComputeAxisTicks(0.0, 1.0, false, 6);
  ASSERT_EQ(ticks.size(), 6u);
  const std::vector<std::string> labels = {"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"};
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    EXPECT_NEAR(ticks[i].value, 0.2 * i, 1e-12);
    EXPECT_EQ(ticks[i].label, labels[i]);
  }
  const auto wide = ComputeAxisTicks(-3.7, 12.1, false, 5);
  ASSERT_GE(wide.size(), 2u);
  EXPECT_LE(wide.size(), 5u);
  EXPECT_EQ(wide[0].label, "0");
  EXPECT_EQ(wide[1].label, "5");
  // Even when asked for two ticks, an axis gets two.
  const auto few = ComputeAxisTicks(0.02, 945.0, false, 2);
  EXPECT_GE(few.size(), 2u);
  EXPECT_LE(few.size(), 4u);  // 200, 400, 600, 800: 500 would leave one
  // Large magnitudes switch to compact scientific labels.
  const auto big = ComputeAxisTicks(0.0, 5e6, false, 6);
  EXPECT_EQ(big[1].label, "1e6");
}

TEST(Plot, LogTicksSitAtDecades) {
  const auto ticks = ComputeAxisTicks(1e-3, 1e2, true, 10);
  const std::vector<std::string> labels = {"0.001", "0.01", "0.1", "1", "10", "100"};
  ASSERT_EQ(ticks.size(), labels.size());
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    EXPECT_NEAR(std::log10(ticks[i].value), -3.0 + i, 1e-12);
    EXPECT_EQ(ticks[i].label, labels[i]);
  }
  // Many decades: every k-th decade, still powers of ten.
  const auto many = ComputeAxisTicks(1e-10, 1e10, true, 6);
  ASSERT_GE(many.size(), 2u);
  EXPECT_LE(many.size(), 6u);
  for (const AxisTick& t : many) {
    const double e = std::log10(t.value);
    EXPECT_NEAR(e, std::round(e), 1e-9);
  }
  EXPECT_EQ(many.back().label, "1e10");
  // Less than two decades: 1-2-5 multiples.
  const auto narrow = ComputeAxisTicks(1.5, 30.0, true, 8);
  std::vector<double> values;
  for (const AxisTick& t : narrow) values.push_back(t.value);
  EXPECT_EQ(values, (std::vector<double>{2.0, 5.0, 10.0, 20.0}));
}

TEST(Plot, LogAxisPlacesDecadesEvenly) {
  PlotSeries s = Series("", {0.01, 0.1, 1, 10, 100}, {1, 2, 3, 4, 5});
  PlotOptions options;
  options.log_x = true;
  options.grid = false;
  const PlotFrame frame = ComputePlotFrame({s}, options);
  ASSERT_FALSE(frame.x_ticks.empty());
  for (const AxisTick& t : frame.x_ticks) {
    const double e = std::log10(t.value);
    EXPECT_NEAR(e, std::round(e), 1e-9) << t.label;
  }
  const double decade = frame.PixelX(10) - frame.PixelX(1);
  EXPECT_GT(decade, 50.0);
  EXPECT_NEAR(frame.PixelX(100) - frame.PixelX(10), decade, 1e-6);
  EXPECT_NEAR(frame.PixelX(0.1) - frame.PixelX(0.01), decade, 1e-6);
  EXPECT_FALSE(frame.x_minor_ticks.empty());
  // Tick marks under the plot area at the decades, none halfway between minor ticks.
  const Image image = RenderPlot({s}, options);
  const int row = frame.bottom + 2;
  for (double v : {0.1, 1.0, 10.0}) {
    EXPECT_TRUE(IsDark(image, static_cast<int>(std::floor(frame.PixelX(v))), row)) << v;
  }
  EXPECT_FALSE(IsDark(image, static_cast<int>(std::floor(frame.PixelX(3.5))), row));
  EXPECT_TRUE(std::isnan(frame.PixelX(0.0)));
  EXPECT_TRUE(std::isnan(frame.PixelX(-1.0)));
}

// ------------------------------------------------------------------------------------------
// Rendering.

TEST(Plot, LineYEqualsXFollowsTheDiagonal) {
  PlotOptions options;
  options.title = "y = x";
  options.x_label = "x";
  options.y_label = "y";
  const std::vector<PlotSeries> series = {Diagonal()};
  const Image image = RenderPlot(series, options);
  ASSERT_EQ(image.width(), 800);
  ASSERT_EQ(image.height(), 500);
  ASSERT_EQ(image.channels(), 3);
  EXPECT_EQ(image.encoding(), Encoding::kSrgb);
  for (float v : image.values()) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
  EXPECT_EQ(image.at(0, 0, 0), 1.0f);  // white background

  const PlotFrame f = ComputePlotFrame(series, options);
  ASSERT_GT(f.right - f.left, 400);
  ASSERT_GT(f.bottom - f.top, 250);
  for (double t = 0.05; t < 1.0; t += 0.05) {
    const int x = static_cast<int>(f.PixelX(t));
    const int y = static_cast<int>(f.PixelY(t));
    EXPECT_TRUE(AnyBlue(image, x - 1, y - 1, x + 2, y + 2)) << "no line at t = " << t;
  }
  // Far corners of the plot area (top-left, bottom-right) stay free of the series.
  const int w = (f.right - f.left) / 5;
  const int h = (f.bottom - f.top) / 5;
  EXPECT_FALSE(AnyBlue(image, f.left, f.top, f.left + w, f.top + h));
  EXPECT_FALSE(AnyBlue(image, f.right - w, f.bottom - h, f.right, f.bottom));
  // Nothing blue outside the plot area.
  EXPECT_FALSE(AnyBlue(image, 0, 0, f.left, image.height()));
  EXPECT_FALSE(AnyBlue(image, f.right, 0, image.width(), image.height()));
  // The frame, the title above and the tick labels below are drawn.
  EXPECT_TRUE(IsDark(image, f.left - 1, (f.top + f.bottom) / 2));
  EXPECT_TRUE(AnyDark(image, 0, 0, image.width(), f.top - 1));
  EXPECT_TRUE(AnyDark(image, f.left, f.bottom + 2, f.right, image.height()));
  // Lines are two pixels wide: the blue coverage (blue minus red, whatever lies below) summed
  // down one column is 2 / cos(slope).
  const double t = 0.55;
  const int cx = static_cast<int>(f.PixelX(t));
  const int cy = static_cast<int>(f.PixelY(t));
  double ink = 0.0;
  for (int y = cy - 8; y <= cy + 8; ++y) ink += image.at(cx, y, 2) - image.at(cx, y, 0);
  const double slope = (f.PixelY(0.0) - f.PixelY(1.0)) / (f.PixelX(1.0) - f.PixelX(0.0));
  EXPECT_NEAR(ink, 2.0 * std::sqrt(1.0 + slope * slope), 0.25);
}

TEST(Plot, NanAndInfPointsAreSkippedAndBreakTheLine) {
  PlotSeries s = Series("", {0, 1, 2, 3}, {0, 1, kNan, 0});
  s.x.push_back(kInf);
  s.y.push_back(7);
  PlotOptions options;
  options.grid = false;
  const PlotFrame f = ComputePlotFrame({s}, options);
  EXPECT_LT(f.x_max, 3.5);  // the Inf point does not stretch the range
  EXPECT_LT(f.y_max, 1.5);  // nor does the y of a point whose x is skipped
  const Image image = RenderPlot({s}, options);
  for (float v : image.values()) ASSERT_TRUE(std::isfinite(v));
  auto blue_near = [&](double x, double y) {
    const int px = static_cast<int>(f.PixelX(x));
    const int py = static_cast<int>(f.PixelY(y));
    return AnyBlue(image, px - 1, py - 1, px + 2, py + 2);
  };
  EXPECT_TRUE(blue_near(0.5, 0.5));   // (0,0)-(1,1) is drawn
  EXPECT_FALSE(blue_near(2.0, 0.5));  // (1,1) and (3,0) are not joined across the NaN
  EXPECT_FALSE(blue_near(2.5, 0.0));

  // Non-positive values on a log axis are skipped the same way.
  PlotSeries logged = Series("", {1, 2, 3, 4, 5}, {1, 0, -1, 10, 100});
  options.log_y = true;
  const PlotFrame lf = ComputePlotFrame({logged}, options);
  EXPECT_GT(lf.y_min, 0.0);
  EXPECT_LT(lf.y_min, 1.0);
  EXPECT_GT(lf.y_max, 100.0);
  EXPECT_NO_THROW(RenderPlot({logged}, options));

  // Only unusable points: "no data", no crash.
  PlotSeries none = Series("none", {kNan, 1}, {1, kInf});
  EXPECT_FALSE(ComputePlotFrame({none}, PlotOptions{}).has_data);
  EXPECT_NE(RenderPlotSvg({none}, PlotOptions{}).find("no data"), std::string::npos);
}

TEST(Plot, EmptySeriesListDrawsAxesAndNoData) {
  PlotOptions options;
  const PlotFrame f = ComputePlotFrame({}, options);
  EXPECT_FALSE(f.has_data);
  EXPECT_EQ(f.x_min, 0.0);
  EXPECT_EQ(f.x_max, 1.0);
  const Image image = RenderPlot({}, options);
  EXPECT_TRUE(IsDark(image, f.left - 1, (f.top + f.bottom) / 2));              // frame
  EXPECT_TRUE(AnyDark(image, f.left, f.bottom + 2, f.right, image.height()));  // tick labels
  // "no data" in the middle of the plot area (grey text).
  const int cx = (f.left + f.right) / 2;
  const int cy = (f.top + f.bottom) / 2;
  bool text = false;
  for (int y = cy - 10; y < cy + 10; ++y) {
    for (int x = cx - 40; x < cx + 40; ++x) text |= Luminance(image, x, y) < 0.7f;
  }
  EXPECT_TRUE(text);
  EXPECT_NE(RenderPlotSvg({}, options).find(">no data<"), std::string::npos);
  // With data there is no such text.
  EXPECT_EQ(RenderPlotSvg({Diagonal()}, options).find("no data"), std::string::npos);
}

TEST(Plot, AllEqualValuesGetAPaddedRange) {
  const PlotFrame f = ComputePlotFrame({Series("", {2, 2, 2}, {5, 5, 5})}, PlotOptions{});
  EXPECT_LT(f.x_min, 2.0);
  EXPECT_GT(f.x_max, 2.0);
  EXPECT_LT(f.y_min, 5.0);
  EXPECT_GT(f.y_max, 5.0);
  EXPECT_GE(f.y_ticks.size(), 2u);
  const PlotFrame zero = ComputePlotFrame({Series("", {0, 0}, {0, 0})}, PlotOptions{});
  EXPECT_LT(zero.y_min, 0.0);
  EXPECT_GT(zero.y_max, 0.0);
  PlotOptions log;
  log.log_y = true;
  const PlotFrame logged = ComputePlotFrame({Series("", {1, 2}, {10, 10})}, log);
  EXPECT_GT(logged.y_min, 0.0);
  EXPECT_LT(logged.y_min, 10.0);
  EXPECT_GT(logged.y_max, 10.0);
  EXPECT_NO_THROW(RenderPlot({Series("", {2, 2, 2}, {5, 5, 5})}, log));
}

TEST(Plot, FixedRangesAreKeptAndClipTheData) {
  PlotOptions options;
  options.x_range = AxisRange{0.0, 10.0};
  options.y_range = AxisRange{0.0, 1.0};
  options.grid = false;
  const PlotSeries s = Series("", {-100, 100}, {0.55, 0.55});
  const PlotFrame f = ComputePlotFrame({s}, options);
  EXPECT_EQ(f.x_min, 0.0);
  EXPECT_EQ(f.x_max, 10.0);
  EXPECT_EQ(f.y_max, 1.0);
  const Image image = RenderPlot({s}, options);
  const int y = static_cast<int>(f.PixelY(0.55));
  EXPECT_TRUE(IsBlue(image, (f.left + f.right) / 2, y));
  EXPECT_TRUE(IsBlue(image, f.left, y));
  EXPECT_TRUE(IsBlue(image, f.right - 1, y));
  EXPECT_FALSE(AnyBlue(image, 0, 0, f.left, image.height()));
  EXPECT_FALSE(AnyBlue(image, f.right, 0, image.width(), image.height()));
}

TEST(Plot, ExtremeValuesDoNotBreakTheChart) {
  const PlotSeries s = Series("big", {-1e308, 0, 1e308}, {1e-300, 1e300, -1e300});
  const Image image = RenderPlot({s}, PlotOptions{});
  for (float v : image.values()) ASSERT_TRUE(std::isfinite(v));
  EXPECT_TRUE(WellFormedXml(RenderPlotSvg({s}, PlotOptions{})));
  PlotOptions log;
  log.log_x = true;
  log.log_y = true;
  EXPECT_NO_THROW(RenderPlot({Series("", {1e-300, 1e300}, {1e-300, 1e300})}, log));
}

TEST(Plot, ScatterWithPointLabelsOnALogTimeAxis) {
  PlotSeries s = Series("methods", {0.5, 3.0, 40.0, 200.0}, {28.0, 31.0, 33.0, 33.5});
  s.style = PlotSeries::kMarkers;
  PlotOptions options;
  options.log_x = true;
  options.legend = false;
  options.grid = false;
  options.x_label = "time per frame (s)";
  options.y_label = "PSNR (dB)";
  const PlotFrame f = ComputePlotFrame({s}, options);
  const Image plain = RenderPlot({s}, options);
  s.point_labels = {"ours", "4DGS", "", "HDR-NeRF"};
  const Image labelled = RenderPlot({s}, options);
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    const int px = static_cast<int>(f.PixelX(s.x[i]));
    const int py = static_cast<int>(f.PixelY(s.y[i]));
    EXPECT_TRUE(IsBlue(plain, px, py)) << "marker " << i;
  }
  // The first label ("ours") is drawn right of its marker; the empty one draws nothing.
  const int px = static_cast<int>(f.PixelX(0.5));
  const int py = static_cast<int>(f.PixelY(28.0));
  const int th = TextHeight(options.font_scale);
  EXPECT_FALSE(AnyDark(plain, px + 6, py - 2 * th, px + 80, py + th));
  EXPECT_TRUE(AnyDark(labelled, px + 6, py - 2 * th, px + 80, py + th));
  const int qx = static_cast<int>(f.PixelX(40.0));
  const int qy = static_cast<int>(f.PixelY(33.0));
  EXPECT_FALSE(AnyDark(labelled, qx + 6, qy - 2 * th, qx + 40, qy + th));
  const std::string svg = RenderPlotSvg({s}, options);
  EXPECT_NE(svg.find(">HDR-NeRF<"), std::string::npos);
  EXPECT_TRUE(WellFormedXml(svg));
}

TEST(Plot, LegendNamesSeriesAndAvoidsTheData) {
  PlotSeries a = Diagonal();
  a.name = "red channel";
  PlotSeries b = Diagonal();
  b.name = "green channel";
  for (double& y : b.y) y = 0.9 * y;
  b.color = PaletteColor(2);
  PlotOptions options;
  const std::string svg = RenderPlotSvg({a, b}, options);
  EXPECT_NE(svg.find(">red channel</text>"), std::string::npos);
  EXPECT_NE(svg.find(">green channel</text>"), std::string::npos);
  EXPECT_NE(svg.find("<title>red channel</title>"), std::string::npos);
  // The legend box (grey border) goes to a corner the rising lines leave empty: top-left or
  // bottom-right, not top-right where the default would put it.
  const PlotFrame f = ComputePlotFrame({a, b}, options);
  const std::size_t box = svg.find("stroke=\"#b3b3b3\"");
  ASSERT_NE(box, std::string::npos);
  const std::size_t rect = svg.rfind("<rect x=\"", box);
  const double x = std::stod(svg.substr(rect + 9));
  const double y = std::stod(svg.substr(svg.find("y=\"", rect) + 3));
  const bool top_left = x < (f.left + f.right) / 2.0 && y < (f.top + f.bottom) / 2.0;
  const bool bottom_right = x > (f.left + f.right) / 2.0 && y > (f.top + f.bottom) / 2.0;
  EXPECT_TRUE(top_left || bottom_right) << x << "," << y;
  // Turned off, or with only unnamed series, there is no legend.
  options.legend = false;
  EXPECT_EQ(RenderPlotSvg({a, b}, options).find(">red channel</text>"), std::string::npos);
  EXPECT_EQ(RenderPlotSvg({Diagonal()}, PlotOptions{}).find("#b3b3b3"), std::string::npos);
}

// Past the palette's ten colours a series keeps its colour's hue but changes shape: a square
// fills the corner of its box that a circle leaves empty, a diamond leaves even the circle's
// diagonal edge empty, and the SVG draws each with its own element.
TEST(Plot, MarkerShapesTellSeriesOfOneColourApart) {
  EXPECT_EQ(PaletteMarker(0), PlotSeries::kCircle);
  EXPECT_EQ(PaletteMarker(9), PlotSeries::kCircle);
  EXPECT_EQ(PaletteMarker(10), PlotSeries::kSquare);
  EXPECT_EQ(PaletteMarker(25), PlotSeries::kDiamond);
  EXPECT_EQ(PaletteMarker(30), PlotSeries::kCircle);
  EXPECT_EQ(PaletteColor(3), PaletteColor(13));
  PlotSeries s = Series("m", {1.0, 2.0}, {1.0, 2.0});
  s.style = PlotSeries::kMarkers;
  PlotOptions options;
  options.legend = false;
  options.grid = false;
  options.marker_radius = 8.0;
  const PlotFrame f = ComputePlotFrame({s}, options);
  const int px = static_cast<int>(f.PixelX(1.0)), py = static_cast<int>(f.PixelY(1.0));
  // Inside the square's corner (6, 6 from the centre; half side 7.1) but outside the circle
  // (distance 8.5) and the diamond (|dx| + |dy| = 12 > 10).
  std::map<PlotSeries::Marker, bool> corner;
  for (auto shape : {PlotSeries::kCircle, PlotSeries::kSquare, PlotSeries::kDiamond}) {
    s.marker = shape;
    const Image image = RenderPlot({s}, options);
    EXPECT_TRUE(IsBlue(image, px, py)) << shape;
    corner[shape] = IsBlue(image, px + 6, py + 6);
  }
  EXPECT_FALSE(corner[PlotSeries::kCircle]);
  EXPECT_TRUE(corner[PlotSeries::kSquare]);
  EXPECT_FALSE(corner[PlotSeries::kDiamond]);
  s.marker = PlotSeries::kSquare;
  std::string svg = RenderPlotSvg({s}, options);
  EXPECT_NE(svg.find("<rect x="), std::string::npos);
  EXPECT_TRUE(WellFormedXml(svg));
  s.marker = PlotSeries::kDiamond;
  svg = RenderPlotSvg({s}, options);
  EXPECT_NE(svg.find("<polygon"), std::string::npos);
  EXPECT_EQ(svg.find("<circle"), std::string::npos);
  EXPECT_TRUE(WellFormedXml(svg));
  s.marker = static_cast<PlotSeries::Marker>(7);
  EXPECT_THROW(RenderPlot({s}, options), Error);
}

TEST(Plot, SvgIsWellFormedEscapedAndNamesTheSeries) {
  PlotSeries a = Diagonal();
  a.name = "R & G <linear>";
  PlotSeries b = Series("ours \"fast\"", {0.1, 0.5}, {0.9, 0.2});
  b.style = PlotSeries::kLineMarkers;
  b.point_labels = {"a<b", "\xc2\xb5s"};
  PlotOptions options;
  options.title = "Tone curves & times";
  options.x_label = "log x";
  options.y_label = "LDR value";
  const std::string svg = RenderPlotSvg({a, b}, options);
  EXPECT_TRUE(WellFormedXml(svg));
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("R &amp; G &lt;linear&gt;"), std::string::npos);
  EXPECT_NE(svg.find("ours &quot;fast&quot;"), std::string::npos);
  EXPECT_NE(svg.find("Tone curves &amp; times"), std::string::npos);
  EXPECT_NE(svg.find("a&lt;b"), std::string::npos);
  EXPECT_NE(svg.find("&#x25A1;s"), std::string::npos);  // µ boxed, as in the PNG
  EXPECT_EQ(svg.find("R & G"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  EXPECT_NE(svg.find("<circle"), std::string::npos);
  EXPECT_NE(svg.find("rotate(-90)"), std::string::npos);  // the y label
  // The checker itself rejects broken documents.
  EXPECT_FALSE(WellFormedXml("<svg><g></svg>"));
  EXPECT_FALSE(WellFormedXml("<svg>R & G</svg>"));
}

TEST(Plot, GridTilesPanels) {
  std::vector<PlotPanel> panels;
  for (int i = 0; i < 3; ++i) {
    PlotOptions options;
    options.width = 300;
    options.height = 200;
    options.title = std::string(1, "RGB"[i]);
    PlotSeries s = Diagonal();
    s.color = PaletteColor(i);
    panels.push_back({{s}, options});
  }
  const Image grid = RenderPlotGrid(panels, 2);
  ASSERT_EQ(grid.width(), 600);
  ASSERT_EQ(grid.height(), 400);
  EXPECT_EQ(grid.encoding(), Encoding::kSrgb);
  for (int i = 0; i < 3; ++i) {
    const Image panel = RenderPlot(panels[i].first, panels[i].second);
    const int x0 = (i % 2) * 300;
    const int y0 = (i / 2) * 200;
    for (int y = 0; y < 200; y += 3) {
      for (int x = 0; x < 300; x += 3) {
        ASSERT_EQ(grid.at(x0 + x, y0 + y, 1), panel.at(x, y, 1)) << i << ": " << x << "," << y;
      }
    }
  }
  EXPECT_FALSE(AnyDark(grid, 300, 200, 600, 400));  // the empty fourth cell
  const std::string svg = RenderPlotGridSvg(panels, 2);
  EXPECT_TRUE(WellFormedXml(svg));
  EXPECT_NE(svg.find("id=\"p2-clip0\""), std::string::npos);  // ids unique per panel
  EXPECT_NE(svg.find("url(#p2-clip0)"), std::string::npos);
  // More columns than panels: one row.
  EXPECT_EQ(RenderPlotGrid(panels, 5).width(), 900);
}

TEST(Plot, WritesPngAndSvgByExtension) {
  TempDir dir;
  const std::vector<PlotSeries> series = {Diagonal()};
  PlotOptions options;
  options.width = 320;
  options.height = 240;
  WritePlot(dir / "sub/curve.png", series, options);
  const Image read = ReadImage(dir / "sub/curve.png");
  EXPECT_EQ(read.width(), 320);
  EXPECT_EQ(read.height(), 240);
  WritePlot(dir / "curve.svg", series, options);
  const std::string svg = testing::ReadTextFile(dir / "curve.svg");
  EXPECT_TRUE(WellFormedXml(svg));
  WritePlotGrid(dir / "grid.svg", {{series, options}, {series, options}}, 2);
  EXPECT_TRUE(WellFormedXml(testing::ReadTextFile(dir / "grid.svg")));
  const std::string error = ErrorOf([&] { WritePlot(dir / "curve.txt", series, options); });
  EXPECT_NE(error.find("curve.txt"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(dir / "curve.txt"));
}

TEST(Plot, InvalidOptionsAndSeriesNameTheProblem) {
  const std::vector<PlotSeries> series = {Diagonal()};
  auto error_with = [&](auto&& change) {
    PlotOptions options;
    change(options);
    const std::string png = ErrorOf([&] { RenderPlot(series, options); });
    EXPECT_EQ(ErrorOf([&] { RenderPlotSvg(series, options); }), png);
    return png;
  };
  auto contains = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) { o.width = 99; }), "width"));
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) { o.height = 20; }), "height"));
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) { o.font_scale = 0; }), "font_scale"));
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) { o.line_width = 0; }), "line_width"));
  EXPECT_TRUE(
      contains(error_with([](PlotOptions& o) { o.marker_radius = kNan; }), "marker_radius"));
  const std::string log_x = error_with([](PlotOptions& o) {
    o.log_x = true;
    o.x_range = AxisRange{0.0, 10.0};
  });
  EXPECT_TRUE(contains(log_x, "x_range") && contains(log_x, "log")) << log_x;
  const std::string log_y = error_with([](PlotOptions& o) {
    o.log_y = true;
    o.y_range = AxisRange{-1.0, 1.0};
  });
  EXPECT_TRUE(contains(log_y, "y_range") && contains(log_y, "log")) << log_y;
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) {
                         o.x_range = AxisRange{2.0, 2.0};
                       }),
                       "x_range"));
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) {
                         o.y_range = AxisRange{0.0, kInf};
                       }),
                       "y_range"));
  // Too small for the chosen font.
  EXPECT_TRUE(contains(error_with([](PlotOptions& o) {
                         o.width = 100;
                         o.font_scale = 8;
                       }),
                       "width"));
  // The defaults and the smallest size with a small font are fine.
  EXPECT_EQ(error_with([](PlotOptions&) {}), "");
  EXPECT_EQ(error_with([](PlotOptions& o) {
              o.width = 100;
              o.height = 100;
              o.font_scale = 1;
            }),
            "");

  PlotSeries bad = Series("bad one", {1, 2, 3}, {1, 2});
  std::string e = ErrorOf([&] { RenderPlot({bad}, PlotOptions{}); });
  EXPECT_TRUE(contains(e, "bad one") && contains(e, "3") && contains(e, "2")) << e;
  PlotSeries labels = Series("labelled", {1, 2}, {1, 2});
  labels.point_labels = {"only one"};
  EXPECT_TRUE(contains(ErrorOf([&] { RenderPlot({labels}, PlotOptions{}); }), "point_labels"));
  PlotSeries color = Series("", {1}, {1});
  color.color = {0.0f, 2.0f, 0.0f};
  EXPECT_TRUE(contains(ErrorOf([&] { RenderPlot({color}, PlotOptions{}); }), "color"));

  EXPECT_TRUE(contains(ErrorOf([&] { RenderPlotGrid({}, 2); }), "no panels"));
  EXPECT_TRUE(contains(ErrorOf([&] { RenderPlotGrid({{series, PlotOptions{}}}, 0); }), "columns"));
}

TEST(Plot, Colors) {
  for (int i = 0; i < 10; ++i) {
    for (int j = i + 1; j < 10; ++j) EXPECT_NE(PaletteColor(i), PaletteColor(j));
  }
  EXPECT_EQ(PaletteColor(10), PaletteColor(0));
  EXPECT_EQ(PaletteColor(-1), PaletteColor(9));
  // The ramp runs dark to light and stays in [0,1].
  auto lum = [](const std::array<float, 3>& c) { return c[0] + c[1] + c[2]; };
  EXPECT_LT(lum(SequentialColor(0.0)), lum(SequentialColor(1.0)));
  EXPECT_EQ(SequentialColor(-5.0), SequentialColor(0.0));
  EXPECT_EQ(SequentialColor(kNan), SequentialColor(0.0));
  EXPECT_EQ(SequentialColor(7.0), SequentialColor(1.0));
  for (double t = 0; t <= 1.0; t += 0.1) {
    for (float c : SequentialColor(t)) EXPECT_TRUE(c >= 0.0f && c <= 1.0f);
  }
}

}  // namespace
}  // namespace hdr4d
