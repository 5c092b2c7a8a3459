#include "core/radiometry/crf.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/image/image.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using hdr4d::testing::ErrorOf;

using ::testing::HasSubstr;
using testing::TempDir;
using testing::WriteTextFile;

// Exposures 0, 1e-12 .. 1e3 (log-spaced), 1e-9, and a fine linear grid over [0, 2].
std::vector<double> DenseGrid() {
  std::vector<double> xs = {0.0, 1e-9};
  for (int i = 0; i <= 1500; ++i) xs.push_back(std::pow(10.0, -12.0 + 15.0 * i / 1500));
  for (int i = 0; i <= 20000; ++i) xs.push_back(2.0 * i / 20000);
  std::sort(xs.begin(), xs.end());
  return xs;
}

// x_of_code for a 256-entry table sampled from a closed-form curve.
std::vector<double> CodesOf(const Crf& crf, int n = 256) {
  std::vector<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = crf.Inverse(static_cast<double>(i) / (n - 1));
  return x;
}

struct Model {
  std::string name;
  std::shared_ptr<Crf> crf;
  double inverse_rel_tol;  // |Inverse(Apply(x)) - x| / x on (0, saturation)
};

std::vector<Model> Models() {
  std::vector<Model> models = {
      {"linear", std::make_shared<LinearCrf>(), 1e-15},
      {"gamma2.2", std::make_shared<GammaCrf>(2.2), 1e-12},
      {"gamma0.45", std::make_shared<GammaCrf>(0.45), 1e-12},
      {"srgb", std::make_shared<SrgbCrf>(), 1e-12},
      {"filmic", std::make_shared<FilmicCrf>(), 1e-9},
      {"filmic3", std::make_shared<FilmicCrf>(3.0, 0.25), 1e-9},
      {"filmic0.7", std::make_shared<FilmicCrf>(0.7, 0.5), 1e-9},
      {"naka-rushton", std::make_shared<NakaRushtonCrf>(0.2, 2.2), 1e-9},
      {"naka-rushton-linear", std::make_shared<NakaRushtonCrf>(3.0, 1.0), 1e-9},
  };
  // Piecewise-linear forward and inverse are exact inverses up to rounding.
  models.push_back(
      {"table_gamma",
       std::shared_ptr<Crf>(TableCrf::FromCodes(CodesOf(GammaCrf(2.2)), "gamma-codes")), 1e-9});
  // Saturation at x = 4 (a recovered response's own units).
  models.push_back({"table_scaled",
                    std::make_shared<TableCrf>(std::vector<double>{0.5, 1.0, 2.0, 4.0},
                                               std::vector<double>{0.3, 0.5, 0.8, 1.0}, "scaled"),
                    1e-12});
  return models;
}

TEST(Crf, EveryModelIsMonotonicBoundedAndClipsAtSaturation) {
  for (const Model& model : Models()) {
    SCOPED_TRACE(model.name);
    const Crf& crf = *model.crf;
    EXPECT_EQ(crf.Apply(0.0), 0.0);
    EXPECT_EQ(crf.Apply(-0.5), 0.0);  // noise below zero is clamped, not an error
    EXPECT_TRUE(std::isnan(crf.Apply(std::numeric_limits<double>::quiet_NaN())));
    EXPECT_EQ(crf.Apply(std::numeric_limits<double>::infinity()), 1.0);
    EXPECT_GT(crf.Apply(1e-9), 0.0);
    const double sat = crf.Saturation();
    EXPECT_EQ(crf.Apply(sat), 1.0);
    EXPECT_LT(crf.Apply(sat * (1 - 1e-6)), 1.0);
    double previous = 0.0;
    for (double x : DenseGrid()) {
      const double y = crf.Apply(x * sat);
      ASSERT_GE(y, previous) << "x = " << x * sat;
      ASSERT_LE(y, 1.0);
      ASSERT_GE(y, 0.0);
      if (x >= 1.0) {
        ASSERT_EQ(y, 1.0) << "x = " << x * sat;
      }
      previous = y;
    }
  }
}

TEST(Crf, InverseUndoesApplyBelowSaturation) {
  for (const Model& model : Models()) {
    SCOPED_TRACE(model.name);
    const Crf& crf = *model.crf;
    ASSERT_TRUE(crf.Invertible());
    EXPECT_EQ(crf.Inverse(0.0), 0.0);
    EXPECT_EQ(crf.Inverse(1.0), crf.Saturation());
    EXPECT_EQ(crf.Inverse(1.5), crf.Saturation());
    EXPECT_EQ(crf.Inverse(-0.5), 0.0);
    double worst = 0;
    for (int i = 0; i <= 2000; ++i) {
      const double x = crf.Saturation() * std::pow(10.0, -9.0 + 9.0 * i / 2000) * (1 - 1e-6);
      const double back = crf.Inverse(crf.Apply(x));
      worst = std::max(worst, std::abs(back - x) / x);
    }
    EXPECT_LE(worst, model.inverse_rel_tol);
  }
}

TEST(Crf, DerivativeMatchesFiniteDifferences) {
  for (const Model& model : Models()) {
    SCOPED_TRACE(model.name);
    const Crf& crf = *model.crf;
    const double sat = crf.Saturation();
    for (double t : {1e-4, 3e-3, 0.01, 0.07, 0.18, 0.33, 0.61, 0.77, 0.93, 0.999}) {
      const double x = t * sat * 1.0000123;  // off the table nodes
      const double h = 1e-7 * x;
      const double fd = (crf.Apply(x + h) - crf.Apply(x - h)) / (2 * h);
      EXPECT_NEAR(crf.Derivative(x), fd, 1e-5 * std::abs(fd) + 1e-9) << "x = " << x;
    }
    EXPECT_EQ(crf.Derivative(2.0 * sat), 0.0);  // flat above saturation
    EXPECT_EQ(crf.Derivative(-1.0), crf.Derivative(0.0));
  }
  // The analytic limits at 0 and the left derivative at the clip point.
  EXPECT_EQ(GammaCrf(2.2).Derivative(0.0), std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(GammaCrf(2.2).Derivative(1.0), 1.0 / 2.2);
  EXPECT_EQ(GammaCrf(0.5).Derivative(0.0), 0.0);
  EXPECT_EQ(LinearCrf().Derivative(1.0), 1.0);
  EXPECT_DOUBLE_EQ(SrgbCrf().Derivative(0.0), 12.92);
  EXPECT_EQ(FilmicCrf(1.5, 0.18).Derivative(0.0), 0.0);
  EXPECT_EQ(NakaRushtonCrf(0.2, 2.2).Derivative(0.0), std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(NakaRushtonCrf(3.0, 1.0).Derivative(0.0), 4.0 / 3.0);
  // At white: (1 + k) k / (1 + k)^2 / gamma.
  EXPECT_DOUBLE_EQ(NakaRushtonCrf(0.2, 2.2).Derivative(1.0), 0.2 / 1.2 / 2.2);
}

// A model without an analytic derivative uses the base class's finite difference.
class CubicCrf final : public Crf {
 public:
  double Apply(double x) const override {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3 - 2 * x);
  }
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return false; }
  double Inverse(double) const override { Fail("no inverse"); }
  std::string Spec() const override { return "cubic"; }
  nlohmann::json ToJson() const override { return {}; }
};

TEST(Crf, DefaultDerivativeIsAFiniteDifference) {
  const CubicCrf crf;
  for (double x : {0.0, 1e-8, 0.1, 0.5, 0.9}) {
    EXPECT_NEAR(crf.Derivative(x), 6 * x * (1 - x), 1e-6) << x;
  }
}

TEST(Crf, GoldenValues) {
  EXPECT_DOUBLE_EQ(LinearCrf().Apply(0.3), 0.3);
  EXPECT_EQ(LinearCrf().Apply(1.7), 1.0);
  EXPECT_DOUBLE_EQ(GammaCrf(2.2).Apply(0.25), std::pow(0.25, 1 / 2.2));
  EXPECT_DOUBLE_EQ(GammaCrf(2.2).Inverse(0.5), std::pow(0.5, 2.2));
  EXPECT_NEAR(SrgbCrf().Apply(0.5), 0.7353569830524495, 1e-15);
  EXPECT_DOUBLE_EQ(SrgbCrf().Apply(0.001), 0.01292);
  // The filmic curve passes (1 + m^k) / 2 at its mid point.
  EXPECT_NEAR(FilmicCrf(1.5, 0.18).Apply(0.18), 0.5381837661840736, 1e-15);
  EXPECT_NEAR(FilmicCrf(1.5, 0.18).Apply(0.05), 0.13745799350330087, 1e-15);
  EXPECT_EQ(FilmicCrf(1.5, 0.18).Apply(1.0), 1.0);
  // y = 1.2 s / (s + 0.2), s = x^(1/2.2): at x = 0.01, s = 0.123284673944207.
  EXPECT_NEAR(NakaRushtonCrf(0.2, 2.2).Apply(0.01), 1.2 * 0.123284673944207 / 0.323284673944207,
              1e-14);
  // Concave in log exposure: code 1 of 8 bits sits near x = 1e-7, mid grey near x = 1.4e-2.
  EXPECT_NEAR(std::log10(NakaRushtonCrf(0.2, 2.2).Inverse(1.0 / 255)), -7.0, 0.2);
  EXPECT_NEAR(std::log10(NakaRushtonCrf(0.2, 2.2).Inverse(0.5)), -1.86, 0.01);
}

TEST(Crf, SrgbIsContinuousAndAgreesWithTheImageFunctions) {
  const SrgbCrf srgb;
  const double t = SrgbCrf::kLinearEnd;
  EXPECT_NEAR(12.92 * t, 1.055 * std::pow(t, 1 / 2.4) - 0.055, 1e-16);
  // Monotonic across both the exact junction and the standard's 0.0031308 breakpoint.
  double previous = 0;
  for (int i = -2000; i <= 2000; ++i) {
    const double x = 0.0031307 + i * 1e-10;
    ASSERT_GE(srgb.Apply(x), previous) << x;
    previous = srgb.Apply(x);
  }
  // The float functions carry a few float ulps of rounding (powf of a rounded base).
  for (int i = 0; i <= 4000; ++i) {
    const double x = i / 4000.0;
    ASSERT_NEAR(srgb.Apply(x), LinearToSrgb(static_cast<float>(x)), 4e-7) << x;
    ASSERT_NEAR(srgb.Inverse(x), SrgbToLinear(static_cast<float>(x)), 4e-7) << x;
  }
}

TEST(Crf, FilmicIsSShapedInLogExposure) {
  for (const auto& [k, m] :
       std::vector<std::pair<double, double>>{{1.5, 0.18}, {3.0, 0.25}, {0.7, 0.05}}) {
    const FilmicCrf crf(k, m);
    // dy/d(ln x) = x y'(x): rises, peaks at x = m, falls.
    double best = 0, best_x = 0;
    std::vector<double> slope;
    const int n = 4000;
    for (int i = 0; i <= n; ++i) {
      const double x = std::pow(10.0, -6.0 + 6.0 * i / n) * (1 - 1e-9);
      slope.push_back(x * crf.Derivative(x));
      if (slope.back() > best) best = slope.back(), best_x = x;
    }
    EXPECT_NEAR(std::log(best_x), std::log(m), 6.0 * std::log(10.0) / n * 1.01) << k;
    EXPECT_GT(best, 10 * slope.front());
    EXPECT_GT(best, 1.2 * slope.back());
  }
  // k > 1 also bends the toe in linear x (y' grows from 0), unlike a gamma curve.
  EXPECT_LT(FilmicCrf(1.5, 0.18).Derivative(1e-6), FilmicCrf(1.5, 0.18).Derivative(0.05));
}

TEST(Crf, TableInterpolationErrorIsWithinTheChordBound) {
  // 256 codes sampled from sRGB: a chord over [a, b] deviates from a C2 curve by at most
  // (b - a)^2 / 8 max|f''|; the segment over the junction of sRGB's pieces adds its kink,
  // at most (b - a) |slope jump| / 4.
  const SrgbCrf srgb;
  const auto table = TableCrf::FromCodes(CodesOf(srgb), "srgb-codes");
  const auto& xs = table->x();
  double worst_ratio = 0;
  for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
    const double a = xs[i], b = xs[i + 1], h = b - a;
    double bound = 1e-15;
    if (b > SrgbCrf::kLinearEnd) {
      const double lo = std::max(a, SrgbCrf::kLinearEnd);
      const double f2 = 1.055 / 2.4 * (1 - 1 / 2.4) * std::pow(lo, 1 / 2.4 - 2);  // |f''| at lo
      bound += h * h / 8 * f2;
      if (a < SrgbCrf::kLinearEnd) bound += h * (12.92 - srgb.Derivative(b)) / 4;
    }
    for (int s = 1; s < 20; ++s) {
      const double x = a + h * s / 20;
      const double err = std::abs(table->Apply(x) - srgb.Apply(x));
      ASSERT_LE(err, bound) << "segment " << i << " x = " << x;
      worst_ratio = std::max(worst_ratio, err / bound);
    }
  }
  EXPECT_GT(worst_ratio, 0.3);  // the bound is tight, so the check means something
  EXPECT_LT(table->Apply(0.5) - srgb.Apply(0.5), 0.0);  // chords lie below a concave curve
}

TEST(Crf, TableWithBlackLevelToeIsInvertibleAboveBlack) {
  // A recovered response whose code 0 sits at x = 0.01: (0, 0) is prepended, a flat toe.
  const auto crf = TableCrf::FromCodes({0.01, 0.2, 0.5, 1.0}, "toe");
  ASSERT_EQ(crf->x().size(), 5u);
  EXPECT_EQ(crf->x()[0], 0.0);
  EXPECT_EQ(crf->Apply(0.005), 0.0);
  EXPECT_TRUE(crf->Invertible());
  EXPECT_EQ(crf->Inverse(0.0), 0.0);
  EXPECT_DOUBLE_EQ(crf->Inverse(1.0 / 3), 0.2);
  EXPECT_DOUBLE_EQ(crf->Inverse(1.0 / 6), 0.105);
  EXPECT_EQ(crf->Derivative(0.005), 0.0);
  EXPECT_DOUBLE_EQ(crf->Derivative(0.2), (1.0 / 3) / 0.19);  // the left segment at a node
  EXPECT_DOUBLE_EQ(crf->Derivative(0.0), 0.0);
}

TEST(Crf, TableWithFlatMidSectionIsNotInvertible) {
  const TableCrf crf({0.0, 0.2, 0.4, 1.0}, {0.0, 0.5, 0.5, 1.0}, "flat");
  EXPECT_FALSE(crf.Invertible());
  EXPECT_EQ(crf.Apply(0.3), 0.5);
  EXPECT_THAT(ErrorOf([&] { crf.Inverse(0.7); }), HasSubstr("not invertible"));
  EXPECT_THAT(ErrorOf([&] { crf.Inverse(0.7); }), HasSubstr("flat"));
  // A flat top at y = 1 before the last node only moves the saturation point.
  const TableCrf top({0.0, 0.5, 2.0}, {0.0, 1.0, 1.0}, "top");
  EXPECT_TRUE(top.Invertible());
  EXPECT_EQ(top.Saturation(), 0.5);
  EXPECT_EQ(top.Apply(1.0), 1.0);
}

TEST(Crf, TableNodesAreValidated) {
  using V = std::vector<double>;
  const auto error = [](V x, V y) { return ErrorOf([&] { TableCrf(x, y, "nodes.json"); }); };
  EXPECT_THAT(error({0, 1}, {0}), HasSubstr("2 x values but 1 y values"));
  EXPECT_THAT(error({}, {}), HasSubstr("no nodes"));
  EXPECT_THAT(error({0, 0.5, 0.4, 1}, {0, 0.2, 0.3, 1}),
              HasSubstr("node 2 of 4: x = 0.4 does not increase"));
  EXPECT_THAT(error({0, 0.5, 0.6, 1}, {0, 0.4, 0.3, 1}),
              HasSubstr("node 2 of 4: y = 0.3 is below"));
  EXPECT_THAT(error({0, 1}, {0, 1.5}), HasSubstr("outside [0, 1]"));
  EXPECT_THAT(error({-1, 1}, {0, 1}), HasSubstr("negative"));
  EXPECT_THAT(error({0, 1}, {0.1, 1}), HasSubstr("at x = 0 must be 0"));
  EXPECT_THAT(error({0, 1}, {0, 0.9}), HasSubstr("must reach y = 1"));
  EXPECT_THAT(error({0, NAN}, {0, 1}), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([] { TableCrf::FromCodes({0.5}, "c"); }), HasSubstr("at least 2"));
}

TEST(Crf, TableCsvFormats) {
  TempDir dir;
  // Two columns with a header, comments, blank lines and CRLF line ends.
  WriteTextFile(dir / "xy.csv", "# measured\nx,y\r\n0.25, 0.5\r\n\n1.0,1.0\r\n");
  const auto xy = TableCrf::FromCsv((dir / "xy.csv").string());
  EXPECT_EQ(xy->x(), (std::vector<double>{0.0, 0.25, 1.0}));
  EXPECT_EQ(xy->y(), (std::vector<double>{0.0, 0.5, 1.0}));
  EXPECT_DOUBLE_EQ(xy->Apply(0.125), 0.25);
  // Whitespace-separated works too.
  WriteTextFile(dir / "ws.txt", "0 0\n0.5\t0.25\n2   1\n");
  EXPECT_EQ(TableCrf::FromCsv((dir / "ws.txt").string())->Saturation(), 2.0);
  // One column: x per code, 256 codes as Debevec / OpenCV inverse responses.
  std::string codes;
  for (int i = 0; i < 256; ++i) codes += fmt::format("{}\n", 0.02 * std::pow(1.0163, i));
  WriteTextFile(dir / "codes.csv", codes);
  const auto table = TableCrf::FromCsv((dir / "codes.csv").string());
  EXPECT_EQ(table->x().size(), 257u);  // (0, 0) prepended
  EXPECT_DOUBLE_EQ(table->Apply(0.02 * 1.0163), 1.0 / 255);
  EXPECT_DOUBLE_EQ(table->Saturation(), 0.02 * std::pow(1.0163, 255));
  EXPECT_TRUE(table->Invertible());
}

TEST(Crf, TableCsvErrorsNameFileAndLine) {
  TempDir dir;
  const auto error = [&](const std::string& text) {
    const std::string path = (dir / "t.csv").string();
    WriteTextFile(path, text);
    return ErrorOf([&] { TableCrf::FromCsv(path); });
  };
  const std::string f = (dir / "t.csv").string();
  EXPECT_THAT(error("x,y\n0,0\n0.5,0.6\n0.4,0.7\n1,1\n"),
              HasSubstr(f + ":4: x = 0.4 does not increase"));
  EXPECT_THAT(error("0,0\n0.5,0.6\n0.7,0.5\n1,1\n"),
              HasSubstr(f + ":3: y = 0.5 is below the previous y = 0.6"));
  EXPECT_THAT(error("0\n0.1\n0.3\n0.2\n1\n"), HasSubstr(f + ":4: x = 0.2 does not increase"));
  EXPECT_THAT(error("0,0\n0.5,abc\n1,1\n"), HasSubstr(f + ":2: '0.5,abc' is not a row of numbers"));
  EXPECT_THAT(error("0,0\n0.5,\n1,1\n"), HasSubstr(f + ":2:"));
  EXPECT_THAT(error("0,0\n0.5\n1,1\n"), HasSubstr(f + ":2: 1 columns, but line 1 has 2"));
  EXPECT_THAT(error("0,0,0\n1,1,1\n"), HasSubstr(f + ":1: 3 columns"));
  EXPECT_THAT(error("0,0\nnan,0.5\n1,1\n"), HasSubstr(f + ":2: non-finite"));
  EXPECT_THAT(error("0,0\n0.5,1.2\n1,1\n"), HasSubstr(f + ":2: y = 1.2 is outside [0, 1]"));
  EXPECT_THAT(error("0,0\n0.5,0.7\n"), HasSubstr(f + ":2: the table ends at y = 0.7"));
  EXPECT_THAT(error("0,0.2\n1,1\n"), HasSubstr(f + ":1: the response at x = 0 must be 0"));
  EXPECT_THAT(error("# nothing\n\n"), HasSubstr(f + ": no data rows"));
  EXPECT_THAT(error("0.5\n"), HasSubstr("at least 2"));
  EXPECT_THAT(ErrorOf([&] { TableCrf::FromCsv((dir / "missing.csv").string()); }),
              HasSubstr("missing.csv: cannot open CRF table"));
}

TEST(Crf, SpecRoundTrips) {
  TempDir dir;
  WriteTextFile(dir / "t.csv", "0.1,0.3\n0.4,0.7\n1.2,1\n");
  const std::string table_spec = "table:" + (dir / "t.csv").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"linear", "linear"},          {"gamma", "gamma:2.2"},
      {"gamma:1.8", "gamma:1.8"},    {"gamma:2.2000000000000006", "gamma:2.2000000000000006"},
      {"gamma:2.20", "gamma:2.2"},   {"srgb", "srgb"},
      {"filmic", "filmic:1.5,0.18"}, {"filmic:2,0.3", "filmic:2,0.3"},
      {"naka-rushton:0.2,2.2", "naka-rushton:0.2,2.2"},
      {table_spec, table_spec},
  };
  for (const auto& [spec, canonical] : cases) {
    SCOPED_TRACE(spec);
    const auto crf = ParseCrf(spec);
    EXPECT_EQ(crf->Spec(), canonical);
    const auto again = ParseCrf(crf->Spec());
    const auto from_json = CrfFromJson(nlohmann::json::parse(crf->ToJson().dump()));
    EXPECT_EQ(again->Spec(), canonical);
    EXPECT_EQ(from_json->Spec(), canonical);
    for (double x : DenseGrid()) {
      ASSERT_EQ(again->Apply(x), crf->Apply(x)) << x;
      ASSERT_EQ(from_json->Apply(x), crf->Apply(x)) << x;
    }
  }
  EXPECT_EQ(ParseCrf("gamma:1.8")->Apply(0.5), std::pow(0.5, 1 / 1.8));
  EXPECT_EQ(dynamic_cast<FilmicCrf&>(*ParseCrf("filmic:2,0.3")).mid(), 0.3);
  // The JSON of a table embeds its nodes: it does not need the file any more.
  const nlohmann::json json = ParseCrf(table_spec)->ToJson();
  std::filesystem::remove(dir / "t.csv");
  EXPECT_DOUBLE_EQ(CrfFromJson(json)->Apply(0.25), 0.5);
  EXPECT_THAT(ErrorOf([&] { ParseCrf(table_spec); }), HasSubstr("cannot open"));
  // Parameters may be left out of hand-written JSON.
  EXPECT_EQ(CrfFromJson({{"model", "gamma"}})->Spec(), "gamma:2.2");
  EXPECT_EQ(CrfFromJson({{"model", "filmic"}, {"mid", 0.25}})->Spec(), "filmic:1.5,0.25");
}

TEST(Crf, BadSpecsGiveClearErrors) {
  const auto error = [](const std::string& spec) { return ErrorOf([&] { ParseCrf(spec); }); };
  EXPECT_THAT(
      error("gamma:-1"),
      HasSubstr("CRF spec 'gamma:-1': gamma CRF: gamma must be a finite number > 0, got -1"));
  EXPECT_THAT(error("gamma:0"), HasSubstr("> 0, got 0"));
  EXPECT_THAT(error("gamma:nan"), HasSubstr("> 0, got nan"));
  EXPECT_THAT(error("gamma:inf"), HasSubstr("> 0, got inf"));
  EXPECT_THAT(error("gamma:abc"), HasSubstr("CRF spec 'gamma:abc': gamma 'abc' is not a number"));
  EXPECT_THAT(error("gamma:"), HasSubstr("gamma '' is not a number"));
  EXPECT_THAT(error("gamma:2.2x"), HasSubstr("'2.2x' is not a number"));
  EXPECT_THAT(error("unknown"),
              HasSubstr("CRF spec 'unknown': unknown model 'unknown'; expected linear"));
  EXPECT_THAT(error(""), HasSubstr("unknown model ''"));
  EXPECT_THAT(error("Gamma:2"), HasSubstr("unknown model 'Gamma'"));
  EXPECT_THAT(error("linear:1"), HasSubstr("'linear' takes no parameters"));
  EXPECT_THAT(error("srgb:2"), HasSubstr("'srgb' takes no parameters"));
  EXPECT_THAT(error("filmic:2"), HasSubstr("filmic takes two parameters"));
  EXPECT_THAT(error("filmic:0,0.2"), HasSubstr("contrast must be a finite number > 0, got 0"));
  EXPECT_THAT(error("filmic:2,-0.1"), HasSubstr("mid must be a finite number > 0, got -0.1"));
  EXPECT_THAT(error("filmic:2,x"), HasSubstr("mid 'x' is not a number"));
  EXPECT_THAT(error("filmic:400,1e-3"), HasSubstr("is not a positive finite number"));
  EXPECT_THAT(error("naka-rushton"), HasSubstr("naka-rushton takes two parameters"));
  EXPECT_THAT(error("naka-rushton:0.2"), HasSubstr("naka-rushton takes two parameters"));
  EXPECT_THAT(error("naka-rushton:0,2.2"), HasSubstr("half-saturation k must be"));
  EXPECT_THAT(error("naka-rushton:0.2,-1"), HasSubstr("gamma must be a finite number > 0"));
  EXPECT_THAT(error("table:"), HasSubstr("table needs a file"));
  EXPECT_THAT(error("table:/no/such/crf.csv"),
              HasSubstr("CRF spec 'table:/no/such/crf.csv': /no/such/crf.csv: cannot open"));
}

TEST(Crf, BadJsonGivesClearErrors) {
  using nlohmann::json;
  const auto error = [](const json& j) { return ErrorOf([&] { CrfFromJson(j); }); };
  EXPECT_THAT(error(json::array()), HasSubstr("expected an object"));
  EXPECT_THAT(error({{"gamma", 2}}), HasSubstr("missing string \"model\""));
  EXPECT_THAT(error({{"model", "cubic"}}), HasSubstr("unknown model 'cubic'"));
  EXPECT_THAT(error({{"model", "gamma"}, {"gamma", "2"}}), HasSubstr("\"gamma\" must be a number"));
  EXPECT_THAT(error({{"model", "gamma"}, {"gamma", -2}}),
              HasSubstr("CRF JSON: gamma CRF: gamma must be"));
  EXPECT_THAT(error({{"model", "table"}, {"x", {0, 1}}}), HasSubstr("both \"x\" and \"y\""));
  EXPECT_THAT(error({{"model", "table"}, {"x", {0, 1}}, {"y", {0, "a"}}}),
              HasSubstr("\"y\"[1] must be a number"));
  EXPECT_THAT(error({{"model", "table"}, {"x", 1}, {"y", {0, 1}}}),
              HasSubstr("\"x\" must be an array"));
  EXPECT_THAT(error({{"model", "table"}, {"x", {0, 1, 0.5}}, {"y", {0, 0.5, 1}}}),
              HasSubstr("CRF table (inline): node 2 of 3: x = 0.5 does not increase"));
  EXPECT_THAT(error({{"model", "table"}}), HasSubstr("needs \"x\" and \"y\" nodes or a \"path\""));
  EXPECT_THAT(error({{"model", "table"}, {"path", 3}}), HasSubstr("\"path\" must be a string"));
}

TEST(Crf, ModelConstructorsRejectBadParameters) {
  EXPECT_THROW(GammaCrf(0.0), Error);
  EXPECT_THROW(GammaCrf(-2.2), Error);
  EXPECT_THROW(GammaCrf{std::numeric_limits<double>::infinity()}, Error);  // braces: an expression
  EXPECT_THROW(FilmicCrf(-1.0, 0.2), Error);
  EXPECT_THROW(FilmicCrf(1.0, 0.0), Error);
  EXPECT_THROW(FilmicCrf(1.0, std::nan("")), Error);
  EXPECT_NO_THROW(FilmicCrf(1.0, 2.0));  // mid above the clip: monotone, just no visible S
}

}  // namespace
}  // namespace hdr4d
