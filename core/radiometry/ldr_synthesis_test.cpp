#include "core/radiometry/ldr_synthesis.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using hdr4d::testing::ErrorOf;

using ::testing::HasSubstr;

Image Flat(int w, int h, int c, float value) { return Image(w, h, c, Encoding::kLinear, value); }

// Radiance log-uniform in [10^lo, 10^hi], deterministic.
Image LogRandom(int w, int h, int c, unsigned seed, double lo, double hi) {
  Image u = testing::RandomImage(w, h, c, seed);
  for (float& v : u.values()) v = static_cast<float>(std::pow(10.0, lo + (hi - lo) * v));
  return u;
}

LdrSynthesisOptions Options(double exposure, int bits = 8) {
  LdrSynthesisOptions options;
  options.exposure = exposure;
  options.bits = bits;
  return options;
}

std::vector<std::shared_ptr<Crf>> Crfs() {
  return {std::make_shared<LinearCrf>(), std::make_shared<GammaCrf>(2.2),
          std::make_shared<SrgbCrf>(), std::make_shared<FilmicCrf>(),
          std::make_shared<TableCrf>(std::vector<double>{0.1, 0.5, 2.0},
                                     std::vector<double>{0.2, 0.6, 1.0}, "t")};
}

double Mean(const Image& image) {
  double sum = 0;
  for (float v : image.values()) sum += v;
  return sum / image.size();
}

TEST(LdrSynthesis, HandComputedPixels) {
  Image hdr = Flat(3, 1, 1, 0.5f);
  hdr.at(1, 0, 0) = 0.4f;
  hdr.at(2, 0, 0) = 10.0f;
  const GammaCrf gamma(2.2);
  const Image ldr8 = SynthesizeLdr(hdr, gamma, Options(0.5, 8));
  EXPECT_EQ(ldr8.encoding(), Encoding::kSrgb);
  // round(255 * 0.25^(1/2.2)) = round(135.79) = 136.
  EXPECT_EQ(ldr8.at(0, 0, 0), static_cast<float>(136.0 / 255));
  EXPECT_EQ(ldr8.at(1, 0, 0), static_cast<float>(std::round(255 * std::pow(0.2, 1 / 2.2)) / 255));
  EXPECT_EQ(ldr8.at(2, 0, 0), 1.0f);
  // round(65535 * 0.25^(1/2.2)) = round(34898.73) = 34899.
  EXPECT_EQ(SynthesizeLdr(hdr, gamma, Options(0.5, 16)).at(0, 0, 0),
            static_cast<float>(34899.0 / 65535));
  EXPECT_EQ(SynthesizeLdr(hdr, gamma, Options(0.5, 0)).at(0, 0, 0),
            static_cast<float>(std::pow(0.25, 1 / 2.2)));
  // sRGB of 0.2 is 0.48453 -> code 124; filmic (1.5, 0.18) of 0.5 is 0.88517 -> code 226.
  const Image one = Flat(1, 1, 1, 0.2f);
  EXPECT_EQ(SynthesizeLdr(one, SrgbCrf(), Options(1.0)).at(0, 0, 0),
            static_cast<float>(124.0 / 255));
  EXPECT_EQ(SynthesizeLdr(one, FilmicCrf(), Options(2.5)).at(0, 0, 0),
            static_cast<float>(226.0 / 255));
  EXPECT_EQ(SynthesizeLdr(one, LinearCrf(), Options(2.0)).at(0, 0, 0),
            static_cast<float>(102.0 / 255));
}

TEST(LdrSynthesis, BrighterWithLongerExposureOverTheWholeRange) {
  const Image hdr = LogRandom(48, 32, 3, 7, -6, 6);
  for (const auto& crf : Crfs()) {
    SCOPED_TRACE(crf->Spec());
    Image previous;
    double previous_mean = -1;
    for (int e = 0; e <= 14; ++e) {
      const double exposure = std::pow(10.0, -4.0 + 7.0 * e / 14);
      const Image ldr = SynthesizeLdr(hdr, *crf, Options(exposure));
      ASSERT_EQ(FirstNonFinite(ldr), -1);
      for (float v : ldr.values()) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
      const double mean = Mean(ldr);
      EXPECT_GT(mean, previous_mean) << exposure;
      if (!previous.empty()) {
        for (std::size_t i = 0; i < ldr.size(); ++i) {
          ASSERT_GE(ldr.values()[i], previous.values()[i]) << exposure << " value " << i;
        }
      }
      previous = ldr;
      previous_mean = mean;
    }
  }
  // The extremes: 1e6 * 1e3 saturates, 1e-6 * 1e-4 is black.
  Image extremes = Flat(2, 1, 1, 1e6f);
  extremes.at(1, 0, 0) = 1e-6f;
  EXPECT_EQ(SynthesizeLdr(extremes, GammaCrf(), Options(1e3)).at(0, 0, 0), 1.0f);
  EXPECT_EQ(SynthesizeLdr(extremes, GammaCrf(), Options(1e-4)).at(1, 0, 0), 0.0f);
  Image huge = Flat(1, 1, 1, std::numeric_limits<float>::max());
  LdrSynthesisOptions noisy = Options(1e300, 0);
  noisy.noise.full_well = 1000;
  noisy.noise.read_sigma = 0.01;
  EXPECT_EQ(SynthesizeLdr(huge, FilmicCrf(), noisy).at(0, 0, 0), 1.0f);  // x overflows to inf
}

TEST(LdrSynthesis, ValuesAtOrAboveSaturationAreExactlyOne) {
  for (const auto& crf : Crfs()) {
    SCOPED_TRACE(crf->Spec());
    const double exposure = 0.25;
    const double sat_radiance = crf->Saturation() / exposure;
    Image hdr(5, 1, 1);
    const double factors[] = {1.0, 1.0001, 3.0, 1e6, 0.999};
    for (int i = 0; i < 5; ++i) hdr.at(i, 0, 0) = static_cast<float>(sat_radiance * factors[i]);
    for (int bits : {0, 8, 16}) {
      const Image ldr = SynthesizeLdr(hdr, *crf, Options(exposure, bits));
      for (int i = 0; i < 4; ++i) EXPECT_EQ(ldr.at(i, 0, 0), 1.0f) << bits << " " << i;
      if (bits != 8) {
        EXPECT_LT(ldr.at(4, 0, 0), 1.0f) << bits;
      }
    }
  }
}

TEST(LdrSynthesis, QuantisesToTheCodeGrid) {
  Image hdr(1024, 1, 3);
  for (int i = 0; i < 1024; ++i) {
    for (int c = 0; c < 3; ++c) hdr.at(i, 0, c) = static_cast<float>((i + 0.37 * c) / 900.0);
  }
  for (int bits : {8, 16}) {
    const double levels = std::ldexp(1.0, bits) - 1;
    const Image ldr = SynthesizeLdr(hdr, SrgbCrf(), Options(1.0, bits));
    std::set<float> distinct;
    for (float v : ldr.values()) {
      ASSERT_EQ(v, static_cast<float>(std::round(v * levels) / levels)) << bits << " " << v;
      distinct.insert(v);
    }
    EXPECT_LE(distinct.size(), static_cast<std::size_t>(levels + 1));
    EXPECT_GT(distinct.size(), bits == 8 ? 200u : 2000u);
  }
  // No quantisation: values off the 16-bit grid exist.
  const Image raw = SynthesizeLdr(hdr, SrgbCrf(), Options(1.0, 0));
  int off_grid = 0;
  for (float v : raw.values())
    off_grid += v != static_cast<float>(std::round(v * 65535.0) / 65535.0);
  EXPECT_GT(off_grid, 1000);
}

TEST(LdrSynthesis, RejectsBadInputsAndOptions) {
  const Image hdr = Flat(4, 3, 3, 0.5f);
  const GammaCrf crf;
  const auto error = [&](const Image& image, LdrSynthesisOptions options) {
    return ErrorOf([&] { SynthesizeLdr(image, crf, options); });
  };
  EXPECT_THAT(error(hdr, Options(0.0)),
              HasSubstr("exposure time must be a finite number of seconds > 0, got 0"));
  EXPECT_THAT(error(hdr, Options(-1.0)), HasSubstr("got -1"));
  EXPECT_THAT(error(hdr, Options(std::nan(""))), HasSubstr("got nan"));
  EXPECT_THAT(error(hdr, Options(std::numeric_limits<double>::infinity())), HasSubstr("got inf"));
  EXPECT_THAT(error(hdr, Options(1.0, 12)),
              HasSubstr("bits must be 8, 16 or 0 (no quantisation), got 12"));
  EXPECT_THAT(error(hdr, Options(1.0, -8)), HasSubstr("got -8"));
  LdrSynthesisOptions options = Options(1.0);
  options.noise.full_well = -5;
  EXPECT_THAT(error(hdr, options), HasSubstr("full_well must be a finite electron count >= 0"));
  options.noise.full_well = std::nan("");
  EXPECT_THAT(error(hdr, options), HasSubstr("full_well"));
  options.noise.full_well = 0;
  options.noise.read_sigma = -0.1;
  EXPECT_THAT(error(hdr, options),
              HasSubstr("read_sigma must be a finite number >= 0 (0 = no read noise), got -0.1"));
  options.noise.read_sigma = std::numeric_limits<double>::infinity();
  EXPECT_THAT(error(hdr, options), HasSubstr("read_sigma"));
  EXPECT_THROW(Options(0.0).Validate(), Error);
  EXPECT_NO_THROW(Options(1e-9, 16).Validate());

  Image bad = hdr;
  bad.at(3, 2, 1) = -0.25f;
  EXPECT_THAT(error(bad, Options(1.0)),
              HasSubstr("HDR value -0.25 at pixel (3, 2) channel 1 is not a radiance; values must "
                        "be finite and >= 0 (image 4x3x3)"));
  bad.at(3, 2, 1) = std::nanf("");
  EXPECT_THAT(error(bad, Options(1.0)), HasSubstr("HDR value nan at pixel (3, 2) channel 1"));
  bad.at(3, 2, 1) = std::numeric_limits<float>::infinity();
  EXPECT_THAT(error(bad, Options(1.0)), HasSubstr("HDR value inf at pixel (3, 2) channel 1"));
  Image srgb = hdr;
  srgb.set_encoding(Encoding::kSrgb);
  EXPECT_THAT(error(srgb, Options(1.0)), HasSubstr("expected linear HDR radiance"));
  EXPECT_THAT(error(Image(), Options(1.0)), HasSubstr("the HDR image is empty (0x0x0)"));
}

LdrSynthesisOptions NoisyOptions(std::uint64_t seed) {
  LdrSynthesisOptions options = Options(0.8, 16);
  options.noise.full_well = 2000;
  options.noise.read_sigma = 0.004;
  options.noise.seed = seed;
  return options;
}

TEST(LdrSynthesis, NoiseIsDeterministicAndThreadIndependent) {
  const Image hdr = testing::RandomImage(97, 61, 3, 3, 0.0f, 1.2f);
  const GammaCrf crf;
  const Image a = SynthesizeLdr(hdr, crf, NoisyOptions(42));
  const Image b = SynthesizeLdr(hdr, crf, NoisyOptions(42));
  EXPECT_EQ(a.values(), b.values());
  const Image c = SynthesizeLdr(hdr, crf, NoisyOptions(43));
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += a.values()[i] != c.values()[i];
  EXPECT_GT(differ, a.size() * 3 / 4);
  Image single;
  {
    ThreadLimit limit(1);
    single = SynthesizeLdr(hdr, crf, NoisyOptions(42));
  }
  EXPECT_EQ(single.values(), a.values());
  // The noise is really there: the clean image differs.
  const Image clean = SynthesizeLdr(hdr, crf, Options(0.8, 16));
  differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += a.values()[i] != clean.values()[i];
  EXPECT_GT(differ, a.size() * 3 / 4);
}

struct Stats {
  double mean = 0, variance = 0;
};
Stats StatsOf(const Image& image, int channel) {
  Stats s;
  const std::size_t n = image.num_pixels();
  for (std::size_t p = 0; p < n; ++p) s.mean += image.values()[p * image.channels() + channel];
  s.mean /= n;
  for (std::size_t p = 0; p < n; ++p) {
    const double d = image.values()[p * image.channels() + channel] - s.mean;
    s.variance += d * d;
  }
  s.variance /= n - 1;
  return s;
}

TEST(LdrSynthesis, NoiseStatisticsMatchTheSensorModel) {
  // Linear CRF, no quantisation: the output is the noisy exposure itself.
  const int n = 256;
  LdrSynthesisOptions options = Options(1.0, 0);
  options.noise = {1000, 0.01, 5};
  const Image flat = SynthesizeLdr(Flat(n, n, 3, 0.3f), LinearCrf(), options);
  const double expected_var = 0.3 / 1000 + 0.01 * 0.01;  // shot (x / full_well) + read
  for (int c = 0; c < 3; ++c) {
    const Stats s = StatsOf(flat, c);
    EXPECT_NEAR(s.mean, 0.3, 4 * std::sqrt(expected_var / (n * n))) << c;
    EXPECT_NEAR(s.variance, expected_var, 0.1 * expected_var) << c;
  }
  // Channels are independent draws.
  double cov = 0;
  const Stats s0 = StatsOf(flat, 0), s1 = StatsOf(flat, 1);
  for (int p = 0; p < n * n; ++p) {
    cov += (flat.values()[p * 3] - s0.mean) * (flat.values()[p * 3 + 1] - s1.mean);
  }
  EXPECT_LT(std::abs(cov / (n * n) / std::sqrt(s0.variance * s1.variance)), 0.02);

  // Read noise only.
  options.noise = {0, 0.05, 6};
  const Stats read = StatsOf(SynthesizeLdr(Flat(n, n, 1, 0.5f), LinearCrf(), options), 0);
  EXPECT_NEAR(read.mean, 0.5, 4 * 0.05 / n);
  EXPECT_NEAR(read.variance, 0.0025, 0.1 * 0.0025);

  // Few electrons: exact Poisson, integer electron counts, P(0) = e^-5.
  options.noise = {1000, 0, 7};
  const Image poisson = SynthesizeLdr(Flat(n, n, 1, 0.005f), LinearCrf(), options);
  int zeros = 0;
  for (float v : poisson.values()) {
    const double electrons = v * 1000.0;
    ASSERT_NEAR(electrons, std::round(electrons), 1e-3);
    zeros += electrons < 0.5;
  }
  const Stats e = StatsOf(poisson, 0);
  EXPECT_NEAR(e.mean * 1000, 5.0, 4 * std::sqrt(5.0 / (n * n)));
  EXPECT_NEAR(e.variance * 1e6, 5.0, 0.1 * 5.0);
  const double expected_zeros = std::exp(-5.0) * n * n;
  EXPECT_NEAR(zeros, expected_zeros, 5 * std::sqrt(expected_zeros));
}

TEST(LdrSynthesis, AlphaPassesThrough) {
  Image hdr = Flat(2, 2, 4, 4.0f);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) hdr.at(x, y, 3) = 0.5f;
  LdrSynthesisOptions options = Options(0.1);
  options.noise = {500, 0.02, 1};
  const Image ldr = SynthesizeLdr(hdr, GammaCrf(), options);
  EXPECT_EQ(ldr.at(1, 1, 3), static_cast<float>(128.0 / 255));  // round(127.5): no CRF, no noise
  EXPECT_NE(ldr.at(1, 1, 0), ldr.at(1, 1, 3));
  const Image linear = LinearizeLdr(ldr, GammaCrf(), 0.1);
  EXPECT_EQ(linear.at(1, 1, 3), ldr.at(1, 1, 3));
  EXPECT_NEAR(linear.at(1, 1, 0), 4.0, 0.4);
  const Image merged = MergeExposures({ldr, ldr}, {0.1, 0.1}, GammaCrf());
  EXPECT_EQ(merged.at(0, 1, 3), ldr.at(0, 1, 3));
}

TEST(LdrSynthesis, LinearizeInvertsSynthesisWithinQuantisationError) {
  const double exposure = 0.37;
  for (const auto& crf : Crfs()) {
    // Exposures x from 1e-3 to 1.5 times saturation (some clip).
    const double sat = crf->Saturation();
    const Image hdr = LogRandom(64, 64, 3, 11, std::log10(1e-3 * sat / exposure),
                                std::log10(1.5 * sat / exposure));
    for (int bits : {8, 16}) {
      SCOPED_TRACE(crf->Spec() + " bits " + std::to_string(bits));
      const double q = 0.5 / (std::ldexp(1.0, bits) - 1);
      const Image ldr = SynthesizeLdr(hdr, *crf, Options(exposure, bits));
      const Image back = LinearizeLdr(ldr, *crf, exposure);
      EXPECT_EQ(back.encoding(), Encoding::kLinear);
      int checked = 0, saturated = 0;
      double worst = 0;
      for (std::size_t i = 0; i < hdr.size(); ++i) {
        const double y = ldr.values()[i];
        const double truth = hdr.values()[i];
        if (y == 1.0) {
          ++saturated;
          ASSERT_EQ(back.values()[i], static_cast<float>(crf->Saturation() / exposure));
          ASSERT_GE(truth * exposure * (1 + 1e-6), crf->Inverse(1 - 1.01 * q));
          continue;
        }
        if (y < 2 * q) continue;
        // |dx| <= q / (the least CRF slope over the quantisation interval), for CRFs whose
        // slope is monotone or unimodal there (it is then least at an end).
        const double x_lo = crf->Inverse(y - 1.01 * q), x_hi = crf->Inverse(y + 1.01 * q);
        const double slope = std::min(crf->Derivative(x_lo), crf->Derivative(x_hi));
        const double bound = (q / slope) / exposure + 1e-6 * truth;
        const double err = std::abs(back.values()[i] - truth);
        ASSERT_LE(err, bound) << "value " << i << " y = " << y << " truth " << truth;
        worst = std::max(worst, err / bound);
        ++checked;
      }
      EXPECT_GT(checked, static_cast<int>(hdr.size()) / 2);
      EXPECT_GT(saturated, 0);
      EXPECT_GT(worst, 0.2);  // the bound is not vacuous
    }
  }
}

TEST(LdrSynthesis, LinearizeRejectsBadInputs) {
  const GammaCrf crf;
  Image ldr(3, 2, 3, Encoding::kSrgb, 0.5f);
  EXPECT_EQ(LinearizeLdr(ldr, crf, 2.0).at(0, 0, 0), static_cast<float>(std::pow(0.5, 2.2) / 2));
  const auto error = [&](const Image& image, const Crf& c, double exposure) {
    return ErrorOf([&] { LinearizeLdr(image, c, exposure); });
  };
  EXPECT_THAT(error(ldr, crf, 0.0), HasSubstr("exposure time must be a finite number"));
  EXPECT_THAT(error(ldr, crf, std::nan("")), HasSubstr("got nan"));
  Image linear = ldr;
  linear.set_encoding(Encoding::kLinear);
  EXPECT_THAT(error(linear, crf, 1.0), HasSubstr("expected display-encoded values"));
  Image bad = ldr;
  bad.at(2, 1, 0) = 1.5f;
  EXPECT_THAT(error(bad, crf, 1.0),
              HasSubstr("value 1.5 at pixel (2, 1) channel 0 is outside [0, 1] (image 3x2x3)"));
  bad.at(2, 1, 0) = std::nanf("");
  EXPECT_THAT(error(bad, crf, 1.0), HasSubstr("value nan at pixel (2, 1) channel 0"));
  EXPECT_THAT(error(Image(0, 0, 0, Encoding::kSrgb), crf, 1.0), HasSubstr("the image is empty"));
  const TableCrf flat({0.0, 0.2, 0.4, 1.0}, {0.0, 0.5, 0.5, 1.0}, "flat.csv");
  EXPECT_THAT(error(ldr, flat, 1.0),
              HasSubstr("the camera response 'table:flat.csv' is not invertible"));
}

// A horizontal ramp of radiance from 1e-3 to 1e3.
Image Ramp(int n) {
  Image hdr(n, 1, 1);
  for (int i = 0; i < n; ++i)
    hdr.at(i, 0, 0) = static_cast<float>(std::pow(10.0, -3.0 + 6.0 * i / (n - 1)));
  return hdr;
}

TEST(LdrSynthesis, MergeRecoversTheRampBetterThanAnySingleExposure) {
  const int n = 2000;
  const Image hdr = Ramp(n);
  const std::vector<double> exposures = {0.125, 2.0, 32.0};
  for (const auto& crf : std::vector<std::shared_ptr<Crf>>{std::make_shared<GammaCrf>(2.2),
                                                           std::make_shared<FilmicCrf>()}) {
    SCOPED_TRACE(crf->Spec());
    std::vector<Image> stack, singles;
    for (double t : exposures) {
      stack.push_back(SynthesizeLdr(hdr, *crf, Options(t)));
      singles.push_back(LinearizeLdr(stack.back(), *crf, t));
    }
    const Image merged = MergeExposures(stack, exposures, *crf);
    // Well exposed: some exposure puts the pixel in [0.1, 0.9] of the display range.
    const auto well_exposed = [&](int i) {
      for (double t : exposures) {
        const double y = crf->Apply(hdr.at(i, 0, 0) * t);
        if (y >= 0.1 && y <= 0.9) return true;
      }
      return false;
    };
    double merged_worst = 0, merged_mean = 0;
    std::vector<double> single_worst(exposures.size(), 0.0), single_mean(exposures.size(), 0.0);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      if (!well_exposed(i)) continue;
      ++count;
      const double truth = hdr.at(i, 0, 0);
      const double err = std::abs(merged.at(i, 0, 0) - truth) / truth;
      merged_worst = std::max(merged_worst, err);
      merged_mean += err;
      for (std::size_t j = 0; j < exposures.size(); ++j) {
        const double single = singles[j].at(i, 0, 0);
        const double e = std::abs(single - truth) / truth;
        single_worst[j] = std::max(single_worst[j], e);
        single_mean[j] += e;
      }
    }
    merged_mean /= count;
    EXPECT_GT(count, n / 3);
    EXPECT_LT(merged_worst, 0.04);
    EXPECT_LT(merged_mean, 0.01);
    for (std::size_t j = 0; j < exposures.size(); ++j) {
      EXPECT_GT(single_worst[j], 2 * merged_worst) << exposures[j];
      EXPECT_GT(single_mean[j] / count, 2 * merged_mean) << exposures[j];
    }
    // Above 8 every exposure clips: the shortest exposure's saturation radiance, 1 / 0.125.
    EXPECT_EQ(merged.at(n - 1, 0, 0), 8.0f);
    std::printf("[ %s ] merged worst %.4f mean %.5f over %d px; singles worst %.3f %.3f %.3f\n",
                crf->Spec().c_str(), merged_worst, merged_mean, count, single_worst[0],
                single_worst[1], single_worst[2]);
  }
}

TEST(LdrSynthesis, MergeFallsBackWhenNoExposureVotes) {
  const GammaCrf crf;
  // Pixel 0 clipped everywhere, pixel 1 black everywhere, pixel 2 clipped in the two longer
  // exposures and black in the shortest (inconsistent, but possible with noise).
  std::vector<Image> stack(3, Image(3, 1, 1, Encoding::kSrgb));
  const std::vector<double> exposures = {2.0, 0.125, 32.0};  // not sorted on purpose
  for (int j = 0; j < 3; ++j) {
    stack[j].at(0, 0, 0) = 1.0f;
    stack[j].at(1, 0, 0) = 0.0f;
    stack[j].at(2, 0, 0) = exposures[j] == 0.125 ? 0.0f : 1.0f;
  }
  const Image merged = MergeExposures(stack, exposures, crf);
  EXPECT_EQ(merged.at(0, 0, 0), 8.0f);  // 1 / shortest exposure
  EXPECT_EQ(merged.at(1, 0, 0), 0.0f);
  EXPECT_EQ(merged.at(2, 0, 0), 0.5f);  // 1 / shortest clipped exposure
  // One image merges to its own linearisation.
  const Image ldr = SynthesizeLdr(LogRandom(32, 32, 3, 4, -2, 0.5), crf, Options(1.0));
  const Image alone = MergeExposures({ldr}, {1.0}, crf);
  const Image linear = LinearizeLdr(ldr, crf, 1.0);
  for (std::size_t i = 0; i < ldr.size(); ++i) {
    ASSERT_NEAR(alone.values()[i], linear.values()[i], 1e-6 * linear.values()[i]) << i;
  }
}

TEST(LdrSynthesis, MergeIsAHatWeightedMeanOfLogRadiance) {
  // Inconsistent estimates, so the weights show: y = (0.2, 0.8) at t = (1, 2) gives estimates
  // 0.2 and 0.4 with equal weights 0.2, their geometric mean; y = (0.1, 0.6) weighs 0.1 : 0.4.
  std::vector<Image> stack(2, Image(2, 1, 1, Encoding::kSrgb));
  stack[0].at(0, 0, 0) = 0.2f;
  stack[1].at(0, 0, 0) = 0.8f;
  stack[0].at(1, 0, 0) = 0.1f;
  stack[1].at(1, 0, 0) = 0.6f;
  const Image merged = MergeExposures(stack, {1.0, 2.0}, LinearCrf());
  EXPECT_NEAR(merged.at(0, 0, 0), std::sqrt(0.2f * (0.8f / 2)), 1e-7);
  const double w0 = 0.1f, w1 = 1 - 0.6f;
  EXPECT_NEAR(merged.at(1, 0, 0),
              std::exp((w0 * std::log(0.1f) + w1 * std::log(0.6f / 2.0)) / (w0 + w1)), 1e-7);
}

TEST(LdrSynthesis, MergeWithSixteenBitsIsNearlyExact) {
  const Image hdr = Ramp(500);
  const std::vector<double> exposures = {0.125, 2.0, 32.0};
  const SrgbCrf crf;
  std::vector<Image> stack;
  for (double t : exposures) stack.push_back(SynthesizeLdr(hdr, crf, Options(t, 16)));
  const Image merged = MergeExposures(stack, exposures, crf);
  for (int i = 0; i < 500; ++i) {
    const double truth = hdr.at(i, 0, 0);
    if (truth * 0.125 >= 0.9) break;
    ASSERT_NEAR(merged.at(i, 0, 0), truth, 2e-3 * truth) << i;
  }
}

TEST(LdrSynthesis, MergeRejectsBadStacks) {
  const GammaCrf crf;
  const Image a(4, 4, 3, Encoding::kSrgb, 0.5f);
  const auto error = [&](const std::vector<Image>& stack, const std::vector<double>& t,
                         const Crf& c) { return ErrorOf([&] { MergeExposures(stack, t, c); }); };
  EXPECT_THAT(error({}, {}, crf), HasSubstr("no images to merge"));
  EXPECT_THAT(error({a, a}, {1.0}, crf), HasSubstr("2 images but 1 exposure times"));
  EXPECT_THAT(error({a, Image(4, 3, 3, Encoding::kSrgb)}, {1.0, 2.0}, crf),
              HasSubstr("image 1 is 4x3x3 but image 0 is 4x4x3"));
  EXPECT_THAT(error({a, a}, {1.0, -2.0}, crf),
              HasSubstr("image 1 (exposure -2 s): exposure time must be"));
  Image bad = a;
  bad.at(1, 2, 2) = -0.1f;
  EXPECT_THAT(error({a, bad}, {1.0, 2.0}, crf),
              HasSubstr("image 1 (exposure 2 s): value -0.1 at pixel (1, 2) channel 2"));
  Image linear = a;
  linear.set_encoding(Encoding::kLinear);
  EXPECT_THAT(error({linear}, {1.0}, crf),
              HasSubstr("image 0 (exposure 1 s): expected display-encoded"));
  const TableCrf flat({0.0, 0.2, 0.4, 1.0}, {0.0, 0.5, 0.5, 1.0}, "flat.csv");
  EXPECT_THAT(error({a}, {1.0}, flat),
              HasSubstr("HDR merge: the camera response 'table:flat.csv' is not invertible"));
}

}  // namespace
}  // namespace hdr4d
