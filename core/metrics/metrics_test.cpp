#include "core/metrics/metrics.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using hdr4d::testing::ErrorOf;

using ::testing::HasSubstr;
using testing::RandomImage;

constexpr double kInf = std::numeric_limits<double>::infinity();

Image FromValues(int width, int height, int channels, const std::vector<float>& values) {
  Image image(width, height, channels);
  HDR4D_CHECK(values.size() == image.size());
  image.values() = values;
  return image;
}

// ---- An obviously-correct SSIM: the full 11x11 window at every pixel, zero outside. ----------

double ReferenceSsim(const std::vector<double>& a,
                     const std::vector<double>& b,
                     int width,
                     int height,
                     int channels,
                     double c1,
                     double c2) {
  double g[11];
  double gsum = 0.0;
  for (int k = 0; k < 11; ++k) {
    g[k] = std::exp(-(k - 5) * (k - 5) / (2.0 * 1.5 * 1.5));
    gsum += g[k];
  }
  for (double& v : g) v /= gsum;
  auto value = [&](const std::vector<double>& img, int x, int y, int c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return 0.0;
    return img[(static_cast<std::size_t>(y) * width + x) * channels + c];
  };
  double total = 0.0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        double ma = 0, mb = 0, eaa = 0, ebb = 0, eab = 0;
        for (int j = -5; j <= 5; ++j) {
          for (int i = -5; i <= 5; ++i) {
            const double w = g[j + 5] * g[i + 5];
            const double va = value(a, x + i, y + j, c);
            const double vb = value(b, x + i, y + j, c);
            ma += w * va;
            mb += w * vb;
            eaa += w * va * va;
            ebb += w * vb * vb;
            eab += w * va * vb;
          }
        }
        const double sa = eaa - ma * ma, sb = ebb - mb * mb, sab = eab - ma * mb;
        total +=
            ((2 * ma * mb + c1) * (2 * sab + c2)) / ((ma * ma + mb * mb + c1) * (sa + sb + c2));
      }
    }
  }
  return total / (static_cast<double>(width) * height * channels);
}

double ReferenceSsim(const Image& a, const Image& b) {
  const std::vector<double> va(a.values().begin(), a.values().end());
  const std::vector<double> vb(b.values().begin(), b.values().end());
  return ReferenceSsim(va, vb, a.width(), a.height(), a.channels(), kSsimC1, kSsimC2);
}

Image AddNoise(const Image& image, float sigma, unsigned seed) {
  Image out = image;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma);
  for (float& v : out.values()) v += noise(rng);
  return out;
}

// ---- PSNR ------------------------------------------------------------------------------------

TEST(PsnrTest, HandComputedWholeImage) {
  // MSE = (0.1^2 + 0.3^2) / 2 = 0.05 -> 10 log10(20) = 13.0103 dB.
  const Image pred = FromValues(2, 1, 1, {0.0f, 0.0f});
  const Image gt = FromValues(2, 1, 1, {0.1f, 0.3f});
  EXPECT_NEAR(MeanSquaredError(pred, gt), 0.05, 1e-8);
  EXPECT_NEAR(Psnr(pred, gt), 13.0103, 1e-4);
}

TEST(PsnrTest, ChannelMeanDiffersFromWholeImage) {
  // Channel 0 errs by 0.5 (MSE 0.25 -> 6.0206 dB), channel 1 by 0.25 (MSE 0.0625 -> 12.0412 dB).
  // Mean of the two: 9.0309 dB; whole image MSE 0.15625 -> 8.0618 dB.
  const Image pred(2, 1, 2, Encoding::kLinear, 0.0f);
  const Image gt = FromValues(2, 1, 2, {0.5f, 0.25f, 0.5f, 0.25f});
  EXPECT_NEAR(PsnrChannelMean(pred, gt), 9.030899869919436, 1e-9);
  EXPECT_NEAR(Psnr(pred, gt), 8.061799739838872, 1e-9);
}

TEST(PsnrTest, IdenticalImagesAreInfinite) {
  const Image a = RandomImage(9, 5, 3, 1);
  EXPECT_EQ(Psnr(a, a), kInf);
  EXPECT_EQ(PsnrChannelMean(a, a), kInf);
}

TEST(PsnrTest, ChannelMeanIsInfiniteWhenOneChannelIsIdentical) {
  const Image gt = FromValues(1, 1, 3, {0.2f, 0.4f, 0.6f});
  const Image pred = FromValues(1, 1, 3, {0.2f, 0.5f, 0.7f});
  EXPECT_EQ(PsnrChannelMean(pred, gt), kInf);
  EXPECT_TRUE(std::isfinite(Psnr(pred, gt)));
}

TEST(PsnrTest, RejectsBadInputs) {
  const Image a(4, 3, 3), b(4, 3, 1);
  const std::string shape = ErrorOf([&] { Psnr(a, b); });
  EXPECT_THAT(shape, HasSubstr("4x3x3"));
  EXPECT_THAT(shape, HasSubstr("4x3x1"));
  EXPECT_THAT(ErrorOf([&] { Psnr(Image(), Image()); }), HasSubstr("empty"));
  Image nan = a;
  nan.at(2, 1, 0) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THAT(ErrorOf([&] { Psnr(nan, a); }), HasSubstr("x=2, y=1"));
  EXPECT_THAT(ErrorOf([&] { PsnrChannelMean(a, nan); }), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([&] { PsnrChannelMean(a, b); }), HasSubstr("shape"));
}

// ---- SSIM ------------------------------------------------------------------------------------

TEST(SsimTest, MatchesDirectWindowOnRandomImages) {
  struct Case {
    int w, h, c;
  };
  for (const Case& s : {Case{13, 7, 3}, Case{5, 4, 1}, Case{23, 40, 2}, Case{1, 1, 3}}) {
    const Image a = RandomImage(s.w, s.h, s.c, 10 + s.w);
    const Image b = RandomImage(s.w, s.h, s.c, 20 + s.h);
    EXPECT_NEAR(Ssim(a, b), ReferenceSsim(a, b), 1e-10) << s.w << "x" << s.h << "x" << s.c;
    // Correlated images give SSIM far from 0, a stronger check of the variance terms.
    const Image c = AddNoise(a, 0.05f, 3);
    EXPECT_NEAR(Ssim(a, c), ReferenceSsim(a, c), 1e-10) << s.w << "x" << s.h << "x" << s.c;
  }
}

TEST(SsimTest, TallImageCrossesParallelBands) {
  // Taller than several 32-row bands, so band borders are exercised.
  const Image a = RandomImage(6, 101, 1, 5);
  const Image b = AddNoise(a, 0.1f, 6);
  EXPECT_NEAR(Ssim(a, b), ReferenceSsim(a, b), 1e-10);
}

TEST(SsimTest, MatchesDirectWindowOnConstantImages) {
  const Image a(12, 9, 3, Encoding::kLinear, 0.3f);
  const Image b(12, 9, 3, Encoding::kLinear, 0.6f);
  const double ssim = Ssim(a, b);
  EXPECT_NEAR(ssim, ReferenceSsim(a, b), 1e-10);
  // Zero padding makes border windows non-constant, so this is not the luminance term alone.
  EXPECT_LT(ssim, 0.9);
  EXPECT_GT(ssim, 0.0);
}

TEST(SsimTest, IdenticalImagesGiveExactlyOne) {
  const Image a = RandomImage(17, 11, 3, 7);
  EXPECT_NEAR(Ssim(a, a), 1.0, 1e-12);
  const Image map = SsimMap(a, a);
  for (float v : map.values()) ASSERT_NEAR(v, 1.0f, 1e-6f);
}

TEST(SsimTest, DecreasesWithNoiseAndIsSymmetric) {
  const Image a = RandomImage(32, 24, 3, 8);
  double previous = 1.0;
  for (float sigma : {0.01f, 0.05f, 0.2f, 0.5f}) {
    const Image noisy = AddNoise(a, sigma, 9);
    const double s = Ssim(a, noisy);
    EXPECT_LT(s, previous) << sigma;
    EXPECT_DOUBLE_EQ(s, Ssim(noisy, a)) << sigma;
    previous = s;
  }
}

TEST(SsimTest, MapMeanEqualsSsim) {
  const Image a = RandomImage(19, 14, 2, 11);
  const Image b = AddNoise(a, 0.1f, 12);
  const Image map = SsimMap(a, b);
  ASSERT_TRUE(map.SameShape(a));
  double sum = 0.0;
  for (float v : map.values()) sum += v;
  EXPECT_NEAR(sum / map.size(), Ssim(a, b), 1e-6);
}

TEST(SsimTest, ConstantsChangeTheResult) {
  const Image a = RandomImage(15, 15, 1, 13);
  const Image b = RandomImage(15, 15, 1, 14);
  const std::vector<double> va(a.values().begin(), a.values().end());
  const std::vector<double> vb(b.values().begin(), b.values().end());
  EXPECT_NEAR(Ssim(a, b, 0.1, 0.2), ReferenceSsim(va, vb, 15, 15, 1, 0.1, 0.2), 1e-10);
  EXPECT_GT(Ssim(a, b, 0.1, 0.2), Ssim(a, b));
}

TEST(SsimTest, SameResultAtAnyThreadCount) {
  const Image a = RandomImage(64, 150, 3, 15);
  const Image b = AddNoise(a, 0.1f, 16);
  const double parallel = Ssim(a, b);
  double serial = 0.0;
  {
    ThreadLimit one(1);
    serial = Ssim(a, b);
  }
  EXPECT_EQ(parallel, serial);
}

TEST(SsimTest, RejectsBadInputs) {
  const Image a(5, 5, 3), b(5, 6, 3);
  EXPECT_THAT(ErrorOf([&] { Ssim(a, b); }), HasSubstr("5x6x3"));
  EXPECT_THAT(ErrorOf([&] { SsimMap(a, b); }), HasSubstr("5x5x3"));
  Image inf = a;
  inf.at(0, 0, 2) = std::numeric_limits<float>::infinity();
  EXPECT_THAT(ErrorOf([&] { Ssim(a, inf); }), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([&] { Ssim(a, a, 0.0, 1.0); }), HasSubstr("constants"));
  EXPECT_THAT(ErrorOf([&] { SsimMap(a, a, 1.0, -1.0); }), HasSubstr("constants"));
}

// ---- mu-law ----------------------------------------------------------------------------------

TEST(MuLawTest, HandValues) {
  const Image x = FromValues(3, 1, 1, {0.0f, 1.0f, 0.5f});
  const Image t = MuLaw(x);
  EXPECT_EQ(t.values()[0], 0.0f);
  EXPECT_NEAR(t.values()[1], 1.0f, 1e-7);
  EXPECT_NEAR(t.values()[2], 0.9186432718796463, 1e-6);  // log(2501) / log(5001)
  EXPECT_NEAR(MuLaw(x, 1.0).values()[2], std::log(1.5) / std::log(2.0), 1e-6);
  EXPECT_THAT(ErrorOf([&] { MuLaw(x, 0.0); }), HasSubstr("mu"));
}

TEST(MuLawTest, OwnMaxIsScaleInvariantGtMaxIsNot) {
  const Image gt = RandomImage(20, 12, 3, 21, 0.01f, 2.0f);
  Image pred4 = gt, pred3 = gt;
  for (float& v : pred4.values()) v *= 4.0f;  // exact in float, so own-max is exactly identical
  for (float& v : pred3.values()) v *= 3.0f;  // rounded in float: identical up to float rounding
  EXPECT_EQ(MuPsnr(pred4, gt, HdrNormalisation::kOwnMax), kInf);
  EXPECT_GT(MuPsnr(pred3, gt, HdrNormalisation::kOwnMax), 100.0);
  EXPECT_NEAR(MuSsim(pred3, gt, HdrNormalisation::kOwnMax), 1.0, 1e-9);
  const double gt_max = MuPsnr(pred3, gt, HdrNormalisation::kGtMax);
  EXPECT_TRUE(std::isfinite(gt_max));
  EXPECT_LT(gt_max, 40.0);
  EXPECT_LT(MuSsim(pred3, gt, HdrNormalisation::kGtMax), 0.99);
  EXPECT_EQ(MuPsnr(gt, gt, HdrNormalisation::kGtMax), kInf);
}

TEST(MuLawTest, MuPsnrHandComputed) {
  // gt max 2; pred max 4. Own max: pred -> [0.25, 1], gt -> [0.5, 1].
  // Gt max: pred -> [0.5, 1 (clamped from 2)], gt -> [0.5, 1] -> identical.
  const Image gt = FromValues(2, 1, 1, {1.0f, 2.0f});
  const Image pred = FromValues(2, 1, 1, {1.0f, 4.0f});
  const double t25 = std::log1p(5000 * 0.25) / std::log1p(5000.0);
  const double t50 = std::log1p(5000 * 0.5) / std::log1p(5000.0);
  const double mse = (t25 - t50) * (t25 - t50) / 2;
  EXPECT_NEAR(MuPsnr(pred, gt), 10 * std::log10(1 / mse), 1e-9);
  EXPECT_EQ(MuPsnr(pred, gt, HdrNormalisation::kGtMax), kInf);
  EXPECT_STREQ(HdrNormalisationName(HdrNormalisation::kOwnMax), "own_max");
  EXPECT_STREQ(HdrNormalisationName(HdrNormalisation::kGtMax), "gt_max");
}

TEST(MuLawTest, MuSsimMatchesReferenceOnMuLawImages) {
  const Image gt = RandomImage(14, 9, 3, 22, 0.0f, 3.0f);
  const Image pred = RandomImage(14, 9, 3, 23, 0.0f, 5.0f);
  const double gm = gt.MaxValue(), pm = pred.MaxValue();
  std::vector<double> a, b;
  for (float v : pred.values())
    a.push_back(std::log1p(5000 * std::min(v / pm, 1.0)) / std::log1p(5000.0));
  for (float v : gt.values())
    b.push_back(std::log1p(5000 * std::min(v / gm, 1.0)) / std::log1p(5000.0));
  EXPECT_NEAR(MuSsim(pred, gt), ReferenceSsim(a, b, 14, 9, 3, kSsimC1, kSsimC2), 1e-10);
}

TEST(MuLawTest, RejectsImagesThatCannotBeNormalised) {
  const Image black(4, 4, 3, Encoding::kLinear, 0.0f);
  const Image some = RandomImage(4, 4, 3, 24, 0.1f, 1.0f);
  EXPECT_THAT(ErrorOf([&] { MuPsnr(some, black); }),
              HasSubstr("ground-truth HDR image has maximum 0"));
  EXPECT_THAT(ErrorOf([&] { MuSsim(some, black, HdrNormalisation::kGtMax); }),
              HasSubstr("all black"));
  // A black prediction has no maximum of its own: it is scored as black, low and finite.
  EXPECT_TRUE(std::isfinite(MuPsnr(black, some)));
  EXPECT_LT(MuPsnr(black, some), 10.0);
  // Gt-max normalisation never divides by the prediction's maximum: a black prediction is fine.
  EXPECT_TRUE(std::isfinite(MuPsnr(black, some, HdrNormalisation::kGtMax)));
  const Image negative(4, 4, 3, Encoding::kLinear, -1.0f);
  EXPECT_THAT(ErrorOf([&] { MuPsnr(some, negative); }), HasSubstr("maximum -1"));
  Image nan = some;
  nan.at(1, 1, 1) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THAT(ErrorOf([&] { MuPsnr(nan, some); }), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([&] { MuSsim(some, nan); }), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([&] { MuPsnr(some, Image(4, 5, 3)); }), HasSubstr("4x5x3"));
}

TEST(MuLawTest, IgnoresAlpha) {
  Image gt = RandomImage(6, 6, 4, 25, 0.1f, 2.0f);
  Image pred = gt;
  for (std::size_t i = 3; i < pred.size(); i += 4) pred.values()[i] = 7.0f;  // alpha only
  EXPECT_EQ(MuPsnr(pred, gt), kInf);
}

// ---- PU21 ------------------------------------------------------------------------------------

TEST(Pu21Test, GoldenValues) {
  EXPECT_NEAR(Pu21Encode(0.005), 5.5e-10, 1e-8);
  const std::pair<double, double> golden[] = {
      {0.01, 0.37223},  {0.1, 5.71707},   {1, 36.54391},     {10, 123.64748},   {80, 242.03600},
      {100, 256.38390}, {200, 302.77433}, {1000, 420.09692}, {4000, 527.49390}, {10000, 595.39392}};
  for (const auto& [y, v] : golden) EXPECT_NEAR(Pu21Encode(y), v, 1e-4) << y;
}

TEST(Pu21Test, DecodeInvertsEncode) {
  for (int i = 0; i <= 400; ++i) {
    const double y = 0.005 * std::pow(10000 / 0.005, i / 400.0);
    EXPECT_NEAR(Pu21Decode(Pu21Encode(y)), y, 1e-9 * y) << y;
  }
}

TEST(Pu21Test, ClampsOutsideTheRange) {
  EXPECT_EQ(Pu21Encode(0.001), Pu21Encode(0.005));
  EXPECT_EQ(Pu21Encode(0.0), Pu21Encode(0.005));
  EXPECT_EQ(Pu21Encode(-3.0), Pu21Encode(0.005));
  EXPECT_EQ(Pu21Encode(20000.0), Pu21Encode(10000.0));
  EXPECT_GT(Pu21Encode(9999.0), Pu21Encode(9000.0));
  EXPECT_NEAR(Pu21Decode(-10.0), 0.005, 1e-9);
  EXPECT_NEAR(Pu21Decode(2000.0), 10000.0, 1e-6);
}

TEST(Pu21Test, LuminanceWeights) {
  EXPECT_DOUBLE_EQ(Luminance(1, 0, 0), 0.212656);
  EXPECT_DOUBLE_EQ(Luminance(0, 1, 0), 0.715158);
  EXPECT_DOUBLE_EQ(Luminance(0, 0, 1), 0.072186);
}

TEST(Pu21Test, PsnrHandComputedOnLuminance) {
  // 1-channel: the value is the luminance. Gt max 1 -> scale 4000: gt = [4000, 2000] cd/m^2,
  // pred = [2000, 2000]; peak 256.
  const Image gt = FromValues(2, 1, 1, {1.0f, 0.5f});
  const Image pred = FromValues(2, 1, 1, {0.5f, 0.5f});
  EXPECT_DOUBLE_EQ(Pu21Scale(gt), 4000.0);
  const double d = Pu21Encode(2000) - 527.4939005367281;
  EXPECT_NEAR(Pu21Psnr(pred, gt), 10 * std::log10(256.0 * 256.0 / (d * d / 2)), 1e-6);
}

TEST(Pu21Test, ScaleUsesGroundTruthLuminance) {
  // Max luminance is the red pixel's 0.212656 * 2, not the max channel value of another pixel.
  const Image gt = FromValues(2, 1, 3, {2.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.5f});
  EXPECT_NEAR(Pu21Scale(gt), 4000.0 / (2 * 0.212656), 1e-9);
  EXPECT_THAT(ErrorOf([&] { Pu21Scale(Image(2, 2, 3)); }), HasSubstr("all black"));
  // Grey + alpha is grey: the alpha (here above the grey) is no luminance.
  EXPECT_NEAR(Pu21Scale(FromValues(2, 1, 2, {1.0f, 3.0f, 0.5f, 3.0f})), 4000.0, 1e-9);
}

TEST(Pu21Test, DependsOnAbsoluteLevelOnlyThroughGroundTruthMax) {
  const Image gt = RandomImage(16, 12, 3, 31, 0.0f, 4.0f);
  Image half = gt, quarter = gt;
  for (float& v : half.values()) v *= 0.5f;
  for (float& v : quarter.values()) v *= 0.25f;
  const double p_half = Pu21Psnr(half, gt);
  const double p_quarter = Pu21Psnr(quarter, gt);
  EXPECT_TRUE(std::isfinite(p_half));
  EXPECT_GT(p_half, p_quarter);  // twice the error in log luminance
  // Mu-law with own-max normalisation cannot tell these apart.
  EXPECT_EQ(MuPsnr(half, gt), kInf);
  EXPECT_EQ(MuPsnr(quarter, gt), kInf);
  // Scaling both images by the same power of two changes nothing (the scale is set by gt).
  Image gt2 = gt, half2 = half;
  for (float& v : gt2.values()) v *= 2.0f;
  for (float& v : half2.values()) v *= 2.0f;
  EXPECT_NEAR(Pu21Psnr(half2, gt2), p_half, 1e-9);
  EXPECT_NEAR(Pu21Ssim(half2, gt2), Pu21Ssim(half, gt), 1e-12);
  EXPECT_EQ(Pu21Psnr(gt, gt), kInf);
  EXPECT_NEAR(Pu21Ssim(gt, gt), 1.0, 1e-12);
}

TEST(Pu21Test, SsimMatchesReferenceOnEncodedLuminance) {
  const Image gt = RandomImage(13, 10, 3, 32, 0.0f, 2.0f);
  const Image pred = RandomImage(13, 10, 3, 33, 0.0f, 2.0f);
  const double scale = Pu21Scale(gt);
  auto encoded = [&](const Image& im) {
    std::vector<double> v;
    for (std::size_t p = 0; p < im.num_pixels(); ++p) {
      const float* px = im.data() + 3 * p;
      v.push_back(Pu21Encode(scale * (0.212656 * px[0] + 0.715158 * px[1] + 0.072186 * px[2])));
    }
    return v;
  };
  const double expected =
      ReferenceSsim(encoded(pred), encoded(gt), 13, 10, 1, 2.56 * 2.56, 7.68 * 7.68);
  EXPECT_NEAR(Pu21Ssim(pred, gt), expected, 1e-10);
}

TEST(Pu21Test, SsimSeesOnlyLuminancePsnrSeesColour) {
  const Image gt = RandomImage(12, 12, 3, 34, 0.2f, 1.0f);
  Image pred = gt;
  // Move colour along a direction of zero luminance.
  for (std::size_t p = 0; p < pred.num_pixels(); ++p) {
    pred.values()[3 * p + 0] += 0.05f * 0.072186f;
    pred.values()[3 * p + 2] -= 0.05f * 0.212656f;
  }
  EXPECT_NEAR(Pu21Ssim(pred, gt), 1.0, 1e-6);
  EXPECT_LT(Pu21Psnr(pred, gt), 80.0);
}

TEST(Pu21Test, RejectsBadInputs) {
  const Image black(3, 3, 3);
  const Image some = RandomImage(3, 3, 3, 35, 0.1f, 1.0f);
  EXPECT_THAT(ErrorOf([&] { Pu21Psnr(some, black); }), HasSubstr("maximum luminance 0"));
  EXPECT_THAT(ErrorOf([&] { Pu21Ssim(some, black); }), HasSubstr("all black"));
  EXPECT_TRUE(std::isfinite(Pu21Psnr(black, some)));  // a black prediction is just wrong
  Image inf = some;
  inf.at(0, 2, 0) = -std::numeric_limits<float>::infinity();
  EXPECT_THAT(ErrorOf([&] { Pu21Psnr(inf, some); }), HasSubstr("non-finite"));
  EXPECT_THAT(ErrorOf([&] { Pu21Ssim(some, Image(3, 3, 1)); }), HasSubstr("3x3x1"));
}

// ---- Bundles ---------------------------------------------------------------------------------

std::vector<std::string> Keys(const MetricList& list) {
  std::vector<std::string> keys;
  for (const auto& [k, v] : list) keys.push_back(k);
  return keys;
}

TEST(BundleTest, LdrKeysAndValues) {
  const Image gt = RandomImage(20, 10, 4, 41);  // RGBA: alpha is ignored
  Image pred = AddNoise(gt, 0.05f, 42);
  const MetricList m = LdrMetrics(pred, gt);
  EXPECT_THAT(Keys(m), ::testing::ElementsAre("psnr", "psnr_channel_mean", "ssim"));
  EXPECT_DOUBLE_EQ(m[0].second, Psnr(pred.Rgb(), gt.Rgb()));
  EXPECT_DOUBLE_EQ(m[1].second, PsnrChannelMean(pred.Rgb(), gt.Rgb()));
  EXPECT_DOUBLE_EQ(m[2].second, Ssim(pred.Rgb(), gt.Rgb()));
  EXPECT_NE(m[0].second, Psnr(pred, gt));  // the alpha noise would count otherwise
}

TEST(BundleTest, HdrKeysAndValues) {
  const Image gt = RandomImage(16, 16, 3, 43, 0.0f, 8.0f);
  Image pred = gt;
  for (float& v : pred.values()) v = v * 1.3f + 0.01f;
  const MetricList m = HdrMetrics(pred, gt);
  EXPECT_THAT(Keys(m), ::testing::ElementsAre("mu_psnr", "mu_ssim", "mu_psnr_gt_max",
                                              "mu_ssim_gt_max", "pu21_psnr", "pu21_ssim"));
  EXPECT_DOUBLE_EQ(m[0].second, MuPsnr(pred, gt));
  EXPECT_DOUBLE_EQ(m[1].second, MuSsim(pred, gt));
  EXPECT_DOUBLE_EQ(m[2].second, MuPsnr(pred, gt, HdrNormalisation::kGtMax));
  EXPECT_DOUBLE_EQ(m[3].second, MuSsim(pred, gt, HdrNormalisation::kGtMax));
  EXPECT_DOUBLE_EQ(m[4].second, Pu21Psnr(pred, gt));
  EXPECT_DOUBLE_EQ(m[5].second, Pu21Ssim(pred, gt));
  EXPECT_GT(m[0].second, m[2].second);  // own max forgives the 1.3x scale
}

TEST(BundleTest, RejectsBadInputs) {
  EXPECT_THAT(ErrorOf([] { LdrMetrics(Image(2, 2, 3), Image(2, 2, 4)); }), HasSubstr("2x2x4"));
  EXPECT_THAT(ErrorOf([] { HdrMetrics(Image(2, 2, 3, Encoding::kLinear, 1.0f), Image(2, 2, 3)); }),
              HasSubstr("all black"));
}

}  // namespace
}  // namespace hdr4d
