#include "method/train/loss.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <random>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/metrics/metrics.h"
#include "core/util/parallel.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

struct Pair {
  int width, height, channels;
  std::vector<double> pred, gt;
};

// Random images in [0, 1] whose values differ everywhere by at least 0.02, so a central
// difference with a small step never crosses the L1 kink.
Pair RandomPair(int width, int height, int channels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Pair p{width, height, channels, {}, {}};
  const std::size_t n = static_cast<std::size_t>(width) * height * channels;
  for (std::size_t i = 0; i < n; ++i) {
    double a, b;
    do {
      a = u(rng);
      b = u(rng);
    } while (std::abs(a - b) < 0.02);
    p.pred.push_back(a);
    p.gt.push_back(b);
  }
  return p;
}

LossResult Eval(const Pair& p, double lambda, std::vector<double>* grad = nullptr) {
  if (grad) grad->assign(p.pred.size(), 0.0);
  return PhotometricLoss(p.pred.data(), p.gt.data(), p.width, p.height, p.channels, lambda,
                         grad ? grad->data() : nullptr);
}

// Central differences of the double loss at the given entries. Step 1e-6: the truncation
// error (~h^2 |L'''| ~ 1e-12) and the rounding error (~1e-16 |L| / h ~ 1e-10) are both far
// below the tolerance used by the callers.
std::vector<double> NumericGradient(Pair p,
                                    double lambda,
                                    const std::vector<std::size_t>& entries) {
  constexpr double kStep = 1e-6;
  std::vector<double> out;
  for (std::size_t i : entries) {
    const double x = p.pred[i];
    p.pred[i] = x + kStep;
    const double plus = Eval(p, lambda).value;
    p.pred[i] = x - kStep;
    const double minus = Eval(p, lambda).value;
    p.pred[i] = x;
    out.push_back((plus - minus) / (2.0 * kStep));
  }
  return out;
}

std::vector<std::size_t> AllEntries(const Pair& p) {
  std::vector<std::size_t> e(p.pred.size());
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = i;
  return e;
}

// Number of entries where analytic and numeric gradients disagree beyond
// |a - n| <= 1e-9 + 1e-6 |n|. Gradients are O(1 / count) >= 1e-4 here, so 1e-9 is a
// relative error of at most 1e-5, while the finite-difference error is ~1e-10.
int Mismatches(const std::vector<double>& analytic,
               const std::vector<double>& numeric,
               const std::vector<std::size_t>& entries,
               std::string* first = nullptr) {
  int bad = 0;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const double a = analytic[entries[k]];
    const double n = numeric[k];
    if (!(std::abs(a - n) <= 1e-9 + 1e-6 * std::abs(n))) {
      if (bad == 0 && first) {
        *first = "entry " + std::to_string(entries[k]) + ": analytic " + std::to_string(a) +
                 ", numeric " + std::to_string(n);
      }
      ++bad;
    }
  }
  return bad;
}

void ExpectGradientMatches(int width, int height, int channels, unsigned seed, double lambda) {
  const Pair p = RandomPair(width, height, channels, seed);
  std::vector<double> grad;
  Eval(p, lambda, &grad);
  const std::vector<std::size_t> entries = AllEntries(p);
  const std::vector<double> numeric = NumericGradient(p, lambda, entries);
  std::string first;
  EXPECT_EQ(Mismatches(grad, numeric, entries, &first), 0)
      << width << "x" << height << "x" << channels << " seed " << seed << " lambda " << lambda
      << ": " << first;
}

TEST(PhotometricLoss, GradientMatchesFiniteDifferences13x9x3) {
  for (unsigned seed : {1u, 2u, 3u}) ExpectGradientMatches(13, 9, 3, seed, 0.2);
}

TEST(PhotometricLoss, GradientMatchesFiniteDifferences20x17x6) {
  for (unsigned seed : {4u, 5u}) ExpectGradientMatches(20, 17, 6, seed, 0.2);
}

TEST(PhotometricLoss, GradientMatchesFiniteDifferencesPureTerms) {
  ExpectGradientMatches(16, 11, 3, 6, 0.0);  // L1 only
  ExpectGradientMatches(16, 11, 3, 7, 1.0);  // 1 - SSIM only
  ExpectGradientMatches(9, 14, 2, 8, 0.5);
}

// Images smaller than the window: every window is cut by the zero padding on several sides.
TEST(PhotometricLoss, GradientMatchesFiniteDifferencesTinyImages) {
  ExpectGradientMatches(1, 1, 1, 9, 0.2);
  ExpectGradientMatches(3, 2, 2, 10, 0.2);
  ExpectGradientMatches(1, 12, 1, 11, 1.0);
  ExpectGradientMatches(12, 1, 3, 12, 1.0);
  ExpectGradientMatches(6, 5, 1, 13, 1.0);
}

// Tall enough for the separable filters to work in several bands of rows (at least 33 rows
// each): the rows around a band's edges are filtered by both bands.
TEST(PhotometricLoss, GradientMatchesFiniteDifferencesAcrossBands) {
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    ExpectGradientMatches(4, 80, 2, 31, 0.2);
  }
}

// The checker is sharp enough to see a wrong sign or a missing factor in the SSIM part.
TEST(PhotometricLoss, FiniteDifferenceCheckCatchesWrongGradients) {
  const Pair p = RandomPair(13, 9, 3, 14);
  std::vector<double> g_l1, g_ssim, g_both;
  Eval(p, 0.0, &g_l1);
  Eval(p, 1.0, &g_ssim);
  Eval(p, 0.2, &g_both);
  const std::vector<std::size_t> entries = AllEntries(p);
  const std::vector<double> numeric = NumericGradient(p, 0.2, entries);
  std::vector<double> good(g_l1.size()), flipped(g_l1.size()), doubled(g_l1.size());
  for (std::size_t i = 0; i < good.size(); ++i) {
    good[i] = 0.8 * g_l1[i] + 0.2 * g_ssim[i];
    flipped[i] = 0.8 * g_l1[i] - 0.2 * g_ssim[i];
    doubled[i] = 0.8 * g_l1[i] + 0.4 * g_ssim[i];
    EXPECT_NEAR(good[i], g_both[i], 1e-15);
  }
  EXPECT_EQ(Mismatches(good, numeric, entries), 0);
  EXPECT_GT(Mismatches(flipped, numeric, entries), static_cast<int>(entries.size()) / 2);
  EXPECT_GT(Mismatches(doubled, numeric, entries), static_cast<int>(entries.size()) / 2);
}

// A 1 x 1 image in closed form: every window sum keeps only the centre tap w = g0^2 of the 2-D
// window, so mu = w x, E[x^2] = w x^2, E[xy] = w x y.
TEST(PhotometricLoss, SinglePixelGoldenValue) {
  double sum = 0.0;
  for (int d = -5; d <= 5; ++d) sum += std::exp(-d * d / (2.0 * 1.5 * 1.5));
  const double w = 1.0 / (sum * sum);
  const double x = 0.7, y = 0.2, c1 = 1e-4, c2 = 9e-4;
  const double mx = w * x, my = w * y;
  const double vx = w * x * x - mx * mx, vy = w * y * y - my * my, cxy = w * x * y - mx * my;
  const double ssim =
      (2 * mx * my + c1) * (2 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
  const LossResult r = PhotometricLoss(&x, &y, 1, 1, 1, 0.2, nullptr);
  EXPECT_NEAR(r.ssim, ssim, 1e-15);
  EXPECT_NEAR(r.l1, 0.5, 1e-15);
  EXPECT_NEAR(r.value, 0.8 * 0.5 + 0.2 * (1.0 - ssim), 1e-15);
}

// The float path agrees with hdr4d::Ssim (core/metrics/metrics.h) and with the stated weighting.
TEST(PhotometricLoss, MatchesCoreSsimAndWeighting) {
  struct Shape {
    int w, h, c;
  };
  for (const Shape s : {Shape{200, 200, 3}, Shape{37, 23, 4}, Shape{5, 40, 1}}) {
    const Image a = testing::RandomImage(s.w, s.h, s.c, 21);
    const Image b = testing::RandomImage(s.w, s.h, s.c, 22);
    const LossResult r =
        PhotometricLoss(a.data(), b.data(), s.w, s.h, s.c, kDefaultLambdaDssim, nullptr);
    EXPECT_NEAR(r.ssim, Ssim(a, b), 1e-6) << a.ShapeString();
    double l1 = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) l1 += std::abs(double{a.data()[i]} - b.data()[i]);
    l1 /= static_cast<double>(a.size());
    EXPECT_NEAR(r.l1, l1, 1e-9);
    EXPECT_NEAR(r.value, 0.8 * r.l1 + 0.2 * (1.0 - r.ssim), 1e-7);
  }
  // A smooth, nearly equal pair, where SSIM is close to 1.
  Image a(64, 48, 3), b(64, 48, 3);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < 3; ++c) {
        a.at(x, y, c) = 0.5f + 0.3f * std::sin(0.1f * x + 0.2f * y + c);
        b.at(x, y, c) = a.at(x, y, c) + 0.02f * std::cos(0.3f * x - 0.1f * y);
      }
    }
  }
  const LossResult r = PhotometricLoss(a.data(), b.data(), 64, 48, 3, 0.2f, nullptr);
  EXPECT_NEAR(r.ssim, Ssim(a, b), 1e-6);
}

// The float kernels compute the same gradient as the double ones, to float precision.
TEST(PhotometricLoss, FloatGradientMatchesDouble) {
  const Pair p = RandomPair(45, 31, 3, 23);
  std::vector<float> pf(p.pred.begin(), p.pred.end()), gf(p.gt.begin(), p.gt.end());
  std::vector<double> pd(pf.begin(), pf.end()), gd(gf.begin(), gf.end());
  std::vector<float> grad_f(pf.size());
  std::vector<double> grad_d(pd.size());
  const LossResult rf = PhotometricLoss(pf.data(), gf.data(), 45, 31, 3, 0.2f, grad_f.data());
  const LossResult rd = PhotometricLoss(pd.data(), gd.data(), 45, 31, 3, 0.2, grad_d.data());
  EXPECT_NEAR(rf.value, rd.value, 1e-6);
  double max_abs = 0.0;
  for (double g : grad_d) max_abs = std::max(max_abs, std::abs(g));
  for (std::size_t i = 0; i < grad_d.size(); ++i) {
    EXPECT_NEAR(grad_f[i], grad_d[i], 1e-4 * max_abs) << i;
  }
}

TEST(PhotometricLoss, IdenticalImagesHaveZeroLossAndGradient) {
  const Pair p = RandomPair(17, 13, 3, 24);
  Pair same = p;
  same.gt = same.pred;
  std::vector<double> grad;
  const LossResult r = Eval(same, 0.2, &grad);
  EXPECT_NEAR(r.ssim, 1.0, 1e-14);
  EXPECT_EQ(r.l1, 0.0);
  EXPECT_NEAR(r.value, 0.0, 1e-14);
  // SSIM is maximal there, so its gradient vanishes; L1's subgradient at 0 is 0.
  for (double g : grad) EXPECT_NEAR(g, 0.0, 1e-14);
}

// sign(0) = 0 for L1, and the L1 gradient is exactly +-(1 - lambda) / count elsewhere.
TEST(PhotometricLoss, L1SubgradientIsZeroWherePredEqualsGt) {
  std::vector<float> pred = {0.1f, 0.5f, 0.9f, 0.3f, 0.3f, 0.0f};
  std::vector<float> gt = {0.2f, 0.5f, 0.1f, 0.3f, 0.4f, 0.0f};
  std::vector<float> grad(6, 123.0f);
  const LossResult r = PhotometricLoss(pred.data(), gt.data(), 3, 2, 1, 0.0f, grad.data());
  EXPECT_NEAR(r.value, (0.1 + 0.8 + 0.1) / 6.0, 1e-7);
  const float w = 1.0f / 6.0f;
  EXPECT_EQ(grad, (std::vector<float>{-w, 0.0f, w, 0.0f, -w, 0.0f}));
}

TEST(PhotometricLoss, GradientIsOverwrittenNotAccumulated) {
  const Image a = testing::RandomImage(30, 20, 3, 25);
  const Image b = testing::RandomImage(30, 20, 3, 26);
  std::vector<float> clean(a.size(), 0.0f), dirty(a.size(), std::nanf(""));
  PhotometricLoss(a.data(), b.data(), 30, 20, 3, 0.2f, clean.data());
  PhotometricLoss(a.data(), b.data(), 30, 20, 3, 0.2f, dirty.data());
  EXPECT_EQ(clean, dirty);
}

// Value and gradient are bit-identical at any thread count and do not depend on what earlier
// calls (of other sizes) left in the reused working memory.
TEST(PhotometricLoss, BitIdenticalAtAnyThreadCount) {
  const Image a = testing::RandomImage(200, 200, 3, 27);
  const Image b = testing::RandomImage(200, 200, 3, 28);
  auto run = [&](int threads) {
    ThreadLimit limit(threads);
    std::vector<float> grad(a.size());
    const LossResult r = PhotometricLoss(a.data(), b.data(), 200, 200, 3, 0.2f, grad.data());
    return std::make_pair(r, grad);
  };
  const auto [r1, g1] = run(1);
  {
    const Image c = testing::RandomImage(310, 7, 5, 29);
    std::vector<float> scratch(c.size());
    PhotometricLoss(c.data(), c.data(), 310, 7, 5, 0.5f, scratch.data());
  }
  for (int threads : {2, 0, 3}) {
    const auto [r, g] = run(threads);
    EXPECT_EQ(r.value, r1.value) << threads;
    EXPECT_EQ(r.ssim, r1.ssim) << threads;
    EXPECT_EQ(r.l1, r1.l1) << threads;
    EXPECT_TRUE(g == g1) << threads;
  }
  // The value does not depend on whether the gradient is requested.
  const LossResult no_grad = PhotometricLoss(a.data(), b.data(), 200, 200, 3, 0.2f, nullptr);
  EXPECT_NEAR(no_grad.value, r1.value, 1e-12);
}

}  // namespace
}  // namespace hdr4d::method
