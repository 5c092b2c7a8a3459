#include "core/metrics/hdr_alignment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "core/metrics/flip.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using ::testing::HasSubstr;
using testing::ErrorOf;

// A grey-ish HDR image whose luminance spans 1e-3 .. 1e3 with a few colours.
Image WideRangeHdr(int w, int h, std::uint32_t seed) {
  Image image(w, h, 3, Encoding::kLinear);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0), tint(0.6, 1.4);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double level = std::pow(10.0, u(rng));
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = float(level * tint(rng));
    }
  }
  return image;
}

Image Power(const Image& gt, double k, double p) {
  Image out = gt;
  for (float& v : out.values()) v = float(k * std::pow(double(v), p));
  return out;
}

std::map<std::string, double> AsMap(const MetricList& list) {
  return {list.begin(), list.end()};
}

TEST(HdrAlignment, SlopeAndScaleOfAPowerOfTheTruth) {
  const Image gt = WideRangeHdr(40, 30, 1);
  // Luminance of a power of the colours is not exactly the power of the luminance; with equal
  // channels it is.
  Image grey(40, 30, 3, Encoding::kLinear);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x)
      for (int c = 0; c < 3; ++c) grey.at(x, y, c) = gt.at(x, y, 0);
  for (double p : {1.0, 0.25, 0.84, 1.3}) {
    SCOPED_TRACE(p);
    const HdrAlignment a = AlignHdr(Power(grey, 7.0, p), grey, nullptr);
    EXPECT_NEAR(a.slope, p, 1e-5);
    EXPECT_NEAR(a.corr, 1.0, 1e-9);
    EXPECT_EQ(a.pixels, 1200u);
    if (p == 1.0) {
      EXPECT_NEAR(a.scale, 1.0 / 7.0, 1e-6);
    }
  }
}

TEST(HdrAlignment, AlignedMetricsIgnoreTheGlobalScaleButNotTheShape) {
  const Image gt = WideRangeHdr(48, 48, 2);
  const auto proportional = AsMap(AlignedHdrMetrics(Power(gt, 1e-3, 1.0), gt, nullptr));
  EXPECT_GT(proportional.at("mu_psnr_aligned"), 90.0);
  EXPECT_GT(proportional.at("pu21_psnr_aligned"), 90.0);
  EXPECT_NEAR(proportional.at("mu_ssim_aligned"), 1.0, 1e-6);
  EXPECT_NEAR(proportional.at("hdr_align_scale"), 1e3, 1e-2);
  EXPECT_EQ(proportional.at("hdr_measured_fraction"), 1.0);
  const auto compressed = AsMap(AlignedHdrMetrics(Power(gt, 1.0, 0.25), gt, nullptr));
  EXPECT_LT(compressed.at("mu_psnr_aligned"), 25.0);
  EXPECT_LT(compressed.at("pu21_psnr_aligned"), 25.0);
  EXPECT_NEAR(compressed.at("hdr_log_slope"), 0.25, 0.02);
  EXPECT_GT(compressed.at("hdr_log_corr"), 0.98);
  EXPECT_NEAR(compressed.at("hdr_log_contrast"), 0.25, 0.02);
}

// HDR-FLIP is not scale-free: a prediction right but for one factor (a model supervised on each
// image over its own maximum) reads as badly wrong in raw HDR-FLIP. The aligned one sees the
// right image, and still sees a wrong shape.
TEST(HdrAlignment, AlignedHdrFlipIgnoresTheGlobalScaleButNotTheShape) {
  const Image gt = WideRangeHdr(48, 48, 2);
  const Image scaled = Power(gt, 1.0 / 37, 1.0);
  EXPECT_EQ(AsMap(AlignedHdrMetrics(scaled, gt, nullptr)).count("hdr_flip_aligned"), 0u);  // only when asked
  const auto proportional = AsMap(AlignedHdrMetrics(scaled, gt, nullptr, /*with_flip=*/true));
  EXPECT_GT(HdrFlip(scaled, gt), 0.3);
  EXPECT_LT(proportional.at("hdr_flip_aligned"), 1e-3);
  const auto compressed = AsMap(AlignedHdrMetrics(Power(gt, 1.0, 0.5), gt, nullptr, true));
  EXPECT_GT(compressed.at("hdr_flip_aligned"), 0.1);
}

// A held-out render misplaces pixels (geometry error, blur): the slope drops with the
// correlation, the ratio of log spreads does not. Here a power-law HDR with a quarter of its
// pixels swapped among themselves: the spread of log Y_pred is exactly that of the power law.
TEST(HdrAlignment, TheContrastRatioIgnoresMisplacedPixels) {
  const Image gt = WideRangeHdr(48, 48, 2);
  for (double p : {1.0, 0.6}) {
    SCOPED_TRACE(p);
    Image pred = Power(gt, 5.0, p);
    const HdrAlignment exact = AlignHdr(pred, gt, nullptr);
    EXPECT_NEAR(exact.contrast, p, 1e-5);
    // Reverse the order of every fourth row: the same values in wrong places.
    for (int y = 0; y < pred.height(); y += 4)
      for (int x = 0; x < pred.width() / 2; ++x)
        for (int c = 0; c < pred.channels(); ++c)
          std::swap(pred.at(x, y, c), pred.at(pred.width() - 1 - x, y, c));
    const HdrAlignment moved = AlignHdr(pred, gt, nullptr);
    EXPECT_LT(moved.corr, 0.97);
    EXPECT_LT(moved.slope, p * 0.97);
    EXPECT_NEAR(moved.slope, moved.corr * moved.contrast, 1e-9);
    EXPECT_NEAR(moved.contrast, p, 1e-5);
  }
}

// The case the metrics exist for: a lamp clipped in every bracket, whose brightness the
// prediction gets wrong by 100x, while everything else is right up to one factor.
TEST(HdrAlignment, ASaturatedLampCannotFoolTheAlignedMetrics) {
  const int w = 64, h = 64;
  Image gt(w, h, 3, Encoding::kLinear);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) gt.at(x, y, c) = float(0.01 + 0.5 * (x + y) / (w + h));
  std::vector<std::uint8_t> measured(std::size_t(w) * h, 1);
  for (int y = 30; y < 34; ++y) {
    for (int x = 30; x < 34; ++x) {
      for (int c = 0; c < 3; ++c) gt.at(x, y, c) = 5000.0f;
      measured[std::size_t(y) * w + x] = 0;
    }
  }
  Image pred = Power(gt, 3.0, 1.0);
  for (int y = 30; y < 34; ++y)
    for (int x = 30; x < 34; ++x)
      for (int c = 0; c < 3; ++c) pred.at(x, y, c) = 150.0f;  // 100x too dim after alignment
  const auto m = AsMap(AlignedHdrMetrics(pred, gt, &measured));
  const auto own = AsMap(HdrMetrics(pred, gt));
  EXPECT_NEAR(m.at("hdr_align_scale"), 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(m.at("hdr_log_slope"), 1.0, 1e-6);
  EXPECT_NEAR(m.at("hdr_measured_fraction"), 1.0 - 16.0 / (w * h), 1e-12);
  // The own-maximum protocol divides by the lamp's guessed brightness: everything else is 100x
  // too bright relative to it.
  EXPECT_LT(own.at("mu_psnr"), 15.0);
  EXPECT_GT(m.at("mu_psnr_aligned"), own.at("mu_psnr") + 10.0);
}

TEST(HdrAlignment, MeasurablePixelsAreUnclippedAndLitInSomeBracket) {
  // Pixel 0: clipped in both brackets. 1: black in both. 2: clipped in one, fine in the other.
  // 3: one channel clipped, another black in the only bracket that is not all black.
  Image short_exposure(4, 1, 3, Encoding::kSrgb), long_exposure(4, 1, 3, Encoding::kSrgb);
  const float v[2][4][3] = {{{1, 1, 1}, {0, 0, 0}, {0.2f, 0.3f, 0.1f}, {1, 0, 0}},
                            {{1, 1, 1}, {0, 0, 0}, {1, 1, 1}, {0, 0, 0}}};
  for (int x = 0; x < 4; ++x) {
    for (int c = 0; c < 3; ++c) {
      short_exposure.at(x, 0, c) = v[0][x][c];
      long_exposure.at(x, 0, c) = v[1][x][c];
    }
  }
  EXPECT_EQ(MeasurableInBrackets({short_exposure, long_exposure}),
            (std::vector<std::uint8_t>{0, 0, 1, 0}));
  // 254/255 is measured, 255/255 is not.
  Image almost(1, 1, 3, Encoding::kSrgb);
  for (int c = 0; c < 3; ++c) almost.at(0, 0, c) = 254.0f / 255.0f;
  EXPECT_EQ(MeasurableInBrackets({almost}), (std::vector<std::uint8_t>{1}));
}

TEST(HdrAlignment, NoMeasuredPixelGivesNoDiagnosticsAndUnitScale) {
  const Image gt = WideRangeHdr(8, 8, 3);
  const std::vector<std::uint8_t> none(64, 0);
  const HdrAlignment a = AlignHdr(gt, gt, &none);
  EXPECT_EQ(a.pixels, 0u);
  EXPECT_EQ(a.scale, 1.0);
  EXPECT_TRUE(std::isnan(a.slope));
  EXPECT_TRUE(std::isnan(a.corr));
  // A black prediction counts every pixel, all at the hole floor: no factor, slope 0, no
  // correlation; a constant one has no correlation either.
  Image black = gt;
  for (float& x : black.values()) x = 0;
  const HdrAlignment b = AlignHdr(black, gt, nullptr);
  EXPECT_EQ(b.pixels, 64u);
  EXPECT_EQ(b.scale, 1.0);
  EXPECT_NEAR(b.slope, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(b.corr));
  Image flat = gt;
  for (float& x : flat.values()) x = 2;
  const HdrAlignment f = AlignHdr(flat, gt, nullptr);
  EXPECT_NEAR(f.slope, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(f.corr));
}

// A hole in the model (measured pixels it renders far too dark) is the same error whether the
// hole is exactly black (a fixed black backdrop) or a tiny positive value (a learned dark
// backdrop): both count, at 1000x below the darkest measured truth. Dropping the black pixels,
// as an earlier version did, scored the black hole as no error at all.
TEST(HdrAlignment, AHoleCountsTheSameBlackOrDark) {
  const Image gt = WideRangeHdr(48, 48, 7);
  const Image right = Power(gt, 4.0, 1.0);
  Image black = right, dark = right;
  for (int y = 10; y < 16; ++y) {
    for (int x = 20; x < 26; ++x) {
      for (int c = 0; c < 3; ++c) {
        black.at(x, y, c) = 0.0f;
        dark.at(x, y, c) = float(4.0 * 1e-9);  // ~1e-6 of the darkest truth, after the factor
      }
    }
  }
  const HdrAlignment exact = AlignHdr(right, gt, nullptr);
  const HdrAlignment with_black = AlignHdr(black, gt, nullptr);
  const HdrAlignment with_dark = AlignHdr(dark, gt, nullptr);
  EXPECT_EQ(with_black.pixels, exact.pixels);
  EXPECT_EQ(with_dark.pixels, exact.pixels);
  EXPECT_NEAR(exact.corr, 1.0, 1e-9);
  EXPECT_LT(with_black.corr, 0.97);
  EXPECT_NEAR(with_black.corr, with_dark.corr, 1e-12);
  EXPECT_NEAR(with_black.slope, with_dark.slope, 1e-12);
  // The factor comes from the pixels both render: the hole does not move it.
  EXPECT_NEAR(with_black.scale, 0.25, 1e-6);
  // A prediction a little darker than the truth, but above its darkest value, is kept as it is.
  Image dim = right;
  dim.at(3, 3, 0) *= 0.5f;
  dim.at(3, 3, 1) *= 0.5f;
  dim.at(3, 3, 2) *= 0.5f;
  EXPECT_LT(AlignHdr(dim, gt, nullptr).corr, 1.0 - 1e-9);
}

TEST(HdrAlignment, ExtremesStayFinite) {
  // Radiance up to 1e6 against a prediction 1e-30 of it: the factor is huge but finite, and
  // the aligned image does not overflow.
  const Image gt = Power(WideRangeHdr(16, 16, 4), 1e3, 1.0);
  const auto m = AsMap(AlignedHdrMetrics(Power(gt, 1e-30, 1.0), gt, nullptr));
  EXPECT_NEAR(std::log10(m.at("hdr_align_scale")), 30.0, 1e-4);
  EXPECT_GT(m.at("mu_psnr_aligned"), 60.0);
  EXPECT_NEAR(m.at("hdr_log_slope"), 1.0, 1e-4);
}

// LDR brackets of a linear HDR image through a gamma-2.2 response, clipped (display values).
Image Bracket(const Image& hdr, double exposure) {
  Image out(hdr.width(), hdr.height(), 3, Encoding::kSrgb);
  for (int y = 0; y < hdr.height(); ++y)
    for (int x = 0; x < hdr.width(); ++x)
      for (int c = 0; c < 3; ++c)
        out.at(x, y, c) = float(std::min(1.0, std::pow(hdr.at(x, y, c) * exposure, 1 / 2.2)));
  return out;
}

TEST(HdrAlignment, ReproducedPixelsAreMeasuredBrightEnoughAndCloseInSomeBracket) {
  // Truth 0.4 grey: the tolerance is kLdrFitRelative x 0.4. Pixel 0: off by just under it
  // (kept). 1: off by just over it. 2: clipped in the truth, so not measured, whatever the
  // render. 3: off in one bracket, right in the other. 4: a NaN render. 5: right but too dim
  // (just under kLdrFitLevel) in its only measured bracket. 6: a red pixel whose other channels
  // are black: the tolerance follows its brightest channel.
  constexpr int n = 7;
  Image gt_a(n, 1, 3, Encoding::kSrgb), gt_b(n, 1, 3, Encoding::kSrgb);
  for (int x = 0; x < n; ++x)
    for (int c = 0; c < 3; ++c) gt_a.at(x, 0, c) = 0.4f, gt_b.at(x, 0, c) = 1.0f;
  Image pred_a = gt_a, pred_b = gt_b;
  const float tolerance = float(kLdrFitRelative) * 0.4f;
  pred_a.at(0, 0, 1) = 0.4f + tolerance * 0.99f;
  pred_a.at(1, 0, 2) = 0.4f - tolerance * 1.01f;
  gt_a.at(2, 0, 0) = pred_a.at(2, 0, 0) = 1.0f;
  pred_a.at(3, 0, 0) = 0.9f;
  for (int c = 0; c < 3; ++c) gt_b.at(3, 0, c) = pred_b.at(3, 0, c) = 0.2f;
  pred_a.at(4, 0, 0) = std::nanf("");
  for (int c = 0; c < 3; ++c) gt_a.at(5, 0, c) = pred_a.at(5, 0, c) = float(kLdrFitLevel) * 0.99f;
  gt_a.at(6, 0, 1) = gt_a.at(6, 0, 2) = 0.0f;
  pred_a.at(6, 0, 1) = tolerance * 0.99f;
  pred_a.at(6, 0, 2) = 0.0f;
  EXPECT_EQ(ReproducedInBrackets({gt_a, gt_b}, {pred_a, pred_b}),
            (std::vector<std::uint8_t>{1, 0, 0, 1, 0, 0, 1}));
}

// The shape where the LDR is right: misplaced pixels (LDR wrong too) drop out, a squeezed HDR
// behind a right LDR (what issue 12 found: the truth to the power 0.25 at 29 dB of LDR) does not.
TEST(HdrAlignment, TheLdrFitShapeDropsMisplacedPixelsButKeepsASqueeze) {
  const Image gt = WideRangeHdr(48, 48, 4);
  const std::vector<double> exposures = {1e-3, 0.1, 10.0};
  std::vector<Image> brackets;
  for (double e : exposures) brackets.push_back(Bracket(gt, e));
  const std::vector<std::uint8_t> measured = MeasurableInBrackets(brackets);

  // Right shape (3x the truth: its LDR is the truth's at exposures / 3), every fourth row
  // reversed: the same values in wrong places, and the renders show them there.
  Image moved = Power(gt, 3.0, 1.0);
  for (int y = 0; y < moved.height(); y += 4)
    for (int x = 0; x < moved.width() / 2; ++x)
      for (int c = 0; c < 3; ++c) std::swap(moved.at(x, y, c), moved.at(moved.width() - 1 - x, y, c));
  std::vector<Image> moved_renders;
  for (double e : exposures) moved_renders.push_back(Bracket(moved, e / 3.0));
  const auto all_moved = AsMap(AlignedHdrMetrics(moved, gt, &measured));
  const auto fit_moved = AsMap(
      LdrFitHdrShape(moved, gt, measured, ReproducedInBrackets(brackets, moved_renders)));
  EXPECT_LT(all_moved.at("hdr_log_slope"), 0.9);
  EXPECT_NEAR(fit_moved.at("hdr_log_slope_ldr_fit"), 1.0, 0.01);
  EXPECT_GT(fit_moved.at("hdr_log_corr_ldr_fit"), 0.99);
  const double moved_fraction = fit_moved.at("hdr_ldr_fit_fraction");

  // Squeezed: the truth to the power 0.25, with a tone curve that undoes it, so every rendered
  // bracket is the truth's own. The LDR cannot tell; the shape still says 0.25.
  const Image squeezed = Power(gt, 2.0, 0.25);
  const auto fit_squeezed =
      AsMap(LdrFitHdrShape(squeezed, gt, measured, ReproducedInBrackets(brackets, brackets)));
  EXPECT_NEAR(fit_squeezed.at("hdr_log_slope_ldr_fit"), 0.25, 0.01);
  // Every measured pixel bright enough in some bracket; the reversed rows (a quarter) are not.
  const double fraction = fit_squeezed.at("hdr_ldr_fit_fraction");
  EXPECT_GT(fraction, 0.9);
  EXPECT_NEAR(moved_fraction, 0.75 * fraction, 0.05);
}

// A split's shape pools the images within each: one image whose few measured pixels span a
// narrow range swings a mean of slopes, not the pooled slope; per-image scales drop out.
TEST(HdrAlignment, PooledShapeWeighsImagesByTheirSpread) {
  const Image wide = WideRangeHdr(32, 32, 7);
  const HdrAlignment a = AlignHdr(Power(wide, 4.0, 0.9), wide, nullptr);
  // A narrow image: truth within 1.01x, the prediction's noise spread at random against it.
  Image narrow(8, 1, 3, Encoding::kLinear), noisy(8, 1, 3, Encoding::kLinear);
  for (int x = 0; x < 8; ++x)
    for (int c = 0; c < 3; ++c) {
      narrow.at(x, 0, c) = 1.0f + 0.001f * float(x);
      noisy.at(x, 0, c) = 1.0f + 0.01f * float((x * 5) % 8);
    }
  const HdrAlignment b = AlignHdr(noisy, narrow, nullptr);
  EXPECT_GT(std::fabs(b.slope - 0.9), 1.0);  // the narrow image's own slope is far off
  const PooledShape pooled = PoolLogShape({a.sums, b.sums});
  EXPECT_NEAR(pooled.slope, 0.9, 0.01);
  EXPECT_NEAR(PoolLogShape({a.sums}).slope, a.slope, 1e-12);
  EXPECT_NEAR(PoolLogShape({a.sums}).corr, a.corr, 1e-12);
  EXPECT_TRUE(std::isnan(PoolLogShape({}).slope));
  // Written into a mean in place of the mean of slopes; removed when undefined.
  nlohmann::json mean = {{"hdr_log_slope_ldr_fit", 0.5}, {"psnr", 20.0}};
  SetPooledLdrFitShape({a.sums, b.sums}, &mean);
  EXPECT_NEAR(mean["hdr_log_slope_ldr_fit"].get<double>(), pooled.slope, 1e-12);
  EXPECT_NEAR(mean["hdr_log_corr_ldr_fit"].get<double>(), pooled.corr, 1e-12);
  SetPooledLdrFitShape({LogShapeSums{}}, &mean);
  EXPECT_FALSE(mean.contains("hdr_log_slope_ldr_fit"));
  EXPECT_EQ(mean["psnr"], 20.0);
}

TEST(HdrAlignment, BadInputsNameTheProblem) {
  const Image a = WideRangeHdr(8, 8, 5), b = WideRangeHdr(8, 9, 6);
  EXPECT_THAT(ErrorOf([&] { AlignHdr(a, b, nullptr); }), HasSubstr("differ in shape"));
  const std::vector<std::uint8_t> small(10, 1);
  EXPECT_THAT(ErrorOf([&] { AlignHdr(a, a, &small); }), HasSubstr("10 entries for 64 pixels"));
  Image nan = a;
  nan.at(3, 3, 1) = std::nanf("");
  EXPECT_THAT(ErrorOf([&] { AlignHdr(nan, a, nullptr); }), HasSubstr("prediction holds a non-finite"));
  EXPECT_THAT(ErrorOf([&] { MeasurableInBrackets({}); }), HasSubstr("no bracket images"));
  EXPECT_THAT(ErrorOf([&] { MeasurableInBrackets({a, b}); }), HasSubstr("differ in size"));
  const std::vector<std::uint8_t> all(64, 1);
  EXPECT_THAT(ErrorOf([&] { LdrFitHdrShape(a, a, small, all); }),
              HasSubstr("10 entries for 64 pixels"));
  EXPECT_THAT(ErrorOf([&] { ReproducedInBrackets({}, {}); }), HasSubstr("0 truth brackets"));
  EXPECT_THAT(ErrorOf([&] { ReproducedInBrackets({a}, {a, a}); }),
              HasSubstr("1 truth brackets and 2 rendered"));
  EXPECT_THAT(ErrorOf([&] { ReproducedInBrackets({a}, {b}); }), HasSubstr("differ in size"));
}

}  // namespace
}  // namespace hdr4d

namespace hdr4d {
namespace {
// Issue 51, case 17: a constant truth gave hdr_log_slope 5.72 and hdr_log_contrast 1e15 from
// the rounding of its mean; the answer is undefined.
TEST(HdrAlignment, ConstantTruthLeavesTheShapeUndefined) {
  for (const float level : {0.3f, 0.7f, 1.9f, 123.4f}) {
    for (const int size : {7, 29, 64}) {
      Image gt(size, size + 3, 3, Encoding::kLinear, level);
      Image pred = gt;
      for (std::size_t i = 0; i < pred.size(); ++i) pred.values()[i] = 0.1f + 0.01f * float(i % 97);
      const HdrAlignment a = AlignHdr(pred, gt, nullptr);
      EXPECT_TRUE(std::isnan(a.slope)) << level << " " << size << ": " << a.slope;
      EXPECT_TRUE(std::isnan(a.contrast)) << level << " " << size << ": " << a.contrast;
      EXPECT_TRUE(std::isnan(a.corr)) << level << " " << size << ": " << a.corr;
    }
  }
  EXPECT_NE(UndefinedMetricReason("hdr_log_slope").find("constant"), std::string::npos);
}
}  // namespace
}  // namespace hdr4d
