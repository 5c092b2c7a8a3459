#include "method/raster/blend.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/util/parallel.h"
#include "method/gaussian/constants.h"
#include "method/raster/binning.h"
#include "method/raster/simd_targets_for_test.h"

namespace hdr4d::method {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Scenes.

struct SceneOptions {
  int count = 20;
  int channels = 3;
  int width = 40;
  int height = 37;
  double min_sigma = 1.0;  // pixels, before the 0.3 dilation
  double max_sigma = 5.0;
  double min_opacity = 0.1;
  double max_opacity = 0.8;  // below kMaxAlpha: no clamp kink in the FD tests
  double margin = 6.0;       // means fall up to this far outside the image
};

// Random splats as the preprocess would produce them: an anisotropic covariance plus the 0.3
// dilation, its inverse as the conic, radius ceil(3 sqrt(lambda_max)).
SplatBuffersT<double> RandomScene(const SceneOptions& o, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  SplatBuffersT<double> s;
  s.channels = o.channels;
  s.Resize(o.count);
  for (int g = 0; g < o.count; ++g) {
    s.mean2d[2 * g] = -o.margin + (o.width + 2 * o.margin) * u(rng);
    s.mean2d[2 * g + 1] = -o.margin + (o.height + 2 * o.margin) * u(rng);
    const double s1 = o.min_sigma + (o.max_sigma - o.min_sigma) * u(rng);
    const double s2 = o.min_sigma + (o.max_sigma - o.min_sigma) * u(rng);
    const double th = kPi * u(rng);
    const double c = std::cos(th), sn = std::sin(th);
    const double xx = c * c * s1 * s1 + sn * sn * s2 * s2 + kCov2dDilation;
    const double yy = sn * sn * s1 * s1 + c * c * s2 * s2 + kCov2dDilation;
    const double xy = c * sn * (s1 * s1 - s2 * s2);
    const double det = xx * yy - xy * xy;
    s.conic[3 * g] = yy / det;
    s.conic[3 * g + 1] = -xy / det;
    s.conic[3 * g + 2] = xx / det;
    const double mid = 0.5 * (xx + yy);
    const double lambda_max = mid + std::sqrt(std::max(0.1, mid * mid - det));
    s.radius[g] = static_cast<int>(std::ceil(kRadiusSigmas * std::sqrt(lambda_max)));
    s.opacity[g] = o.min_opacity + (o.max_opacity - o.min_opacity) * u(rng);
    s.depth[g] = 1.0 + 9.0 * u(rng);
    for (int ch = 0; ch < o.channels; ++ch) s.features[g * o.channels + ch] = -1.0 + 2.0 * u(rng);
  }
  return s;
}

template <typename To, typename From>
SplatBuffersT<To> Convert(const SplatBuffersT<From>& in) {
  SplatBuffersT<To> out;
  out.channels = in.channels;
  const auto conv = [](const std::vector<From>& v) { return std::vector<To>(v.begin(), v.end()); };
  out.mean2d = conv(in.mean2d);
  out.conic = conv(in.conic);
  out.opacity = conv(in.opacity);
  out.depth = conv(in.depth);
  out.radius = in.radius;
  out.features = conv(in.features);
  return out;
}

std::vector<double> RandomValues(std::size_t n, unsigned seed, double lo = -1.0, double hi = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

// The same values as float, for dL/dimage and dL/dT.
std::vector<float> RandomFloats(std::size_t n, unsigned seed) {
  const std::vector<double> v = RandomValues(n, seed);
  return std::vector<float>(v.begin(), v.end());
}

RasterSettings Settings(int width,
                        int height,
                        std::vector<float> background,
                        RasterBackend backend = RasterBackend::kSimd) {
  RasterSettings s;
  s.width = width;
  s.height = height;
  s.background = std::move(background);
  s.backend = backend;
  return s;
}

// One float forward + backward through the public API.
struct FloatRun {
  std::vector<float> image;
  RasterState state;
  SplatGradients grads;
  std::vector<float> dL_dbackground;
};
FloatRun RunFloat(const SplatBuffers& splats,
                  const RasterSettings& settings,
                  const std::vector<float>& dL_dimage,
                  const std::vector<float>* dL_dT) {
  FloatRun r;
  r.image.assign(static_cast<std::size_t>(settings.width) * settings.height * splats.channels,
                 -7.0f);
  RasterizeForward(splats, settings, &r.state, r.image.data());
  r.dL_dbackground.assign(splats.channels, 0.0f);
  BlendBackward(splats, settings, &r.state, dL_dimage.data(), dL_dT ? dL_dT->data() : nullptr,
                &r.grads, r.dL_dbackground.data());
  return r;
}

// Two runs' image and every gradient equal bit for bit.
void ExpectSameImageAndGradients(const FloatRun& a, const FloatRun& b) {
  EXPECT_EQ(a.image, b.image);
  EXPECT_EQ(a.grads.mean2d, b.grads.mean2d);
  EXPECT_EQ(a.grads.conic, b.grads.conic);
  EXPECT_EQ(a.grads.opacity, b.grads.opacity);
  EXPECT_EQ(a.grads.features, b.grads.features);
  EXPECT_EQ(a.dL_dbackground, b.dL_dbackground);
}

// ---------------------------------------------------------------------------------------------
// An independent naive renderer: every Gaussian in (depth, id) order, kept where its tile
// rectangle holds the pixel's tile. It also counts each pixel's contributors, the signature used
// to detect a finite difference that crosses one of the rules' thresholds.

struct Naive {
  std::vector<double> image, final_T;
  std::vector<int> n_contrib, contributors;
};
Naive NaiveForward(const SplatBuffersT<double>& s,
                   int width,
                   int height,
                   const std::vector<double>& background) {
  const int n = static_cast<int>(s.size());
  const int ch = s.channels;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return static_cast<float>(s.depth[a]) < static_cast<float>(s.depth[b]);
  });
  const int tx_count = TileCount(width), ty_count = TileCount(height);
  Naive out;
  out.image.assign(static_cast<std::size_t>(width) * height * ch, 0.0);
  out.final_T.assign(static_cast<std::size_t>(width) * height, 0.0);
  out.n_contrib.assign(out.final_T.size(), 0);
  out.contributors.assign(out.final_T.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int tx = x / kTileSize, ty = y / kTileSize;
      std::vector<double> color(ch, 0.0);
      double T = 1.0;
      int position = 0, last = 0, contributors = 0;
      for (int g : order) {
        const TileRect r =
            GaussianTileRect(s.mean2d[2 * g], s.mean2d[2 * g + 1], s.radius[g], tx_count, ty_count);
        if (tx < r.x0 || tx >= r.x1 || ty < r.y0 || ty >= r.y1) continue;
        ++position;
        const double dx = s.mean2d[2 * g] - (x + 0.5), dy = s.mean2d[2 * g + 1] - (y + 0.5);
        const double* q = &s.conic[3 * g];
        const double power = -0.5 * (q[0] * dx * dx + q[2] * dy * dy) - q[1] * dx * dy;
        if (power > 0) continue;
        const double alpha = std::min<double>(kMaxAlpha, s.opacity[g] * std::exp(power));
        if (alpha < kMinAlpha) continue;
        const double test_T = T * (1 - alpha);
        if (test_T < kMinTransmittance) break;
        for (int c = 0; c < ch; ++c) color[c] += s.features[g * ch + c] * alpha * T;
        T = test_T;
        last = position;
        ++contributors;
      }
      const std::size_t pix = static_cast<std::size_t>(y) * width + x;
      for (int c = 0; c < ch; ++c) out.image[pix * ch + c] = color[c] + T * background[c];
      out.final_T[pix] = T;
      out.n_contrib[pix] = last;
      out.contributors[pix] = contributors;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Finite differences of the double reference.

struct Forward64 {
  std::vector<double> image, final_T;
  std::vector<std::int32_t> n_contrib;
};
Forward64 Reference64(const SplatBuffersT<double>& s,
                      const RasterState& bins,
                      const std::vector<double>& bg) {
  Forward64 f;
  const std::size_t pixels = static_cast<std::size_t>(bins.width) * bins.height;
  f.image.assign(pixels * s.channels, 0.0);
  f.final_T.assign(pixels, 0.0);
  f.n_contrib.assign(pixels, -1);
  BlendForwardReference<double>(s, bins, bg.data(), f.image.data(), f.final_T.data(),
                                f.n_contrib.data());
  return f;
}

struct FdReport {
  int checked = 0;
  int skipped = 0;      // the +h and -h evaluations took different branches somewhere
  int significant = 0;  // |gradient| > 1e-3: a sign error there would be caught
  double worst = 0.0;   // max |fd - analytic| / (1 + |analytic|)
};

// L = sum w image + sum v final_T (v may be empty). Checks every input against central
// differences. The binning is held fixed (it is piecewise constant, with no gradient).
// Steps: 1e-6, and 1e-7 for the conic, whose third derivatives reach ~(3 sigma)^6 / 8 ~ 1e8.
// Error budget: truncation h^2 |L'''| / 6 <= ~2e-6, rounding ~1e-16 |L| / h ~ 1e-9 with
// |L| ~ 1e2; tolerance 1e-5 (1 + |g|) (measured worst: 4e-7). A wrong sign or a missing factor 2
// on any significant component exceeds it by orders of magnitude. Threshold kinks: opacities stay
// below kMaxAlpha, and a parameter whose +h and -h renders differ in any pixel's contributor set
// or n_contrib (an alpha crossing kMinAlpha, a test_T crossing kMinTransmittance) is skipped and
// counted; at most 5% may be (none are with these seeds).
FdReport CheckFiniteDifferences(SplatBuffersT<double> s,
                                std::vector<double> bg,
                                int width,
                                int height,
                                unsigned seed,
                                bool with_T_loss) {
  RasterState bins;
  BinSplats(s, Settings(width, height, {}), &bins);
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  const std::vector<double> w = RandomValues(pixels * s.channels, seed + 100);
  const std::vector<double> v =
      with_T_loss ? RandomValues(pixels, seed + 200) : std::vector<double>();

  // Analytic gradients.
  const Forward64 f = Reference64(s, bins, bg);
  SplatGradientsT<double> grads;
  std::vector<double> dbg(s.channels, 0.0);
  BlendBackwardReference<double>(s, bins, bg.data(), f.final_T.data(), f.n_contrib.data(), w.data(),
                                 with_T_loss ? v.data() : nullptr, &grads, dbg.data());

  const auto loss = [&](std::vector<int>* signature) {
    const Forward64 e = Reference64(s, bins, bg);
    double L = 0.0;
    for (std::size_t i = 0; i < e.image.size(); ++i) L += w[i] * e.image[i];
    if (with_T_loss)
      for (std::size_t i = 0; i < pixels; ++i) L += v[i] * e.final_T[i];
    if (signature != nullptr) {
      const Naive naive = NaiveForward(s, width, height, bg);
      *signature = naive.contributors;
      signature->insert(signature->end(), naive.n_contrib.begin(), naive.n_contrib.end());
    }
    return L;
  };

  FdReport report;
  const auto check = [&](double* param, double analytic, double step, const std::string& what) {
    const double x = *param;
    std::vector<int> sig_plus, sig_minus;
    *param = x + step;
    const double plus = loss(&sig_plus);
    *param = x - step;
    const double minus = loss(&sig_minus);
    *param = x;
    if (sig_plus != sig_minus) {
      ++report.skipped;
      return;
    }
    const double fd = (plus - minus) / (2 * step);
    const double err = std::abs(fd - analytic) / (1.0 + std::abs(analytic));
    report.worst = std::max(report.worst, err);
    ++report.checked;
    if (std::abs(analytic) > 1e-3) ++report.significant;
    EXPECT_LT(err, 1e-5) << what << ": analytic " << analytic << " fd " << fd;
  };
  for (std::size_t g = 0; g < s.size(); ++g) {
    const std::string id = " of Gaussian " + std::to_string(g);
    for (int k = 0; k < 2; ++k)
      check(&s.mean2d[2 * g + k], grads.mean2d[2 * g + k], 1e-6,
            "mean2d[" + std::to_string(k) + "]" + id);
    for (int k = 0; k < 3; ++k)
      check(&s.conic[3 * g + k], grads.conic[3 * g + k], 1e-7,
            "conic[" + std::to_string(k) + "]" + id);
    check(&s.opacity[g], grads.opacity[g], 1e-6, "opacity" + id);
    for (int c = 0; c < s.channels; ++c)
      check(&s.features[g * s.channels + c], grads.features[g * s.channels + c], 1e-6,
            "feature " + std::to_string(c) + id);
  }
  for (int c = 0; c < s.channels; ++c)
    check(&bg[c], dbg[c], 1e-6, "background " + std::to_string(c));
  return report;
}

TEST(RasterBlendFd, EveryInputMatchesCentralDifferences) {
  for (int channels : {3, 6}) {
    for (unsigned seed : {1u, 2u, 3u}) {
      for (bool with_T_loss : {false, true}) {
        SceneOptions o;
        o.channels = channels;
        const SplatBuffersT<double> s = RandomScene(o, seed + 10 * channels);
        const std::vector<double> bg = RandomValues(channels, seed + 7, 0.0, 1.0);
        const FdReport r = CheckFiniteDifferences(s, bg, o.width, o.height, seed, with_T_loss);
        SCOPED_TRACE("channels " + std::to_string(channels) + " seed " + std::to_string(seed));
        const int total = r.checked + r.skipped;
        EXPECT_EQ(total, 20 * (6 + channels) + channels);
        // Threshold crossings are rare; most parameters are checked, most of them non-trivial.
        EXPECT_LE(r.skipped, total / 20);
        EXPECT_GE(r.significant, r.checked * 3 / 4);
        EXPECT_LT(r.worst, 1e-5);
      }
    }
  }
}

// The FD harness must be able to fail: a gradient with a flipped sign is rejected.
TEST(RasterBlendFd, HarnessCatchesAWrongSign) {
  SceneOptions o;
  const SplatBuffersT<double> s = RandomScene(o, 5);
  const std::vector<double> bg = {0.2, 0.3, 0.4};
  RasterState bins;
  BinSplats(s, Settings(o.width, o.height, {}), &bins);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(o.width) * o.height * 3, 9);
  const Forward64 f = Reference64(s, bins, bg);
  SplatGradientsT<double> grads;
  BlendBackwardReference<double>(s, bins, bg.data(), f.final_T.data(), f.n_contrib.data(), w.data(),
                                 nullptr, &grads, nullptr);
  int caught = 0, tried = 0;
  for (std::size_t g = 0; g < s.size(); ++g) {
    SplatBuffersT<double> p = s;
    const double h = 1e-6;
    p.opacity[g] += h;
    const Forward64 fp = Reference64(p, bins, bg);
    p.opacity[g] -= 2 * h;
    const Forward64 fm = Reference64(p, bins, bg);
    double fd = 0;
    for (std::size_t i = 0; i < w.size(); ++i) fd += w[i] * (fp.image[i] - fm.image[i]) / (2 * h);
    if (std::abs(grads.opacity[g]) < 1e-3) continue;
    ++tried;
    caught += std::abs(fd + grads.opacity[g]) / (1 + std::abs(grads.opacity[g])) > 1e-5;
  }
  EXPECT_GT(tried, 10);
  EXPECT_EQ(caught, tried);
}

// The reference (binned tiles) equals the naive all-Gaussians renderer.
TEST(RasterBlend, ReferenceMatchesNaiveRenderer) {
  for (int channels : {1, 3, 6}) {
    SceneOptions o;
    o.count = 60;
    o.channels = channels;
    o.width = 70;
    o.height = 45;
    const SplatBuffersT<double> s = RandomScene(o, 31 + channels);
    const std::vector<double> bg = RandomValues(channels, 3, 0.0, 1.0);
    RasterState bins;
    BinSplats(s, Settings(o.width, o.height, {}), &bins);
    const Forward64 f = Reference64(s, bins, bg);
    const Naive naive = NaiveForward(s, o.width, o.height, bg);
    for (std::size_t i = 0; i < f.image.size(); ++i) ASSERT_NEAR(f.image[i], naive.image[i], 1e-12);
    for (std::size_t i = 0; i < f.final_T.size(); ++i) {
      ASSERT_NEAR(f.final_T[i], naive.final_T[i], 1e-12);
      ASSERT_EQ(f.n_contrib[i], naive.n_contrib[i]);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Hand-computed cases, on both backends.

class RasterBlendCases : public ::testing::TestWithParam<RasterBackend> {};

SplatBuffers OneGaussian(float x,
                         float y,
                         float opacity,
                         std::vector<float> feature,
                         float depth = 1,
                         int radius = 3,
                         float a = 1,
                         float b = 0,
                         float c = 1) {
  SplatBuffers s;
  s.channels = static_cast<int>(feature.size());
  s.mean2d = {x, y};
  s.conic = {a, b, c};
  s.opacity = {opacity};
  s.depth = {depth};
  s.radius = {radius};
  s.features = std::move(feature);
  return s;
}

void Append(SplatBuffers* s, const SplatBuffers& more) {
  s->mean2d.insert(s->mean2d.end(), more.mean2d.begin(), more.mean2d.end());
  s->conic.insert(s->conic.end(), more.conic.begin(), more.conic.end());
  s->opacity.insert(s->opacity.end(), more.opacity.begin(), more.opacity.end());
  s->depth.insert(s->depth.end(), more.depth.begin(), more.depth.end());
  s->radius.insert(s->radius.end(), more.radius.begin(), more.radius.end());
  s->features.insert(s->features.end(), more.features.begin(), more.features.end());
}

TEST_P(RasterBlendCases, OneGaussianAtAPixelCentre) {
  const SplatBuffers s = OneGaussian(8.5f, 8.5f, 0.5f, {1.0f, 2.0f, 3.0f});
  const RasterSettings settings = Settings(20, 20, {0.1f, 0.2f, 0.4f}, GetParam());
  std::vector<float> image(20 * 20 * 3);
  RasterState state;
  RasterizeForward(s, settings, &state, image.data());
  const std::size_t centre = 8 * 20 + 8;
  EXPECT_NEAR(image[centre * 3 + 0], 0.5f * 1.0f + 0.5f * 0.1f, 1e-6);
  EXPECT_NEAR(image[centre * 3 + 1], 0.5f * 2.0f + 0.5f * 0.2f, 1e-6);
  EXPECT_NEAR(image[centre * 3 + 2], 0.5f * 3.0f + 0.5f * 0.4f, 1e-6);
  EXPECT_NEAR(state.final_transmittance[centre], 0.5f, 1e-7);
  EXPECT_EQ(state.n_contrib[centre], 1);
  // One pixel to the right: d = (-1, 0), power = -0.5, alpha = 0.5 exp(-0.5).
  const double alpha = 0.5 * std::exp(-0.5);
  EXPECT_NEAR(state.final_transmittance[centre + 1], 1 - alpha, 1e-6);
  EXPECT_NEAR(image[(centre + 1) * 3 + 2], alpha * 3 + (1 - alpha) * 0.4, 1e-6);
  // Far corner (same tile, alpha < 1/255): background, nothing listed as contributing.
  EXPECT_FLOAT_EQ(image[0], 0.1f);
  EXPECT_EQ(state.final_transmittance[0], 1.0f);
  EXPECT_EQ(state.n_contrib[0], 0);
}

TEST_P(RasterBlendCases, TwoGaussiansBlendInDepthOrder) {
  const auto render = [&](float depth_red, float depth_green) {
    SplatBuffers s = OneGaussian(5.5f, 5.5f, 0.5f, {1, 0, 0}, depth_red, 4, 0.01f, 0, 0.01f);
    Append(&s, OneGaussian(5.5f, 5.5f, 0.5f, {0, 1, 0}, depth_green, 4, 0.01f, 0, 0.01f));
    std::vector<float> image(16 * 16 * 3);
    RasterState state;
    RasterizeForward(s, Settings(16, 16, {0, 0, 1}, GetParam()), &state, image.data());
    const std::size_t p = 5 * 16 + 5;
    return std::vector<float>{image[3 * p], image[3 * p + 1], image[3 * p + 2],
                              state.final_transmittance[p]};
  };
  const std::vector<float> red_front = render(1, 2);
  EXPECT_NEAR(red_front[0], 0.5, 1e-6);
  EXPECT_NEAR(red_front[1], 0.25, 1e-6);
  EXPECT_NEAR(red_front[2], 0.25, 1e-6);  // the background through T = 0.25
  EXPECT_NEAR(red_front[3], 0.25, 1e-6);
  const std::vector<float> green_front = render(3, 2);
  EXPECT_NEAR(green_front[0], 0.25, 1e-6);
  EXPECT_NEAR(green_front[1], 0.5, 1e-6);
  EXPECT_NEAR(green_front[2], 0.25, 1e-6);
}

TEST_P(RasterBlendCases, TransmittanceStopRule) {
  // Opacity 0.99: T = 0.01 after one layer, 1e-4 (just below, in float) after two, so the second
  // layer stops the pixel and does not contribute.
  for (float opacity : {0.99f, 0.95f}) {
    SplatBuffers s;
    s.channels = 1;
    for (int k = 0; k < 8; ++k)
      Append(&s, OneGaussian(3.5f, 3.5f, opacity, {static_cast<float>(k + 1)}, 1.0f + k));
    std::vector<float> image(8 * 8);
    RasterState state;
    RasterizeForward(s, Settings(8, 8, {10.0f}, GetParam()), &state, image.data());
    const std::size_t p = 3 * 8 + 3;
    // Expected with float arithmetic in the kernel's order.
    float T = 1, color = 0;
    int contributors = 0;
    for (int k = 0; k < 8; ++k) {
      const float test_T = T * (1 - opacity);
      if (test_T < kMinTransmittance) break;
      color += static_cast<float>(k + 1) * opacity * T;
      T = test_T;
      ++contributors;
    }
    EXPECT_EQ(contributors, opacity == 0.99f ? 1 : 3);
    EXPECT_EQ(state.n_contrib[p], contributors);
    EXPECT_NEAR(state.final_transmittance[p], T, 1e-7);
    EXPECT_NEAR(image[p], color + T * 10.0f, 1e-5);
    EXPECT_GE(state.final_transmittance[p], kMinTransmittance);
  }
}

TEST_P(RasterBlendCases, SkippedGaussiansStillCountInNContrib) {
  // The front Gaussian is far from pixel (2, 2) (alpha < 1/255 there) but listed in its tile.
  SplatBuffers s = OneGaussian(12.5f, 12.5f, 0.5f, {1}, 1.0f, 3);
  Append(&s, OneGaussian(2.5f, 2.5f, 0.5f, {1}, 2.0f, 3));
  std::vector<float> image(16 * 16);
  RasterState state;
  RasterizeForward(s, Settings(16, 16, {}, GetParam()), &state, image.data());
  EXPECT_EQ(state.n_contrib[2 * 16 + 2], 2);
  EXPECT_EQ(state.n_contrib[12 * 16 + 12], 1);
  EXPECT_NEAR(image[2 * 16 + 2], 0.5, 1e-6);
}

TEST_P(RasterBlendCases, RadiusZeroContributesNothing) {
  SplatBuffers s = OneGaussian(5.5f, 5.5f, 0.5f, {1, 1, 1}, 2.0f);
  SplatBuffers with_culled = s;
  Append(&with_culled, OneGaussian(5.5f, 5.5f, 0.9f, {5, 5, 5}, 1.0f, /*radius=*/0));
  const RasterSettings settings = Settings(16, 16, {0.3f, 0.3f, 0.3f}, GetParam());
  std::vector<float> a(16 * 16 * 3), b(16 * 16 * 3);
  RasterState sa, sb;
  RasterizeForward(s, settings, &sa, a.data());
  RasterizeForward(with_culled, settings, &sb, b.data());
  EXPECT_EQ(a, b);
  EXPECT_EQ(sb.num_entries(), 1u);
  const std::vector<float> dL(16 * 16 * 3, 1.0f);
  SplatGradients grads;
  BlendBackward(with_culled, settings, &sb, dL.data(), nullptr, &grads, nullptr);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(grads.conic[3 + k], 0.0f);
  EXPECT_EQ(grads.opacity[1], 0.0f);
  EXPECT_NE(grads.opacity[0], 0.0f);
}

TEST_P(RasterBlendCases, TilesOutsideEveryGaussianStayBackground) {
  const SplatBuffers s = OneGaussian(6.5f, 6.5f, 0.8f, {1, 2, 3}, 1.0f, 4);
  const std::vector<float> bg = {0.25f, 0.5f, 0.75f};
  std::vector<float> image(50 * 40 * 3, -1.0f);
  RasterState state;
  RasterizeForward(s, Settings(50, 40, bg, GetParam()), &state, image.data());
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 50; ++x) {
      if (x < 16 && y < 16) continue;
      const std::size_t p = static_cast<std::size_t>(y) * 50 + x;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(image[p * 3 + c], bg[c]) << x << "," << y;
      ASSERT_EQ(state.final_transmittance[p], 1.0f);
      ASSERT_EQ(state.n_contrib[p], 0);
    }
  }
  // Backward: dL/dbackground = sum of T_final dL/dimage; away from the Gaussian T = 1.
  std::vector<float> dL(50 * 40 * 3, 0.0f);
  dL[(30 * 50 + 40) * 3 + 1] = 2.0f;
  SplatGradients grads;
  std::vector<float> dbg(3, 0.0f);
  BlendBackward(s, Settings(50, 40, bg, GetParam()), &state, dL.data(), nullptr, &grads,
                dbg.data());
  EXPECT_FLOAT_EQ(dbg[1], 2.0f);
  EXPECT_EQ(dbg[0], 0.0f);
  EXPECT_EQ(grads.opacity[0], 0.0f);
}

TEST_P(RasterBlendCases, ClampedAlphaPassesGradientAsTheReference) {
  // opacity 2 at the centre gives alpha = min(0.99, 2) = 0.99; the reference still returns
  // dL/dopacity = G dL/dalpha with G = 1 (not 0).
  const SplatBuffers s = OneGaussian(0.5f, 0.5f, 2.0f, {1.0f}, 1.0f, 1, 50, 0, 50);
  const RasterSettings settings = Settings(1, 1, {0.0f}, GetParam());
  float image = 0;
  RasterState state;
  RasterizeForward(s, settings, &state, &image);
  EXPECT_NEAR(image, 0.99f, 1e-6);
  const float dL = 1.0f;
  SplatGradients grads;
  BlendBackward(s, settings, &state, &dL, nullptr, &grads, nullptr);
  EXPECT_NEAR(grads.opacity[0], 1.0f, 1e-6);  // dimage/dalpha = f T = 1, G = 1
  EXPECT_NEAR(grads.features[0], 0.99f, 1e-6);
}

TEST_P(RasterBlendCases, BackwardAccumulatesIntoGradients) {
  const SplatBuffers s = OneGaussian(4.5f, 4.5f, 0.5f, {1.0f, 2.0f});
  const RasterSettings settings = Settings(9, 9, {}, GetParam());
  std::vector<float> image(9 * 9 * 2);
  RasterState state;
  RasterizeForward(s, settings, &state, image.data());
  const std::vector<float> dL(image.size(), 1.0f);
  SplatGradients once, twice;
  BlendBackward(s, settings, &state, dL.data(), nullptr, &once, nullptr);
  BlendBackward(s, settings, &state, dL.data(), nullptr, &twice, nullptr);
  BlendBackward(s, settings, &state, dL.data(), nullptr, &twice, nullptr);
  ASSERT_EQ(once.opacity.size(), 1u);
  EXPECT_FLOAT_EQ(twice.opacity[0], 2 * once.opacity[0]);
  EXPECT_FLOAT_EQ(twice.features[1], 2 * once.features[1]);
  EXPECT_NE(once.features[1], 0.0f);
}

// The backward of `s` on a 32 x 32 image (3 channels, dL/dimage = 1), keeping the largest
// weights from `start` on (none when empty), or with `share` the shares of its forward image.
SplatGradients TrackedBackward(const SplatBuffers& s, RasterBackend backend, bool share,
                               std::vector<float> start) {
  RasterSettings settings = Settings(32, 32, {}, backend);
  std::vector<float> image(32 * 32 * 3);
  RasterState state;
  RasterizeForward(s, settings, &state, image.data());
  if (share) settings.share_image = image.data();
  const std::vector<float> dL(image.size(), 1.0f);
  SplatGradients grads;
  grads.max_weight = std::move(start);
  BlendBackward(s, settings, &state, dL.data(), nullptr, &grads, nullptr);
  return grads;
}

// The backward's largest blending weight per Gaussian (--prune-contribution): a max of alpha T
// over the frame's pixels, raised into what the buffer holds, and nothing when it is empty.
TEST_P(RasterBlendCases, MaxWeightIsTheLargestAlphaTimesTransmittance) {
  // Two wide Gaussians on one pixel centre (front 0.5, back 0.5: the back one's weight is
  // 0.5 x 0.5 at that centre and less elsewhere), one alone in another tile (0.3), one culled.
  SplatBuffers s = OneGaussian(5.5f, 5.5f, 0.5f, {1, 0, 0}, 1, 4, 0.01f, 0, 0.01f);
  Append(&s, OneGaussian(5.5f, 5.5f, 0.5f, {0, 1, 0}, 2, 4, 0.01f, 0, 0.01f));
  Append(&s, OneGaussian(24.5f, 24.5f, 0.3f, {0, 0, 1}));
  Append(&s, OneGaussian(24.5f, 8.5f, 0.7f, {0, 0, 1}, 1, /*radius=*/0));
  // A value already there is only raised.
  const SplatGradients grads = TrackedBackward(s, GetParam(), false, {0.0f, 0.0f, 0.0f, 0.9f});
  ASSERT_EQ(grads.max_weight.size(), 4u);
  EXPECT_NEAR(grads.max_weight[0], 0.5f, 1e-6);
  EXPECT_NEAR(grads.max_weight[1], 0.25f, 1e-6);
  EXPECT_NEAR(grads.max_weight[2], 0.3f, 1e-6);
  EXPECT_EQ(grads.max_weight[3], 0.9f);
  EXPECT_TRUE(TrackedBackward(s, GetParam(), false, {}).max_weight.empty());
}

TEST_P(RasterBlendCases, ShareImageCountsAFaintGaussiansPartOfTheRadiance) {
  // A faint red light (alpha 0.02 G, radiance 100) in front of an opaque white Gaussian of the
  // same shape (alpha 0.99 G), both centred on pixel (5, 5). The light's weight is 0.02, but its
  // part of the red radiance is 2 G / (2 G + 0.99 G (1 - 0.02 G)), largest at the centre (G = 1):
  // 2 / (2 + 0.99 x 0.98) = 0.6734. The white one carries all of the green and blue: share 1
  // (within the floor). A lone Gaussian whose pixels hold only it has share 1, though its weight
  // is 0.3.
  SplatBuffers s = OneGaussian(5.5f, 5.5f, 0.02f, {100, 0, 0}, 1, 4, 0.01f, 0, 0.01f);
  Append(&s, OneGaussian(5.5f, 5.5f, 0.99f, {1, 1, 1}, 2, 4, 0.01f, 0, 0.01f));
  Append(&s, OneGaussian(24.5f, 24.5f, 0.3f, {0, 0, 1}));
  const SplatGradients weights = TrackedBackward(s, GetParam(), false, {0, 0, 0});
  EXPECT_NEAR(weights.max_weight[0], 0.02f, 1e-6);
  EXPECT_NEAR(weights.max_weight[2], 0.3f, 1e-6);
  const SplatGradients shares = TrackedBackward(s, GetParam(), true, {0, 0, 0});
  EXPECT_NEAR(shares.max_weight[0], 2.0 / (2.0 + 0.99 * 0.98), 1e-5);
  EXPECT_NEAR(shares.max_weight[1], 1.0f, 1e-5);
  EXPECT_NEAR(shares.max_weight[2], 1.0f, 1e-5);
  // The gradients do not depend on it.
  EXPECT_EQ(shares.opacity, weights.opacity);
  EXPECT_EQ(shares.features, weights.features);
}

TEST_P(RasterBlendCases, EmptySceneIsBackground) {
  SplatBuffers s;
  s.channels = 2;
  const RasterSettings settings = Settings(33, 17, {0.5f, -1.0f}, GetParam());
  std::vector<float> image(33 * 17 * 2, 9.0f);
  RasterState state;
  RasterizeForward(s, settings, &state, image.data());
  for (std::size_t p = 0; p < 33 * 17; ++p) {
    ASSERT_EQ(image[2 * p], 0.5f);
    ASSERT_EQ(image[2 * p + 1], -1.0f);
  }
  std::vector<float> dL(image.size(), 1.0f), dbg(2, 0.0f);
  SplatGradients grads;
  BlendBackward(s, settings, &state, dL.data(), nullptr, &grads, dbg.data());
  EXPECT_FLOAT_EQ(dbg[0], 33 * 17);
  EXPECT_TRUE(grads.opacity.empty());
}

INSTANTIATE_TEST_SUITE_P(Backends,
                         RasterBlendCases,
                         ::testing::Values(RasterBackend::kScalar, RasterBackend::kSimd),
                         [](const auto& info) {
                           return std::string(info.param == RasterBackend::kScalar ? "Scalar"
                                                                                   : "Simd");
                         });

// ---------------------------------------------------------------------------------------------
// The fast path against the scalar float path.

// The blend kernels' 2^x (alpha = opacity 2^power), on every compiled target: the AVX-512 build
// scales by 2^n with vscalefps, the others in the exponent bits.
TEST(RasterBlendSimd, FastExp2RelativeErrorBelow3e7OnEveryTarget) {
  std::vector<float> x;
  for (double v = -125.5; v <= 0.0; v += 1.1e-4) x.push_back(static_cast<float>(v));
  for (float v : {0.0f, -1e-30f, -0.5f, -1.5f, -125.0f}) x.push_back(v);
  const int ran = ForEachCompiledTarget([&] {
    std::vector<float> out(x.size());
    FastExp2(x.data(), out.data(), x.size());
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double want = std::exp2(static_cast<double>(x[i]));
      worst = std::max(worst, std::abs(out[i] - want) / want);
    }
    EXPECT_LT(worst, 3e-7);
    EXPECT_GT(worst, 0.0);  // an approximation, not std::exp2
    // Clamped outside [-125.5, 0]; odd lengths use the tail path.
    const float outside[3] = {-300.0f, 2.0f, -3.0f};
    float got[3];
    FastExp2(outside, got, 3);
    EXPECT_NEAR(got[0] / std::exp2(-125.5), 1.0, 3e-7);
    EXPECT_EQ(got[1], 1.0f);
    EXPECT_EQ(got[2], 0.125f);
  });
  EXPECT_GE(ran, 1);
}

struct Comparison {
  double image = 0, final_T = 0;
  int flipped = 0;                   // pixels where the two paths took different branches
  double grad[5] = {0, 0, 0, 0, 0};  // mean2d, conic, opacity, features, background (relative)
};

double MaxAbs(const std::vector<float>& v) {
  double m = 0;
  for (float x : v) m = std::max(m, static_cast<double>(std::abs(x)));
  return m;
}
// max |a - b| / max(1e-3, max |b|)
double RelativeDiff(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    m = std::max(m, static_cast<double>(std::abs(a[i] - b[i])));
  return m / std::max(1e-3, MaxAbs(b));
}

// Runs both backends on one random scene. A pixel where an alpha or test_T lies within the fast
// exp's error of kMinAlpha / kMinTransmittance may branch differently (n_contrib or final_T
// differ); such pixels are counted, left out of the image comparison, and given zero loss
// weight, so the gradient comparison sees only pixels where both paths made the same decisions.
Comparison CompareSplats(
    const SplatBuffers& s, int width, int height, unsigned seed, bool with_T_loss) {
  struct {
    int channels, width, height;
  } o{s.channels, width, height};
  std::vector<float> bg(o.channels);
  for (int c = 0; c < o.channels; ++c) bg[c] = 0.1f * (c + 1);
  const int ch = o.channels;
  const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
  const RasterSettings scalar_settings = Settings(o.width, o.height, bg, RasterBackend::kScalar);
  const RasterSettings simd_settings = Settings(o.width, o.height, bg, RasterBackend::kSimd);
  std::vector<float> scalar_image(pixels * ch), simd_image(pixels * ch);
  RasterState scalar, simd;
  RasterizeForward(s, scalar_settings, &scalar, scalar_image.data());
  RasterizeForward(s, simd_settings, &simd, simd_image.data());

  std::vector<float> w = RandomFloats(pixels * ch, seed + 1);
  std::vector<float> v = RandomFloats(pixels, seed + 2);
  Comparison c;
  for (std::size_t p = 0; p < pixels; ++p) {
    const float dT = std::abs(scalar.final_transmittance[p] - simd.final_transmittance[p]);
    if (scalar.n_contrib[p] != simd.n_contrib[p] || dT > 1e-5f) {
      ++c.flipped;
      for (int k = 0; k < ch; ++k) w[p * ch + k] = 0.0f;
      v[p] = 0.0f;
      continue;
    }
    c.final_T = std::max(c.final_T, static_cast<double>(dT));
    for (int k = 0; k < ch; ++k)
      c.image = std::max(c.image, static_cast<double>(
                                      std::abs(scalar_image[p * ch + k] - simd_image[p * ch + k])));
  }
  SplatGradients scalar_grads, simd_grads;
  std::vector<float> scalar_bg(ch, 0.0f), simd_bg(ch, 0.0f);
  BlendBackward(s, scalar_settings, &scalar, w.data(), with_T_loss ? v.data() : nullptr,
                &scalar_grads, scalar_bg.data());
  BlendBackward(s, simd_settings, &simd, w.data(), with_T_loss ? v.data() : nullptr, &simd_grads,
                simd_bg.data());
  c.grad[0] = RelativeDiff(simd_grads.mean2d, scalar_grads.mean2d);
  c.grad[1] = RelativeDiff(simd_grads.conic, scalar_grads.conic);
  c.grad[2] = RelativeDiff(simd_grads.opacity, scalar_grads.opacity);
  c.grad[3] = RelativeDiff(simd_grads.features, scalar_grads.features);
  c.grad[4] = RelativeDiff(simd_bg, scalar_bg);
  return c;
}

Comparison CompareBackends(const SceneOptions& o, unsigned seed, bool with_T_loss) {
  return CompareSplats(Convert<float>(RandomScene(o, seed)), o.width, o.height, seed, with_T_loss);
}

// The largest blending weights of the fast path against the scalar path's, on random scenes of
// both channel kinds (templated 3, run-time 5). Pixels that branch differently (CompareSplats)
// may move a weight by about the fast exp's error.
TEST(RasterBlendSimd, MaxWeightMatchesScalar) {
  for (int channels : {3, 5}) {
    SceneOptions o;
    o.count = 60;
    o.channels = channels;
    const SplatBuffers s = Convert<float>(RandomScene(o, 90 + channels));
    // Plain weights, then the shares of the forward's own image (--prune-radiance-share).
    for (bool share : {false, true}) {
      SplatGradients grads[2];
      int k = 0;
      for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
        RasterSettings settings = Settings(o.width, o.height, {}, backend);
        std::vector<float> image(static_cast<std::size_t>(o.width) * o.height * channels);
        RasterState state;
        RasterizeForward(s, settings, &state, image.data());
        const std::vector<float> dL(image.size(), 1.0f);
        if (share) settings.share_image = image.data();
        grads[k].max_weight.assign(s.size(), 0.0f);
        BlendBackward(s, settings, &state, dL.data(), nullptr, &grads[k], nullptr);
        ++k;
      }
      int blended = 0;
      for (std::size_t g = 0; g < s.size(); ++g) {
        EXPECT_NEAR(grads[1].max_weight[g], grads[0].max_weight[g],
                    1e-5 * std::max(1.0f, grads[0].max_weight[g]))
            << "Gaussian " << g << (share ? ", shares" : ", weights");
        blended += grads[0].max_weight[g] > 0.0f;
      }
      EXPECT_GT(blended, 20);  // the scene is not empty
    }
  }
}

// A geometry image (BlendBackward's dL_dimage_geometry) drives dL/dalpha alone: the means,
// conics and opacities get exactly the gradients of a backward with that image, the features
// and the background exactly those of a backward with dL_dimage, on both backends and for the
// templated and run-time channel counts. (Each of the two is the plain backward, which the
// finite-difference test above covers; the split only chooses which image each part reads.)
// Bit-equality holds because both backwards run the same operations in the same order; the SIMD
// backend on every compiled target (the AVX2 kernel once fused a sum in one case and not the
// other, issue 50).
TEST(RasterBlend, GeometryImageDrivesOnlyTheAlphaGradients) {
  const auto check = [](RasterBackend backend) {
    for (int channels : {3, 6, 5}) {
      SCOPED_TRACE("channels " + std::to_string(channels) + " backend " +
                   std::to_string(static_cast<int>(backend)));
      SceneOptions o;
      o.channels = channels;
      o.count = 200;
      o.width = 70;
      o.height = 45;
      const SplatBuffers s = Convert<float>(RandomScene(o, 90 + channels));
      const std::vector<float> bg(channels, 0.2f);
      const RasterSettings settings = Settings(o.width, o.height, bg, backend);
      const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
      const auto as_float = [](const std::vector<double>& v) {
        return std::vector<float>(v.begin(), v.end());
      };
      const std::vector<float> colour = as_float(RandomValues(pixels * channels, 5));
      const std::vector<float> geometry = as_float(RandomValues(pixels * channels, 6));
      const std::vector<float> dT = as_float(RandomValues(pixels, 7));
      RasterState state;
      std::vector<float> image(pixels * channels);
      RasterizeForward(s, settings, &state, image.data());
      const auto backward = [&](const std::vector<float>& dL, const float* geo,
                                std::vector<float>* dbg) {
        SplatGradients g;
        dbg->assign(channels, 0.0f);
        BlendBackward(s, settings, &state, dL.data(), dT.data(), &g, dbg->data(), geo);
        return g;
      };
      std::vector<float> bg_split, bg_colour, bg_geometry, bg_same;
      const SplatGradients split = backward(colour, geometry.data(), &bg_split);
      const SplatGradients by_colour = backward(colour, nullptr, &bg_colour);
      const SplatGradients by_geometry = backward(geometry, nullptr, &bg_geometry);
      const SplatGradients same = backward(colour, colour.data(), &bg_same);
      EXPECT_EQ(split.mean2d, by_geometry.mean2d);
      EXPECT_EQ(split.conic, by_geometry.conic);
      EXPECT_EQ(split.opacity, by_geometry.opacity);
      EXPECT_EQ(split.features, by_colour.features);
      EXPECT_EQ(bg_split, bg_colour);
      EXPECT_NE(split.mean2d, by_colour.mean2d);
      EXPECT_EQ(same.mean2d, by_colour.mean2d);  // the same image twice: the plain backward
      EXPECT_EQ(same.opacity, by_colour.opacity);
      EXPECT_EQ(same.features, by_colour.features);
    }
  };
  check(RasterBackend::kScalar);
  EXPECT_GE(ForEachCompiledTarget([&] { check(RasterBackend::kSimd); }), MinimumTargetRuns());
  // The double reference takes the same argument.
  SceneOptions o;
  const SplatBuffersT<double> s = RandomScene(o, 3);
  RasterState bins;
  BinSplats(s, Settings(o.width, o.height, {}), &bins);
  const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
  std::vector<double> image(pixels * o.channels), final_T(pixels);
  std::vector<std::int32_t> n_contrib(pixels);
  BlendForwardReference(s, bins, static_cast<const double*>(nullptr), image.data(), final_T.data(),
                        n_contrib.data());
  const std::vector<double> colour = RandomValues(pixels * o.channels, 8);
  const std::vector<double> geometry = RandomValues(pixels * o.channels, 9);
  SplatGradientsT<double> split, by_colour, by_geometry;
  const auto run = [&](const std::vector<double>& dL, const double* geo,
                       SplatGradientsT<double>* g) {
    BlendBackwardReference(s, bins, static_cast<const double*>(nullptr), final_T.data(),
                           n_contrib.data(), dL.data(), static_cast<const double*>(nullptr), g,
                           static_cast<double*>(nullptr), geo);
  };
  run(colour, geometry.data(), &split);
  run(colour, nullptr, &by_colour);
  run(geometry, nullptr, &by_geometry);
  EXPECT_EQ(split.mean2d, by_geometry.mean2d);
  EXPECT_EQ(split.conic, by_geometry.conic);
  EXPECT_EQ(split.opacity, by_geometry.opacity);
  EXPECT_EQ(split.features, by_colour.features);
}

// Forward within 1e-5 (features in [-1, 1]); gradients within 1e-5 of each field's largest
// magnitude. Justification: both paths round in float (unit round-off 6e-8) through sums of up
// to a few thousand terms per gradient (pixels x layers) with different orders (per pixel vs.
// tree sums over lanes), fused multiply-adds and a fast exp (<= 1e-6 relative); measured
// differences are 2e-7..7e-7 of the field's maximum, and the float scalar path differs from the
// double reference by the same order (next test). Branch flips must stay rare: at most 1 pixel
// in 1000 (1 of 7500 seen, with 6 channels).
TEST(RasterBlendSimd, MatchesScalarPath) {
  for (int channels : {1, 3, 4, 5, 6, 9}) {
    for (bool with_T_loss : {false, true}) {
      SceneOptions o;
      o.channels = channels;
      o.count = 400;
      o.width = 100;
      o.height = 75;
      o.max_opacity = 0.99;
      const Comparison c = CompareBackends(o, 40 + channels, with_T_loss);
      SCOPED_TRACE("channels " + std::to_string(channels));
      EXPECT_LE(c.flipped, o.width * o.height / 1000);
      EXPECT_LT(c.image, 1e-5);
      EXPECT_LT(c.final_T, 1e-5);
      for (int k = 0; k < 5; ++k) EXPECT_LT(c.grad[k], 1e-5) << "gradient field " << k;
    }
  }
}

// Every SIMD target compiled in (AVX-512: 16 lanes, one tile row per vector; AVX2: 8; SSE4 and
// SSSE3: 4, several vectors per row with column culling; scalar: 1) against the scalar path, by
// restricting Highway's dispatch to one target at a time.
TEST(RasterBlendSimd, EveryCompiledTargetMatchesScalarPath) {
  const int tested = ForEachCompiledTarget([] {
    for (int channels : {3, 5}) {
      SceneOptions o;
      o.channels = channels;
      o.count = 150;
      o.width = 50;
      o.height = 41;
      const Comparison c = CompareBackends(o, 60 + channels, true);
      EXPECT_LE(c.flipped, 2);
      EXPECT_LT(c.image, 1e-5);
      EXPECT_LT(c.final_T, 1e-5);
      for (int k = 0; k < 5; ++k) EXPECT_LT(c.grad[k], 1e-5) << "gradient field " << k;
    }
  });
  EXPECT_GE(tested, MinimumTargetRuns());  // at least one vector target and the scalar fallback
}

// Unusual splats take the same branches on both paths: a conic that is not positive definite
// (power > 0 in some directions, reach box = whole tile), opacity 0 and exactly kMinAlpha,
// opacity above 1 (alpha clamped), a sub-pixel Gaussian, one larger than the image, means on
// tile boundaries and outside the image.
TEST(RasterBlendSimd, UnusualSplatsMatchScalarPath) {
  SceneOptions o;
  o.count = 60;
  o.width = 70;
  o.height = 50;
  SplatBuffers s = Convert<float>(RandomScene(o, 91));
  const auto set = [&](int g, float x, float y, float a, float b, float c, float opacity,
                       int radius) {
    s.mean2d[2 * g] = x;
    s.mean2d[2 * g + 1] = y;
    s.conic[3 * g] = a;
    s.conic[3 * g + 1] = b;
    s.conic[3 * g + 2] = c;
    s.opacity[g] = opacity;
    s.radius[g] = radius;
  };
  set(0, 20.3f, 20.7f, 0.05f, 0.2f, 0.05f, 0.7f, 20);  // det < 0
  set(1, 40.0f, 10.0f, -0.1f, 0.0f, 0.2f, 0.7f, 12);   // a < 0
  set(2, 30.5f, 30.5f, 0.1f, 0.0f, 0.1f, 0.0f, 10);    // opacity 0
  set(3, 31.5f, 30.5f, 0.1f, 0.0f, 0.1f, kMinAlpha, 10);
  set(4, 50.2f, 40.1f, 0.1f, 0.02f, 0.1f, 3.0f, 10);     // alpha clamped at kMaxAlpha
  set(5, 16.0f, 32.0f, 50.0f, 0.0f, 50.0f, 0.9f, 1);     // sub-pixel, on a tile corner
  set(6, 35.0f, 25.0f, 1e-4f, 0.0f, 2e-4f, 0.4f, 300);   // larger than the image
  set(7, -3.0f, 25.0f, 0.05f, 0.0f, 0.05f, 0.8f, 14);    // centre left of the image
  set(8, 48.0f, 16.0f, 0.02f, -0.01f, 0.03f, 0.8f, 25);  // on a tile boundary
  const Comparison c = CompareSplats(s, o.width, o.height, 92, true);
  EXPECT_LE(c.flipped, 2);
  EXPECT_LT(c.image, 1e-5);
  EXPECT_LT(c.final_T, 1e-5);
  for (int k = 0; k < 5; ++k) EXPECT_LT(c.grad[k], 1e-5) << "gradient field " << k;
}

// Forward on one backend and backward on the other: the SIMD backward then packs its own
// records (the scalar forward leaves none).
TEST(RasterBlendSimd, BackendsCanBeMixedBetweenForwardAndBackward) {
  SceneOptions o;
  o.count = 100;
  const SplatBuffers s = Convert<float>(RandomScene(o, 17));
  const std::vector<float> dL(static_cast<std::size_t>(o.width) * o.height * 3, 0.5f);
  std::vector<float> image(dL.size());
  RasterState mixed, pure;
  RasterizeForward(s, Settings(o.width, o.height, {}, RasterBackend::kScalar), &mixed,
                   image.data());
  RasterizeForward(s, Settings(o.width, o.height, {}, RasterBackend::kSimd), &pure, image.data());
  SplatGradients g_mixed, g_pure;
  BlendBackward(s, Settings(o.width, o.height, {}, RasterBackend::kSimd), &mixed, dL.data(),
                nullptr, &g_mixed, nullptr);
  BlendBackward(s, Settings(o.width, o.height, {}, RasterBackend::kSimd), &pure, dL.data(), nullptr,
                &g_pure, nullptr);
  EXPECT_LT(RelativeDiff(g_mixed.opacity, g_pure.opacity), 1e-5);
  EXPECT_LT(RelativeDiff(g_mixed.mean2d, g_pure.mean2d), 1e-5);
}

// A scene rounded to float, binned, with its double reference forward; Gradients gives the
// reference backward for a dL/dimage. The float paths are measured against these.
struct RoundedReference {
  SplatBuffers s;                   // the float splats
  SplatBuffersT<double> s_rounded;  // the same values in double
  std::vector<double> bg;
  RasterState bins;
  Forward64 f;
  SplatGradientsT<double> Gradients(const std::vector<double>& dL) const {
    SplatGradientsT<double> g;
    BlendBackwardReference<double>(s_rounded, bins, bg.data(), f.final_T.data(), f.n_contrib.data(),
                                   dL.data(), nullptr, &g, nullptr);
    return g;
  }
};
RoundedReference MakeRoundedReference(const SplatBuffersT<double>& s64,
                                      const SceneOptions& o,
                                      double background) {
  RoundedReference r;
  r.s = Convert<float>(s64);
  r.s_rounded = Convert<double>(r.s);
  r.bg.assign(o.channels, background);
  BinSplats(r.s_rounded, Settings(o.width, o.height, {}), &r.bins);
  r.f = Reference64(r.s_rounded, r.bins, r.bg);
  return r;
}

std::vector<float> ToFloat(const std::vector<double>& v) {
  return std::vector<float>(v.begin(), v.end());
}

// The float scalar path against the double reference: the scale of float round-off that the
// SIMD tolerance above is measured against.
TEST(RasterBlendSimd, FloatPathsAgreeWithDoubleReference) {
  SceneOptions o;
  o.count = 300;
  o.width = 80;
  o.height = 64;
  o.channels = 6;
  const RoundedReference ref = MakeRoundedReference(RandomScene(o, 77), o, 0.5);
  const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
  const std::vector<double> w64 = RandomValues(pixels * 6, 78);
  const SplatGradientsT<double> g64 = ref.Gradients(w64);
  for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
    const FloatRun r =
        RunFloat(ref.s, Settings(o.width, o.height, std::vector<float>(6, 0.5f), backend),
                 ToFloat(w64), nullptr);
    double image = 0;
    for (std::size_t i = 0; i < r.image.size(); ++i)
      image = std::max(image, std::abs(r.image[i] - ref.f.image[i]));
    EXPECT_LT(image, 1e-5);
    EXPECT_LT(RelativeDiff(r.grads.mean2d, ToFloat(g64.mean2d)), 1e-5);
    EXPECT_LT(RelativeDiff(r.grads.conic, ToFloat(g64.conic)), 1e-5);
    EXPECT_LT(RelativeDiff(r.grads.opacity, ToFloat(g64.opacity)), 1e-5);
    EXPECT_LT(RelativeDiff(r.grads.features, ToFloat(g64.features)), 1e-5);
  }
}

// HDR-4DGS's 6-channel pass: three HDR radiances from 1e-2 to 1e5 beside three LDR values, with
// the HDR image's gradient at the scale of 1 / radiance (as the pixel branch's is). The SIMD
// backward folds the channels into one behind term per pixel before the subtraction in
// dL/dalpha; its error against the double reference stays at the scalar per-channel form's.
TEST(RasterBlendSimd, HdrAndLdrChannelsTogetherMatchTheDoubleReference) {
  SceneOptions o;
  o.count = 300;
  o.width = 80;
  o.height = 64;
  o.channels = 6;
  SplatBuffersT<double> s64 = RandomScene(o, 81);
  std::mt19937 rng(82);
  std::uniform_real_distribution<double> exponent(-2.0, 5.0);
  for (std::size_t g = 0; g < s64.size(); ++g) {
    for (int ch = 0; ch < 3; ++ch) s64.features[g * 6 + ch] = std::pow(10.0, exponent(rng));
    for (int ch = 3; ch < 6; ++ch) s64.features[g * 6 + ch] = 0.5 + 0.5 * s64.features[g * 6 + ch];
  }
  const RoundedReference ref = MakeRoundedReference(s64, o, 0.0);
  const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
  std::vector<double> w64 = RandomValues(pixels * 6, 83);
  for (std::size_t px = 0; px < pixels; ++px) {
    for (int ch = 0; ch < 3; ++ch) w64[px * 6 + ch] /= std::max(1e-2, ref.f.image[px * 6 + ch]);
  }
  const SplatGradientsT<double> g64 = ref.Gradients(w64);
  const auto errors = [&](RasterBackend backend) {
    const FloatRun r =
        RunFloat(ref.s, Settings(o.width, o.height, std::vector<float>(6, 0.0f), backend),
                 ToFloat(w64), nullptr);
    return std::vector<double>{RelativeDiff(r.grads.mean2d, ToFloat(g64.mean2d)),
                               RelativeDiff(r.grads.conic, ToFloat(g64.conic)),
                               RelativeDiff(r.grads.opacity, ToFloat(g64.opacity))};
  };
  const std::vector<double> scalar = errors(RasterBackend::kScalar);
  // Every SIMD target, within 6x the scalar path's error (1e-5 relative error in the behind
  // term fails this; measured: 0.8-2.9x).
  const int tested = ForEachCompiledTarget([&] {
    const std::vector<double> simd = errors(RasterBackend::kSimd);
    for (int k = 0; k < 3; ++k) {
      SCOPED_TRACE(::testing::Message()
                   << "field " << k << ": scalar " << scalar[k] << ", SIMD " << simd[k]);
      EXPECT_LT(scalar[k], 1e-4);
      EXPECT_LT(simd[k], 6 * scalar[k] + 1e-7);
    }
  });
  EXPECT_GE(tested, 1);
}

// 3000 splats of up to 8 px sigma on 160x120 with 6 channels (HDR + LDR): many overlaps per
// tile, for the tests that compare whole frames.
SceneOptions DenseSixChannelScene() {
  SceneOptions o;
  o.count = 3000;
  o.width = 160;
  o.height = 120;
  o.channels = 6;
  o.max_sigma = 8;
  return o;
}

TEST(RasterBlendSimd, DeterministicAcrossThreadCounts) {
  const SplatBuffers s = Convert<float>(RandomScene(DenseSixChannelScene(), 5));
  const std::vector<float> w = RandomFloats(static_cast<std::size_t>(160) * 120 * 6, 6);
  const std::vector<float> v = RandomFloats(static_cast<std::size_t>(160) * 120, 7);
  for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
    const RasterSettings settings = Settings(160, 120, std::vector<float>(6, 0.25f), backend);
    FloatRun one, two;
    {
      ThreadLimit limit(1);
      one = RunFloat(s, settings, w, &v);
    }
    {
      ThreadLimit limit(2);
      two = RunFloat(s, settings, w, &v);
    }
    ExpectSameImageAndGradients(one, two);
    EXPECT_EQ(one.state.point_list, two.state.point_list);
  }
}

// RasterizeForward packs the SIMD records beside the depth sort; binning first and packing in
// BlendForward gives the same records, image and gradients bit for bit, at one and two threads,
// with and without the per-entry records, and with a state last used for a larger frame.
TEST(RasterBlendSimd, PackedBesideTheSortEqualsPackedAfterIt) {
  const SplatBuffers s = Convert<float>(RandomScene(DenseSixChannelScene(), 11));
  const SplatBuffers other = Convert<float>(RandomScene(DenseSixChannelScene(), 12));
  const std::vector<float> w = RandomFloats(static_cast<std::size_t>(160) * 120 * 6, 13);
  for (const int threads : {1, 2}) {
    for (const bool keep : {true, false}) {
      SCOPED_TRACE("threads " + std::to_string(threads) + (keep ? " records" : " no records"));
      ThreadLimit limit(threads);
      RasterSettings settings = Settings(160, 120, std::vector<float>(6, 0.25f));
      settings.keep_records = keep;
      FloatRun beside, after;
      for (FloatRun* r : {&beside, &after}) r->image.assign(w.size(), -7.0f);
      std::vector<float> scratch(w.size());
      for (FloatRun* r : {&beside, &after})  // a frame before, packed beside its sort
        RasterizeForward(other, settings, &r->state, scratch.data());
      RasterizeForward(s, settings, &beside.state, beside.image.data());
      BinSplats(s, settings, &after.state);
      EXPECT_FALSE(after.state.packed_ready);
      BlendForward(s, settings, &after.state, after.image.data());
      EXPECT_EQ(beside.state.packed_splats, after.state.packed_splats);
      EXPECT_EQ(beside.state.final_transmittance, after.state.final_transmittance);
      if (!keep) {
        EXPECT_EQ(beside.image, after.image);
        continue;
      }
      for (FloatRun* r : {&beside, &after}) {
        r->dL_dbackground.assign(6, 0.0f);
        BlendBackward(s, settings, &r->state, w.data(), nullptr, &r->grads,
                      r->dL_dbackground.data());
      }
      ExpectSameImageAndGradients(beside, after);
    }
  }
}

// The per-axis reach the preprocess computes (preprocess_common.h BinningReach), from the conic:
// Sigma_xx = c / det and Sigma_yy = a / det of the conic (a, b, c).
void AddPreprocessReach(SplatBuffers* s) {
  s->reach.assign(2 * s->size(), 0);
  for (std::size_t g = 0; g < s->size(); ++g) {
    const double a = s->conic[3 * g], b = s->conic[3 * g + 1], c = s->conic[3 * g + 2];
    const double det = a * c - b * b;
    const double level = 255.0 * s->opacity[g];
    if (s->radius[g] <= 0 || !(level > 1.0) || !(det > 0.0)) continue;
    const double sigma[2] = {c / det, a / det};
    for (int k = 0; k < 2; ++k) {
      const int r = static_cast<int>(std::ceil(std::sqrt(2.0 * std::log(level) * sigma[k]))) + 1;
      s->reach[2 * g + k] = std::min(s->radius[g], r);
    }
  }
}

// Binning with the per-axis reach drops only tiles where no pixel blends: the image, the final
// transmittance, every gradient and the background's gradient are bit-identical to the square's,
// with fewer list entries (needles and tilted splats at every opacity).
TEST(RasterBlend, PerAxisReachChangesNoPixelAndNoGradient) {
  SceneOptions o;
  o.count = 1500;
  o.width = 96;
  o.height = 80;
  o.min_sigma = 0.3;
  o.max_sigma = 12.0;
  o.min_opacity = 0.005;
  o.max_opacity = 1.0;
  for (int channels : {3, 6}) {
    o.channels = channels;
    const SplatBuffers square = Convert<float>(RandomScene(o, 21 + channels));
    SplatBuffers snug = square;
    AddPreprocessReach(&snug);
    const std::size_t pixels = static_cast<std::size_t>(o.width) * o.height;
    const std::vector<float> w = RandomFloats(pixels * channels, 22);
    const std::vector<float> v = RandomFloats(pixels, 23);
    for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
      const RasterSettings settings =
          Settings(o.width, o.height, std::vector<float>(channels, 0.25f), backend);
      const FloatRun a = RunFloat(square, settings, w, &v);
      const FloatRun b = RunFloat(snug, settings, w, &v);
      SCOPED_TRACE(channels);
      ExpectSameImageAndGradients(a, b);
      EXPECT_EQ(a.state.final_transmittance, b.state.final_transmittance);
      EXPECT_LT(b.state.num_entries(), a.state.num_entries() * 9 / 10);
    }
  }
}

// A forward no backward follows (keep_records false) reads the per-Gaussian records in place
// and keeps no n_contrib: the same image and final transmittance bit for bit, on every compiled
// SIMD target and for the templated and run-time channel counts.
TEST(RasterBlendSimd, ForwardWithoutRecordsIsIdenticalAndKeepsLess) {
  const SplatBuffers s = Convert<float>(RandomScene(DenseSixChannelScene(), 9));
  for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
    RasterSettings settings = Settings(160, 120, std::vector<float>(6, 0.25f), backend);
    std::vector<float> kept_image(static_cast<std::size_t>(160) * 120 * 6), lean_image(
                                                                             kept_image.size());
    RasterState kept, lean;
    RasterizeForward(s, settings, &kept, kept_image.data());
    settings.keep_records = false;
    RasterizeForward(s, settings, &lean, lean_image.data());
    EXPECT_EQ(kept_image, lean_image);
    EXPECT_EQ(kept.final_transmittance, lean.final_transmittance);
    EXPECT_EQ(kept.n_contrib.size(), kept_image.size() / 6);
    EXPECT_TRUE(lean.n_contrib.empty());  // only a backward reads it
    EXPECT_EQ(kept.point_list, lean.point_list);
    EXPECT_EQ(kept.entry_slots.size(), kept.point_list.size());
    EXPECT_TRUE(lean.entry_slots.empty() && lean.point_entries.empty());
    if (backend == RasterBackend::kSimd) {
      EXPECT_LT(lean.packed_splats.size(), kept.packed_splats.size() / 2);
    }
  }
  const int tested = ForEachCompiledTarget([] {
    for (int channels : {1, 3, 4, 6, 5}) {
      SCOPED_TRACE("channels " + std::to_string(channels));
      SceneOptions o;
      o.channels = channels;
      o.count = 400;
      o.width = 70;
      o.height = 45;
      const SplatBuffers splats = Convert<float>(RandomScene(o, 30 + channels));
      RasterSettings settings = Settings(o.width, o.height, std::vector<float>(channels, 0.1f));
      std::vector<float> kept_image(static_cast<std::size_t>(o.width) * o.height * channels);
      std::vector<float> lean_image(kept_image.size());
      RasterState kept, lean;
      RasterizeForward(splats, settings, &kept, kept_image.data());
      settings.keep_records = false;
      RasterizeForward(splats, settings, &lean, lean_image.data());
      EXPECT_EQ(kept_image, lean_image);
      EXPECT_EQ(kept.final_transmittance, lean.final_transmittance);
      EXPECT_TRUE(lean.n_contrib.empty());
    }
  });
  EXPECT_GE(tested, MinimumTargetRuns());
}

TEST(RasterBlendSimd, StateIsReusedAcrossFrames) {
  SceneOptions big;
  big.count = 500;
  big.width = 90;
  big.height = 70;
  SceneOptions small = big;
  small.count = 40;
  small.width = 33;
  small.height = 21;
  const SplatBuffers a = Convert<float>(RandomScene(big, 1));
  const SplatBuffers b = Convert<float>(RandomScene(small, 2));
  const RasterSettings sa = Settings(big.width, big.height, {0.1f, 0.2f, 0.3f});
  const RasterSettings sb = Settings(small.width, small.height, {0.1f, 0.2f, 0.3f});
  const std::vector<float> wb(static_cast<std::size_t>(33) * 21 * 3, 0.5f);
  const std::vector<float> wa(static_cast<std::size_t>(90) * 70 * 3, 0.5f);
  RasterState reused;
  std::vector<float> image_a(wa.size()), image_b(wb.size()), fresh_image(wb.size());
  RasterizeForward(a, sa, &reused, image_a.data());
  SplatGradients ga;
  BlendBackward(a, sa, &reused, wa.data(), nullptr, &ga, nullptr);
  RasterizeForward(b, sb, &reused, image_b.data());
  SplatGradients gb, g_fresh;
  BlendBackward(b, sb, &reused, wb.data(), nullptr, &gb, nullptr);
  RasterState fresh;
  RasterizeForward(b, sb, &fresh, fresh_image.data());
  BlendBackward(b, sb, &fresh, wb.data(), nullptr, &g_fresh, nullptr);
  EXPECT_EQ(image_b, fresh_image);
  EXPECT_EQ(gb.opacity, g_fresh.opacity);
  EXPECT_EQ(gb.mean2d, g_fresh.mean2d);
}

// ---------------------------------------------------------------------------------------------
// Caller bugs abort with a check.

// A backward of a frame rendered without keep_records has no entry slots to write: caught by
// CheckBinnedForBackward (blend.cpp), which every backward runs first. Its passing side is every
// backward test of this file, the finite-difference ones (RasterBlendFd) included.
TEST(RasterBlendDeathTest, BackwardAfterAForwardWithoutRecordsIsCaught) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  SceneOptions o;
  o.count = 50;
  const SplatBuffers s = Convert<float>(RandomScene(o, 4));
  const std::vector<float> dL(static_cast<std::size_t>(o.width) * o.height * 3, 0.5f);
  std::vector<float> image(dL.size());
  for (RasterBackend backend : {RasterBackend::kScalar, RasterBackend::kSimd}) {
    RasterSettings settings = Settings(o.width, o.height, {}, backend);
    settings.keep_records = false;
    RasterState state;
    RasterizeForward(s, settings, &state, image.data());
    SplatGradients g;
    EXPECT_DEATH(BlendBackward(s, settings, &state, dL.data(), nullptr, &g, nullptr), "entry_slots");
  }
}

TEST(RasterBlendDeathTest, MisuseIsCaught) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const SplatBuffers s = OneGaussian(4.5f, 4.5f, 0.5f, {1, 2, 3});
  std::vector<float> image(16 * 16 * 3);
  RasterState state;
  EXPECT_DEATH(BlendForward(s, Settings(16, 16, {}), &state, image.data()), "check failed");
  RasterizeForward(s, Settings(16, 16, {}), &state, image.data());
  EXPECT_DEATH(BlendForward(s, Settings(15, 16, {}), &state, image.data()), "check failed");
  EXPECT_DEATH(BlendForward(s, Settings(16, 16, {1.0f}), &state, image.data()), "check failed");
  SplatBuffers broken = s;
  broken.features.pop_back();
  EXPECT_DEATH(BlendForward(broken, Settings(16, 16, {}), &state, image.data()), "check failed");
  SplatGradients wrong;
  wrong.opacity.assign(3, 0.0f);
  const std::vector<float> dL(image.size(), 1.0f);
  EXPECT_DEATH(BlendBackward(s, Settings(16, 16, {}), &state, dL.data(), nullptr, &wrong, nullptr),
               "check failed");
  RasterState not_blended;
  BinSplats(s, Settings(16, 16, {}), &not_blended);
  SplatGradients grads;
  EXPECT_DEATH(
      BlendBackward(s, Settings(16, 16, {}), &not_blended, dL.data(), nullptr, &grads, nullptr),
      "check failed");
}

}  // namespace
}  // namespace hdr4d::method
