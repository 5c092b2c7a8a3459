// FLIP against NVIDIA's reference tool, and its contract.
//
// The fixture pairs are generated here, deterministically (FlipPairs). The expected means come
// from NVIDIA's FLIP tool (github.com/NVlabs/flip at commit 1eb247c, built by
// /work/shared/peers/build_flip.sh, defaults: 67 pixels per degree, ACES, exposure range from
// the reference), run as `flip -r ref_<name>.<png|exr> -t test_<name>.<png|exr> -nerm -c out.csv`
// on the files that this test writes when HDR4D_FLIP_PAIRS_DIR is set (LDR pairs as 8-bit PNG,
// HDR pairs as float EXR, so that both programs read the same values):
//   HDR4D_FLIP_PAIRS_DIR=/tmp/pairs build/core/metrics/core_flip_test --gtest_filter='*Write*'
#include "core/metrics/flip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d {
namespace {

// splitmix64: the same numbers on every platform.
struct Rng {
  std::uint64_t state;
  std::uint64_t Next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return (Next() >> 11) * 0x1.0p-53; }
  double Normal() {  // Box-Muller
    const double u = 1.0 - Uniform(), v = Uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  }
};

// Gradients, hard-edged discs, fine stripes and grain in [0,1]: something for both the colour
// and the feature pipeline.
Image Scene(int w, int h, std::uint64_t seed) {
  Rng rng{seed};
  struct Disc {
    double cx, cy, r, c[3];
  };
  std::vector<Disc> discs;
  for (int i = 0; i < 4; ++i) {
    discs.push_back({rng.Uniform() * w, rng.Uniform() * h, (0.08 + 0.12 * rng.Uniform()) * h,
                     {rng.Uniform(), rng.Uniform(), rng.Uniform()}});
  }
  Image image(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double u = double(x) / w, v = double(y) / h;
      double c[3] = {0.5 + 0.4 * std::sin(6.2832 * 1.3 * u), 0.5 + 0.4 * std::sin(6.2832 * v + 1),
                     0.5 + 0.4 * std::cos(4.4 * (u + v))};
      for (const Disc& d : discs) {
        if (std::hypot(x - d.cx, y - d.cy) < d.r) c[0] = d.c[0], c[1] = d.c[1], c[2] = d.c[2];
      }
      const bool stripes = v > 0.7 && v < 0.85 && u < 0.5;
      for (int k = 0; k < 3; ++k) {
        if (stripes) c[k] = (x / 2) % 2 ? 0.9 : 0.1;
        image.at(x, y, k) = float(std::clamp(c[k] + 0.06 * (rng.Uniform() - 0.5), 0.0, 1.0));
      }
    }
  }
  return image;
}

template <typename Fn>
Image Map(const Image& in, Fn fn) {
  Image out = in;
  for (int y = 0; y < in.height(); ++y) {
    for (int x = 0; x < in.width(); ++x) {
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = fn(x, y, c);
    }
  }
  return out;
}

Image BoxBlur(const Image& in, int radius) {
  return Map(in, [&](int x, int y, int c) {
    double sum = 0;
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dx = -radius; dx <= radius; ++dx) {
        sum += in.at(std::clamp(x + dx, 0, in.width() - 1), std::clamp(y + dy, 0, in.height() - 1),
                     c);
      }
    }
    return float(sum / ((2 * radius + 1) * (2 * radius + 1)));
  });
}

// What an 8-bit PNG holds: display-encoded values k / 255.
Image Quantised8(const Image& in) {
  Image out = Map(in, [&](int x, int y, int c) {
    return float(std::lround(std::clamp(in.at(x, y, c), 0.0f, 1.0f) * 255.0f)) / 255.0f;
  });
  out.set_encoding(Encoding::kSrgb);
  return out;
}

struct FlipPair {
  std::string name;
  Image gt, pred;
  bool hdr;
};

std::vector<FlipPair> LdrPairs(int w, int h) {
  const Image ref = Scene(w, h, 7);
  Rng rng{11};
  // JPEG-like: per 8x8 block, the deviation from the block mean quantised to quarters.
  auto blocky = [&](int x, int y, int c) {
    double mean = 0;
    const int bx = x / 8 * 8, by = y / 8 * 8;
    int n = 0;
    for (int yy = by; yy < std::min(by + 8, h); ++yy) {
      for (int xx = bx; xx < std::min(bx + 8, w); ++xx) mean += ref.at(xx, yy, c), ++n;
    }
    mean /= n;
    return float(mean + std::round((ref.at(x, y, c) - mean) * 4.0) / 4.0);
  };
  std::vector<FlipPair> pairs = {
      {"ldr_noise", ref, Map(ref, [&](int x, int y, int c) {
         return float(ref.at(x, y, c) + 0.06 * rng.Normal());
       }), false},
      {"ldr_blur", ref, BoxBlur(ref, 2), false},
      {"ldr_shift", ref, Map(ref, [&](int x, int y, int c) {
         return ref.at(std::max(x - 2, 0), std::max(y - 1, 0), c);
       }), false},
      {"ldr_colour", ref, Map(ref, [&](int x, int y, int c) {
         return ref.at(x, y, c) * (c == 0 ? 1.12f : c == 2 ? 0.85f : 1.0f);
       }), false},
      {"ldr_jpeg", ref, Map(ref, blocky), false},
      {"ldr_tone", ref, Map(ref, [&](int x, int y, int c) {
         return std::pow(ref.at(x, y, c), 1.4f);
       }), false},
  };
  for (FlipPair& p : pairs) p.gt = Quantised8(p.gt), p.pred = Quantised8(p.pred);
  return pairs;
}

// Linear radiance: the scene's colours squared and scaled, a dark corner, and highlights from
// 50 to 1e4.
Image HdrScene(int w, int h) {
  const Image base = Scene(w, h, 3);
  Image out = Map(base, [&](int x, int y, int c) {
    float v = 4.0f * base.at(x, y, c) * base.at(x, y, c);
    if (x < w / 6 && y < h / 6) v *= 0.001f;
    return v;
  });
  const float peaks[3] = {50.0f, 800.0f, 1e4f};
  for (int i = 0; i < 3; ++i) {
    const int cx = w * (i + 1) / 4, cy = h / 3, r = std::max(1, h / 20);
    for (int y = cy - r; y <= cy + r; ++y) {
      for (int x = cx - r; x <= cx + r; ++x) {
        for (int c = 0; c < 3; ++c) out.at(x, y, c) = peaks[i] * (c == 2 ? 0.8f : 1.0f);
      }
    }
  }
  return out;
}

std::vector<FlipPair> HdrPairs(int w, int h) {
  const Image ref = HdrScene(w, h);
  Rng rng{5};
  return {
      {"hdr_noise", ref, Map(ref, [&](int x, int y, int c) {
         return std::max(0.0f, float(ref.at(x, y, c) * (1 + 0.1 * rng.Normal()) +
                                     0.002 * rng.Normal()));
       }), true},
      {"hdr_blur", ref, BoxBlur(ref, 1), true},
      {"hdr_exposure", ref, Map(ref, [&](int x, int y, int c) { return 1.3f * ref.at(x, y, c); }),
       true},
      {"hdr_colour", ref, Map(ref, [&](int x, int y, int c) {
         return ref.at(x, y, c) * (c == 1 ? 0.9f : c == 2 ? 1.15f : 1.0f);
       }), true},
      {"hdr_clipped", ref, Map(ref, [&](int x, int y, int c) {
         return std::min(ref.at(x, y, c), 20.0f);
       }), true},
  };
}

std::vector<FlipPair> AllPairs(int w, int h) {
  std::vector<FlipPair> pairs = LdrPairs(w, h);
  for (FlipPair& p : HdrPairs(w, h)) pairs.push_back(std::move(p));
  return pairs;
}

double Score(const FlipPair& p) { return p.hdr ? HdrFlip(p.pred, p.gt) : Flip(p.pred, p.gt); }

// Writes the pairs for the reference tool (see the top of this file); skipped without
// HDR4D_FLIP_PAIRS_DIR. HDR4D_FLIP_PAIRS_SIZE=WxH changes the size (default: the fixtures').
TEST(FlipFixtures, WritePairsForTheReferenceTool) {
  const char* dir = std::getenv("HDR4D_FLIP_PAIRS_DIR");
  if (!dir) GTEST_SKIP() << "HDR4D_FLIP_PAIRS_DIR not set";
  int w = 96, h = 64;
  if (const char* size = std::getenv("HDR4D_FLIP_PAIRS_SIZE")) {
    ASSERT_EQ(std::sscanf(size, "%dx%d", &w, &h), 2);
  }
  for (const FlipPair& p : AllPairs(w, h)) {
    const std::string ext = p.hdr ? ".exr" : ".png";
    ImageWriteOptions options;
    options.format = p.hdr ? PixelFormat::kFloat : PixelFormat::kUint8;
    WriteImage(std::filesystem::path(dir) / ("ref_" + p.name + ext), p.gt, options);
    WriteImage(std::filesystem::path(dir) / ("test_" + p.name + ext), p.pred, options);
    std::printf("%s %.6f\n", p.name.c_str(), Score(p));
  }
}

// ---- Against the reference tool ------------------------------------------------------------

// The tool's "Mean" for the 96x64 fixture pairs (its CSV, 6 decimals).
const std::map<std::string, double> kToolMeans = {
    {"ldr_noise", 0.130544},
    {"ldr_blur", 0.143292},
    {"ldr_shift", 0.301507},
    {"ldr_colour", 0.310862},
    {"ldr_jpeg", 0.220556},
    {"ldr_tone", 0.336881},
    {"hdr_noise", 0.070119},
    {"hdr_blur", 0.196808},
    {"hdr_exposure", 0.322257},
    {"hdr_colour", 0.214316},
    {"hdr_clipped", 0.057723},
};

TEST(Flip, MatchesTheReferenceToolOnTheFixturePairs) {
  const std::vector<FlipPair> pairs = AllPairs(96, 64);
  ASSERT_EQ(pairs.size(), kToolMeans.size());
  for (const FlipPair& p : pairs) {
    // The issue asks for 1e-3; we hold float rounding (the tool sums in float) plus its 6 digits.
    EXPECT_NEAR(Score(p), kToolMeans.at(p.name), 2e-5) << p.name;
  }
}

// ---- Contract ---------------------------------------------------------------------------------

TEST(Flip, IdenticalImagesScoreZero) {
  const Image a = Quantised8(Scene(40, 30, 1));
  EXPECT_EQ(Flip(a, a), 0.0);
  const Image h = HdrScene(40, 30);
  EXPECT_EQ(HdrFlip(h, h), 0.0);
}

TEST(Flip, BlackAgainstWhiteIsNearlyTheLargestError) {
  const Image black(32, 32, 3, Encoding::kSrgb, 0.0f), white(32, 32, 3, Encoding::kSrgb, 1.0f);
  const double f = Flip(black, white);
  EXPECT_GT(f, 0.9);
  EXPECT_LE(f, 1.0);
}

TEST(Flip, LdrFlipIsSymmetricAndGrowsWithTheError) {
  const Image ref = Quantised8(Scene(48, 40, 2));
  auto noisy = [&](double sigma) {
    Rng rng{3};
    return Quantised8(Map(ref, [&](int x, int y, int c) {
      return float(ref.at(x, y, c) + sigma * rng.Normal());
    }));
  };
  const Image a = noisy(0.02), b = noisy(0.1);
  EXPECT_NEAR(Flip(a, ref), Flip(ref, a), 1e-6);
  EXPECT_LT(Flip(a, ref), Flip(b, ref));
}

TEST(Flip, EncodingDecidesTheDecoding) {
  // The same stored values read as sRGB or as linear are different colours.
  Image a = Quantised8(Scene(32, 24, 4)), b = Quantised8(BoxBlur(Scene(32, 24, 4), 1));
  const double srgb = Flip(a, b);
  a.set_encoding(Encoding::kLinear), b.set_encoding(Encoding::kLinear);
  EXPECT_NE(Flip(a, b), srgb);
}

TEST(Flip, GreyImagesAreThreeEqualChannels) {
  const Image rgb = Quantised8(Scene(24, 20, 5));
  Image grey(24, 20, 1, Encoding::kSrgb), grey3(24, 20, 3, Encoding::kSrgb);
  Image other = grey, other3 = grey3;
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 24; ++x) {
      grey.at(x, y, 0) = rgb.at(x, y, 1), other.at(x, y, 0) = rgb.at(x, y, 0);
      for (int c = 0; c < 3; ++c) {
        grey3.at(x, y, c) = rgb.at(x, y, 1), other3.at(x, y, c) = rgb.at(x, y, 0);
      }
    }
  }
  EXPECT_DOUBLE_EQ(Flip(grey, other), Flip(grey3, other3));
}

TEST(Flip, MapsDoNotDependOnTheThreadCount) {
  const std::vector<FlipPair> pairs = AllPairs(64, 48);
  const FlipPair& ldr = pairs[0];
  const FlipPair& hdr = pairs.back();
  const Image ldr_all = FlipMap(ldr.pred, ldr.gt), hdr_all = HdrFlipMap(hdr.pred, hdr.gt);
  ThreadLimit one(1);
  EXPECT_EQ(FlipMap(ldr.pred, ldr.gt).values(), ldr_all.values());
  EXPECT_EQ(HdrFlipMap(hdr.pred, hdr.gt).values(), hdr_all.values());
}

TEST(Flip, TinyImagesWork) {
  const Image a(1, 1, 3, Encoding::kSrgb, 0.2f), b(1, 1, 3, Encoding::kSrgb, 0.7f);
  const double f = Flip(a, b);
  EXPECT_GT(f, 0.0);
  EXPECT_LE(f, 1.0);
}

TEST(Flip, RejectsBadInputs) {
  const Image a(8, 8, 3, Encoding::kSrgb, 0.5f), b(8, 9, 3, Encoding::kSrgb, 0.5f);
  EXPECT_THROW(Flip(a, b), Error);
  EXPECT_THROW(Flip(Image(), Image()), Error);
  Image nan = a;
  nan.at(3, 4, 1) = std::nanf("");
  EXPECT_THROW(Flip(nan, a), Error);
  EXPECT_THROW(HdrFlip(a, nan), Error);
  EXPECT_THROW(Flip(a, a, 0.0), Error);
  const Image black(8, 8, 3, Encoding::kLinear, 0.0f);
  EXPECT_THROW(HdrFlip(black, black), Error);  // no exposure range
}

// ---- HDR exposure range ----------------------------------------------------------------------

TEST(HdrFlip, ExposureRangeFollowsTheReferencesMaximumAndMedian) {
  // ACES maps x85 to 0.85; the range puts the maximum there first and the median last.
  Image gt(4, 1, 3, Encoding::kLinear);
  const float lum[4] = {0.01f, 0.1f, 1.0f, 64.0f};
  for (int x = 0; x < 4; ++x) {
    for (int c = 0; c < 3; ++c) gt.at(x, 0, c) = lum[x];
  }
  const HdrFlipExposures r = HdrFlipExposureRange(gt);
  // Median: the upper middle of 4 (index 2), luminance 1 (the weights sum to 1).
  EXPECT_NEAR(r.stop - r.start, std::log2(64.0), 1e-5);
  EXPECT_EQ(r.count, 6);
  // ACES(x85) = 0.85 with the tool's coefficients.
  const double x85 = std::exp2(r.stop);
  const double a = 0.36 * 2.51, b = 0.6 * 0.03, c = 0.36 * 2.43, d = 0.6 * 0.59, e = 0.14;
  EXPECT_NEAR((a * x85 * x85 + b * x85) / (c * x85 * x85 + d * x85 + e), 0.85, 1e-6);
}

TEST(HdrFlip, MostlyBlackReferenceUsesThePositiveMedian) {
  // Four of seven pixels black: the median luminance is 0 (log2(x85 / 0) is no exposure); the
  // median of the positive luminances {2, 8, 32} is 8, the maximum 32.
  Image gt(7, 1, 3, Encoding::kLinear, 0.0f);
  const float lum[3] = {2.0f, 8.0f, 32.0f};
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 3; ++c) gt.at(4 + i, 0, c) = lum[i];
  }
  const HdrFlipExposures r = HdrFlipExposureRange(gt);
  EXPECT_NEAR(r.stop - r.start, 2.0, 1e-5);
  EXPECT_EQ(r.count, 2);
  EXPECT_TRUE(std::isfinite(HdrFlip(gt, gt)));
}

// ---- Magma ------------------------------------------------------------------------------------

TEST(FlipMagma, EndsAndRounding) {
  Image map(3, 1, 1);
  map.at(0, 0, 0) = 0.0f, map.at(1, 0, 0) = 1.0f, map.at(2, 0, 0) = 0.5f;
  const Image m = FlipMagma(map);
  EXPECT_EQ(m.encoding(), Encoding::kSrgb);
  EXPECT_NEAR(m.at(0, 0, 2), 0.013866f, 1e-6);  // near black, bluish
  EXPECT_NEAR(m.at(1, 0, 0), 0.987053f, 1e-6);  // pale yellow
  EXPECT_NEAR(m.at(1, 0, 2), 0.749504f, 1e-6);
  EXPECT_NEAR(m.at(2, 0, 0), 0.716387f, 1e-6);  // index round(127.5) = 128
  EXPECT_THROW(FlipMagma(Image(2, 2, 3)), Error);
}

}  // namespace
}  // namespace hdr4d
