#include "method/tonemap/tone_curve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

template <typename T>
struct Curve {
  ToneCurveShape shape;
  std::vector<T> params, f;
};

// Torch init with every weight scaled by `scale` (a trained curve is steeper than a fresh one);
// `flat_units` hidden units get a zero x-weight (a constant unit, on or off).
template <typename T>
Curve<T> RandomCurve(int hidden, int d, unsigned seed, double scale, int flat_units = 0) {
  Curve<T> c;
  c.shape = {d, hidden};
  c.params.resize(c.shape.NumParams());
  MlpInit(c.shape.Mlp(), seed, c.params.data());
  for (T& p : c.params) p *= T(scale);
  for (int o = 0; o < flat_units; ++o) c.params[o * (1 + d)] = T(0);
  std::mt19937 rng(seed + 1000);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < d; ++k) c.f.push_back(T(u(rng)));
  return c;
}

// The network's pre-sigmoid output on [x, f] through MlpForward (the reference).
template <typename T>
double MlpPreSigmoid(const Curve<T>& c, double x) {
  MlpShape lin = c.shape.Mlp();
  lin.output = MlpOutput::kLinear;
  std::vector<double> p(c.params.begin(), c.params.end()), in = {x}, cache(lin.CacheSize());
  for (T v : c.f) in.push_back(double(v));
  double z;
  MlpForward(lin, p.data(), in.data(), &z, cache.data());
  return z;
}

TEST(ToneCurve, DirectIsTheMlpOnXAndContext) {
  const Curve<float> c = RandomCurve<float>(64, 2, 1, 1.0);
  FrameToneCurve<float> curve;
  curve.Prepare(c.shape, c.params.data(), c.f.data(), 0);
  EXPECT_EQ(curve.nodes(), 0);
  std::vector<float> scratch(curve.DirectScratchSize()), cache(c.shape.Mlp().CacheSize());
  for (float x : {-30.0f, -3.0f, 0.0f, 0.7f, 12.0f}) {
    const float in[3] = {x, c.f[0], c.f[1]};
    float y;
    MlpForward(c.shape.Mlp(), c.params.data(), in, &y, cache.data());
    EXPECT_EQ(curve.Direct(x, scratch.data()), y) << x;
  }
}

// The piecewise-linear form is the network itself, inside and far outside the table range,
// including constant hidden units.
TEST(ToneCurve, PiecewiseLinearFormIsExact) {
  for (int flat : {0, 5}) {
    const Curve<double> c = RandomCurve<double>(64, 2, 2 + flat, 3.0, flat);
    FrameToneCurve<double> curve;
    curve.Prepare(c.shape, c.params.data(), c.f.data(), 257);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-60, 60);
    for (int i = 0; i < 2000; ++i) {
      const double x = u(rng), z = MlpPreSigmoid(c, x);
      ASSERT_NEAR(curve.PiecewiseLinear(x), z, 1e-10 * (1 + std::abs(z))) << x;
    }
    for (int j = 0; j < curve.nodes(); ++j) {
      const double z = MlpPreSigmoid(c, curve.NodeX(j));
      ASSERT_NEAR(curve.node_values()[j], z, 1e-10 * (1 + std::abs(z))) << j;
    }
  }
}

// The tabulated curve against the direct MLP (float, 1024 nodes, the default), over random x in
// the table's range, for fresh and steeper (trained-looking) weights and random contexts.
TEST(ToneCurve, TabulatedErrorIsBounded) {
  double worst = 0;
  for (double scale : {1.0, 2.0, 4.0}) {
    double worst_scale = 0, steepest = 0;
    for (unsigned seed = 0; seed < 6; ++seed) {
      const Curve<float> c = RandomCurve<float>(64, 2, 10 + seed, scale);
      FrameToneCurve<float> curve;
      curve.Prepare(c.shape, c.params.data(), c.f.data(), 1024);
      std::vector<float> scratch(curve.DirectScratchSize());
      std::mt19937 rng(seed);
      std::uniform_real_distribution<float> u{float(kTableXMin), float(kTableXMax)};
      for (int i = 0; i < 4000; ++i) {
        const float x = u(rng);
        ASSERT_TRUE(curve.InTable(x));
        int j;
        float w;
        curve.Locate(x, &j, &w);
        ASSERT_GE(w, 0.0f);
        ASSERT_LE(w, 1.0001f);  // rounding of 1 / step may overshoot the last node a little
        const float y = StableSigmoid(curve.TablePreSigmoid(j, w));
        worst_scale = std::max(worst_scale, double(std::abs(y - curve.Direct(x, scratch.data()))));
        steepest = std::max(steepest, double(std::abs(curve.TableSlope(j))));
      }
    }
    std::printf("scale %g: max |dy| %.3g, max |dz/dx| %.3g\n", scale, worst_scale, steepest);
    if (scale == 1.0) {
      EXPECT_LT(worst_scale, 2.5e-4);  // fresh weights (measured 7.5e-5)
    }
    worst = std::max(worst, worst_scale);
  }
  // Curves as steep as dz/dx ~ 10 (0 -> 1 within half a stop) stay within one 8-bit level
  // (measured 2.8e-3).
  EXPECT_LT(worst, 1.0 / 255);
  EXPECT_GT(worst, 0.0);  // kinks inside intervals exist: the check measures something
}

// dL/dparams, dL/df and dL/dx of the table path against central differences (double). Values
// sit away from nodes so that the step never crosses one.
TEST(ToneCurve, TableGradientsMatchFiniteDifferences) {
  for (int flat : {0, 3}) {
    const Curve<double> c = RandomCurve<double>(12, 2, 20 + flat, 2.0, flat);
    const int nodes = 48;
    const double step = (kTableXMax - kTableXMin) / (nodes - 1);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(0.05, 0.95), wdist(-1, 1);
    std::vector<double> xs, ws;
    for (int i = 0; i < 60; ++i) {
      xs.push_back(kTableXMin + (int(u(rng) * (nodes - 1)) + u(rng)) * step);
      ws.push_back(wdist(rng));
    }
    auto loss = [&](const std::vector<double>& params, const std::vector<double>& f,
                    const std::vector<double>& x) {
      FrameToneCurve<double> curve;
      curve.Prepare(c.shape, params.data(), f.data(), nodes);
      double l = 0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        int j;
        double w;
        curve.Locate(x[i], &j, &w);
        l += ws[i] * StableSigmoid(curve.TablePreSigmoid(j, w));
      }
      return l;
    };
    FrameToneCurve<double> curve;
    curve.Prepare(c.shape, c.params.data(), c.f.data(), nodes);
    std::vector<double> dz_nodes(nodes, 0.0), dx(xs.size());
    for (std::size_t i = 0; i < xs.size(); ++i) {
      int j;
      double w;
      curve.Locate(xs[i], &j, &w);
      const double y = StableSigmoid(curve.TablePreSigmoid(j, w));
      const double dz = ws[i] * y * (1 - y);
      dz_nodes[j] += dz * (1 - w);
      dz_nodes[j + 1] += dz * w;
      dx[i] = dz * curve.TableSlope(j);
    }
    std::vector<double> dp(c.params.size(), 0.0), df(2, 0.0);
    curve.TableBackward(dz_nodes.data(), dp.data(), df.data());

    auto vec = [](const FdVector& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
    auto map = [](const std::vector<double>& v) {
      return FdVector(Eigen::Map<const FdVector>(v.data(), v.size()));
    };
    ExpectGradientsMatch(map(dp),
                         NumericGradient([&](const FdVector& p) { return loss(vec(p), c.f, xs); },
                                         map(c.params), 1e-6),
                         1e-6);
    ExpectGradientsMatch(
        map(df),
        NumericGradient([&](const FdVector& f) { return loss(c.params, vec(f), xs); }, map(c.f),
                        1e-6),
        1e-6);
    // Per value: the loss is separable in x.
    const FdVector num_x = NumericGradient(
        [&](const FdVector& x) { return loss(c.params, c.f, vec(x)); }, map(xs), 1e-7);
    ExpectGradientsMatch(map(dx), num_x, 1e-6);
  }
}

// FirstLayersBackward (FrameToneCurve's private share of TableBackward: the first two layers'
// weights W1, b1, W2 and the context f, through the per-unit prefix and suffix sums over the
// segments) driven through TableBackward from a random gradient on every node value, against
// central differences in double of the node values Prepare builds. The other paths of
// TableBackward (b2, w3, b3) are checked by TableGradientsMatchFiniteDifferences above.
TEST(ToneCurve, FirstLayersBackwardMatchesFiniteDifferences) {
  for (int flat : {0, 3}) {  // with constant units (a = 0, on or off) too
    SCOPED_TRACE(flat);
    const Curve<double> c = RandomCurve<double>(10, 2, 40 + flat, 2.0, flat);
    const int nodes = 37, H = c.shape.hidden, in = 1 + c.shape.context_size;
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<double> dz(nodes);
    for (double& g : dz) g = u(rng);
    auto loss = [&](const std::vector<double>& params, const std::vector<double>& f) {
      FrameToneCurve<double> curve;
      curve.Prepare(c.shape, params.data(), f.data(), nodes);
      double l = 0;
      for (int j = 0; j < nodes; ++j) l += dz[j] * curve.node_values()[j];
      return l;
    };
    FrameToneCurve<double> curve;
    curve.Prepare(c.shape, c.params.data(), c.f.data(), nodes);
    std::vector<double> dp(c.params.size(), 0.0), df(c.f.size(), 0.0);
    curve.TableBackward(dz.data(), dp.data(), df.data());
    // W1 (H x in), b1 (H), W2 (H x H): the layout's first block.
    const std::size_t count = std::size_t(H) * in + H + std::size_t(H) * H;
    const FdVector p0 = Eigen::Map<const FdVector>(c.params.data(), count);
    const FdVector numeric_p = NumericGradient(
        [&](const FdVector& head) {
          std::vector<double> p = c.params;
          std::copy(head.data(), head.data() + count, p.begin());
          return loss(p, c.f);
        },
        p0, 1e-6);
    ExpectGradientsMatch(Eigen::Map<const FdVector>(dp.data(), count), numeric_p, 1e-6);
    const FdVector numeric_f = NumericGradient(
        [&](const FdVector& f) { return loss(c.params, {f.data(), f.data() + f.size()}); },
        Eigen::Map<const FdVector>(c.f.data(), c.f.size()), 1e-6);
    ExpectGradientsMatch(Eigen::Map<const FdVector>(df.data(), df.size()), numeric_f, 1e-6);
  }
}

TEST(ToneCurve, DirectGradientsMatchFiniteDifferences) {
  const Curve<double> c = RandomCurve<double>(16, 3, 30, 2.0);
  FrameToneCurve<double> curve;
  curve.Prepare(c.shape, c.params.data(), c.f.data(), 0);
  const std::vector<double> xs = {-7.3, -0.4, 0.9, 3.3, 15.1};
  auto loss = [&](const std::vector<double>& params, const std::vector<double>& f,
                  const std::vector<double>& x) {
    FrameToneCurve<double> k;
    k.Prepare(c.shape, params.data(), f.data(), 0);
    std::vector<double> s(k.DirectScratchSize());
    double l = 0;
    for (std::size_t i = 0; i < x.size(); ++i) l += (i + 1.0) * k.Direct(x[i], s.data());
    return l;
  };
  std::vector<double> s(curve.DirectScratchSize()), dp(c.params.size(), 0.0), df(3, 0.0),
      dx(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) {
    curve.Direct(xs[i], s.data());
    dx[i] = curve.DirectBackward(i + 1.0, s.data(), dp.data(), df.data());
  }
  auto vec = [](const FdVector& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  auto map = [](const std::vector<double>& v) {
    return FdVector(Eigen::Map<const FdVector>(v.data(), v.size()));
  };
  ExpectGradientsMatch(map(dp),
                       NumericGradient([&](const FdVector& p) { return loss(vec(p), c.f, xs); },
                                       map(c.params), 1e-6),
                       1e-6);
  ExpectGradientsMatch(
      map(df),
      NumericGradient([&](const FdVector& f) { return loss(c.params, vec(f), xs); }, map(c.f),
                      1e-6),
      1e-6);
  ExpectGradientsMatch(
      map(dx),
      NumericGradient([&](const FdVector& x) { return loss(c.params, c.f, vec(x)); }, map(xs),
                      1e-6),
      1e-6);
}

TEST(ToneCurve, LocateCoversTheRangeEnds) {
  const Curve<float> c = RandomCurve<float>(8, 2, 40, 1.0);
  FrameToneCurve<float> curve;
  curve.Prepare(c.shape, c.params.data(), c.f.data(), 5);
  int j;
  float w;
  curve.Locate(float(kTableXMin), &j, &w);
  EXPECT_EQ(j, 0);
  EXPECT_EQ(w, 0.0f);
  curve.Locate(float(kTableXMax), &j, &w);
  EXPECT_EQ(j, 3);  // the last interval, weight 1 on the last node
  EXPECT_FLOAT_EQ(w, 1.0f);
  EXPECT_FLOAT_EQ(curve.TablePreSigmoid(j, w), curve.node_values()[4]);
  EXPECT_FALSE(curve.InTable(std::nextafter(float(kTableXMax), 100.0f)));
  EXPECT_FALSE(curve.InTable(std::nextafter(float(kTableXMin), -100.0f)));
  EXPECT_FALSE(curve.InTable(std::nanf("")));
}

TEST(ToneCurve, ExtremeInputsStayFiniteAndInRange) {
  const Curve<float> c = RandomCurve<float>(64, 2, 50, 4.0);
  FrameToneCurve<float> curve;
  curve.Prepare(c.shape, c.params.data(), c.f.data(), 1024);
  std::vector<float> s(curve.DirectScratchSize()), dp(c.params.size(), 0.0f), df(2, 0.0f);
  for (float x : {-1e6f, -60.0f, -24.0f, 0.0f, 22.0f, 60.0f, 1e6f}) {
    const float y = curve.Direct(x, s.data());
    EXPECT_TRUE(y >= 0.0f && y <= 1.0f) << x;
    const float dx = curve.DirectBackward(1.0f, s.data(), dp.data(), df.data());
    EXPECT_TRUE(std::isfinite(dx)) << x;
  }
  for (float v : dp) ASSERT_TRUE(std::isfinite(v));
  for (float v : df) ASSERT_TRUE(std::isfinite(v));
  for (float z : curve.node_values()) ASSERT_TRUE(std::isfinite(z));
}

}  // namespace
}  // namespace hdr4d::method
