#include "baselines/static_mlp_tone_mapper.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "baselines/static_mlp_curve.h"
#include "baselines/test_util.h"
#include "core/util/parallel.h"
#include "method/optim/adam.h"
#include "method/tonemap/monotone_mlp.h"
#include "method/tonemap/tone_curve_samples.h"

namespace hdr4d::baselines {
namespace {

using namespace testing;  // baselines/test_util.h

method::ToneMapperConfig Config(std::uint64_t seed = 3,
                                bool tabulated = true,
                                bool monotone = true) {
  method::ToneMapperConfig config;
  config.kind = "mlp";
  config.seed = seed;
  config.tabulated = tabulated;
  config.monotone_curves = monotone;
  return config;
}

// HDR-GS's free network (the reference's), which tests compare with the plain MLP functions.
method::ToneMapperConfig FreeConfig(std::uint64_t seed = 3) { return Config(seed, true, false); }

std::vector<double> DoubleParams(const StaticMlpToneMapper& mapper) {
  auto& p = const_cast<StaticMlpToneMapper&>(mapper).params();
  return std::vector<double>(p.begin(), p.end());
}

TEST(StaticMlpToneMapper, HasHdrGsShapeAndLearningRate) {
  StaticMlpToneMapper mapper(Config());
  EXPECT_EQ(StaticMlpShape().widths, (std::vector<int>{1, 128, 1}));
  EXPECT_EQ(mapper.params().size(), 3u * (128 + 128 + 128 + 1));
  EXPECT_EQ(mapper.grads().size(), mapper.params().size());
  EXPECT_TRUE(mapper.pointwise());
  EXPECT_FLOAT_EQ(mapper.learning_rate(), 5e-4f);
}

TEST(StaticMlpToneMapper, EachChannelIsItsOwnNetworkOfLogHdrPlusLogExposure) {
  StaticMlpToneMapper mapper(FreeConfig());
  const float log_e = 0.75f;
  mapper.BeginFrame({0, -1, log_e});
  const std::vector<float> log_hdr = {-1.f, 0.2f, 2.f, 0.5f, -3.f, 1.f};
  std::vector<float> ldr(6);
  mapper.Map(log_hdr.data(), 2, ldr.data());
  const auto& shape = StaticMlpShape();
  std::vector<float> cache(shape.CacheSize());
  for (int k = 0; k < 6; ++k) {
    const float x = log_hdr[k] + log_e;
    float y;
    method::MlpForward(shape, mapper.params().data() + (k % 3) * shape.NumParams(), &x, &y,
                       cache.data());
    EXPECT_NEAR(ldr[k], y, 1e-6) << k;
  }
  // Different seeds per channel: the three curves differ.
  EXPECT_NE(std::memcmp(mapper.params().data(), mapper.params().data() + shape.NumParams(),
                        shape.NumParams() * sizeof(float)),
            0);
  // And the same seed gives the same weights; another seed others.
  EXPECT_EQ(StaticMlpToneMapper(Config(3)).params(), mapper.params());
  EXPECT_NE(StaticMlpToneMapper(Config(4)).params(), mapper.params());
}

// The default monotone mapper is the free network on the effective weights (monotone_mlp.h),
// its parameter gradient goes through |p| to the stored weights, and its curves never decrease.
TEST(StaticMlpToneMapper, MonotoneIsTheFreeNetworkOnEffectiveWeights) {
  for (bool tabulated : {true, false}) {
    SCOPED_TRACE(tabulated);
    StaticMlpToneMapper monotone(Config(5, tabulated, true));
    StaticMlpToneMapper free(Config(5, tabulated, false));
    ASSERT_EQ(monotone.params(), free.params());
    const std::size_t per_channel = StaticMlpShape().NumParams();
    for (int c = 0; c < 3; ++c) {
      method::MonotoneEffective(StaticMlpShape(), monotone.params().data() + c * per_channel,
                                free.params().data() + c * per_channel);
    }
    const std::size_t n = 200;
    const std::vector<float> log_hdr = Uniform<float>(3 * n, -6, 6, 21);
    const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 22);
    std::vector<float> a(3 * n), b(3 * n), da(3 * n), db(3 * n);
    for (StaticMlpToneMapper* m : {&monotone, &free}) m->BeginFrame({0, -1, -0.5f});
    monotone.Map(log_hdr.data(), n, a.data());
    free.Map(log_hdr.data(), n, b.data());
    EXPECT_EQ(a, b);
    monotone.MapBackward(log_hdr.data(), n, dL.data(), da.data());
    free.MapBackward(log_hdr.data(), n, dL.data(), db.data());
    EXPECT_EQ(da, db);
    std::vector<float> chained(monotone.params().size(), 0.0f);
    for (int c = 0; c < 3; ++c) {
      method::MonotoneGradientAdd(StaticMlpShape(), monotone.params().data() + c * per_channel,
                                  free.grads().data() + c * per_channel,
                                  chained.data() + c * per_channel);
    }
    EXPECT_EQ(monotone.grads(), chained);
    // Non-decreasing over the whole table range, for a random start far from monotone.
    const std::size_t m = 2000;
    std::vector<float> grid(3 * m), y(3 * m);
    for (std::size_t i = 0; i < m; ++i)
      for (int c = 0; c < 3; ++c) grid[3 * i + c] = -25.0f + 50.0f * float(i) / float(m - 1);
    monotone.Map(grid.data(), m, y.data());
    for (std::size_t i = 1; i < m; ++i)
      for (int c = 0; c < 3; ++c) ASSERT_GE(y[3 * i + c], y[3 * (i - 1) + c]) << i;
  }
}

// Both evaluations, as function pointers of the same signature.
struct Path {
  const char* name;
  void (*forward)(const double*, double, const double*, std::size_t, double*);
  void (*backward)(
      const double*, double, const double*, std::size_t, const double*, double*, double*);
};
const Path kPaths[] = {
    {"direct", StaticMlpForward<double>, StaticMlpBackward<double>},
    {"piecewise", StaticMlpForwardPiecewise<double>, StaticMlpBackwardPiecewise<double>}};

TEST(StaticMlpToneMapper, BackwardMatchesFiniteDifferencesInInputsAndParameters) {
  StaticMlpToneMapper mapper(Config());
  const std::vector<double> params = DoubleParams(mapper);
  const std::size_t n = 5;
  const double log_e = -0.4;
  const std::vector<double> log_hdr = Uniform(3 * n, -3.0, 3.0, 11);
  const std::vector<double> weights = Uniform(3 * n, -1.0, 1.0, 12);
  for (const Path& path : kPaths) {
    SCOPED_TRACE(path.name);
    std::vector<double> d_log_hdr(3 * n), d_params(params.size(), 0.0);
    path.backward(params.data(), log_e, log_hdr.data(), n, weights.data(), d_log_hdr.data(),
                  d_params.data());
    ExpectFdMatch(
        [&](const std::vector<double>& v) {
          std::vector<double> ldr(3 * n);
          path.forward(params.data(), log_e, v.data(), n, ldr.data());
          return Dot(weights, ldr);
        },
        log_hdr, d_log_hdr);
    ExpectFdMatch(
        [&](const std::vector<double>& p) {
          std::vector<double> ldr(3 * n);
          path.forward(p.data(), log_e, log_hdr.data(), n, ldr.data());
          return Dot(weights, ldr);
        },
        params, d_params);
  }
}

// The piecewise-linear form is the same function with the same gradient, including hidden units
// with a zero input weight (always on or always off) and inputs beyond every switch point.
TEST(StaticMlpToneMapper, PiecewiseLinearFormEqualsTheDirectNetwork) {
  StaticMlpToneMapper mapper(Config(9));
  std::vector<double> params = DoubleParams(mapper);
  params[0] = 0.0, params[128] = 0.3;   // channel 0, unit 0: w = 0, b > 0 (always on)
  params[1] = 0.0, params[129] = -0.2;  // unit 1: w = 0, b < 0 (always off)
  const std::size_t n = 400;
  std::vector<double> log_hdr = Uniform(3 * n, -30.0, 30.0, 13);
  log_hdr[0] = -std::numeric_limits<double>::infinity();
  log_hdr[4] = 1e9;
  const std::vector<double> dL = Uniform(3 * n, -1.0, 1.0, 14);
  std::vector<double> out[2], d_in[2], d_params[2];
  for (int k = 0; k < 2; ++k) {
    out[k].resize(3 * n);
    d_in[k].resize(3 * n);
    d_params[k].assign(params.size(), 0.0);
    kPaths[k].forward(params.data(), 0.7, log_hdr.data(), n, out[k].data());
    kPaths[k].backward(params.data(), 0.7, log_hdr.data(), n, dL.data(), d_in[k].data(),
                       d_params[k].data());
  }
  for (std::size_t k = 0; k < 3 * n; ++k) {
    EXPECT_NEAR(out[1][k], out[0][k], 1e-13) << k;
    EXPECT_NEAR(d_in[1][k], d_in[0][k], 1e-12) << k;
  }
  for (std::size_t k = 0; k < params.size(); ++k) {
    EXPECT_NEAR(d_params[1][k], d_params[0][k], 1e-11 * (1 + std::abs(d_params[0][k]))) << k;
  }
  EXPECT_NE(d_params[0][128], 0.0);  // the always-on unit learns
  EXPECT_EQ(d_params[0][129], 0.0);  // the always-off one does not
  EXPECT_EQ(d_params[1][129], 0.0);
}

// The bucketed lookup finds the same segment as a binary search (the number of switch points
// below x), also for values exactly on a switch point, next to one, or outside them all.
TEST(StaticMlpCurve, SegmentLookupCountsTheSwitchPointsBelow) {
  StaticMlpToneMapper mapper(Config(21));
  const float* p = mapper.params().data();
  const StaticMlpCurve<float> curve(p, kStaticMlpHidden);
  std::vector<float> at;
  for (int j = 0; j < kStaticMlpHidden; ++j) at.push_back(float(-double(p[128 + j]) / p[j]));
  std::sort(at.begin(), at.end());
  ASSERT_EQ(curve.segments(), kStaticMlpHidden + 1);
  std::vector<float> xs = Uniform<float>(20000, at.front() - 1, at.back() + 1, 3);
  for (float t : at) {
    xs.insert(xs.end(), {t, std::nextafter(t, -1e30f), std::nextafter(t, 1e30f)});
  }
  xs.insert(xs.end(), {-1e30f, 1e30f, 0.f});
  for (float x : xs) {
    const int expected = int(std::lower_bound(at.begin(), at.end(), x) - at.begin());
    ASSERT_EQ(curve.Segment(x), expected) << x;
  }
}

TEST(StaticMlpToneMapper, TabulatedSwitchSelectsAnEquivalentPath) {
  StaticMlpToneMapper fast(Config(3, true)), direct(Config(3, false));
  const std::size_t n = 2000;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -8, 8, 15);
  const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 16);
  std::vector<float> y[2], d[2];
  StaticMlpToneMapper* mappers[2] = {&fast, &direct};
  for (int k = 0; k < 2; ++k) {
    y[k].resize(3 * n);
    d[k].resize(3 * n);
    mappers[k]->BeginFrame({0, -1, 0.4f});
    mappers[k]->Map(log_hdr.data(), n, y[k].data());
    mappers[k]->MapBackward(log_hdr.data(), n, dL.data(), d[k].data());
  }
  for (std::size_t k = 0; k < 3 * n; ++k) {
    EXPECT_NEAR(y[0][k], y[1][k], 2e-6);
    EXPECT_NEAR(d[0][k], d[1][k], 2e-6);
  }
  for (std::size_t k = 0; k < fast.grads().size(); ++k) {
    EXPECT_NEAR(fast.grads()[k], direct.grads()[k], 1e-4 * (1 + std::abs(direct.grads()[k])));
  }
}

TEST(StaticMlpToneMapper, FloatAgreesWithDoubleAndGradientsAccumulate) {
  StaticMlpToneMapper mapper(FreeConfig());
  const std::size_t n = 300;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -4, 4, 5);
  const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 6);
  mapper.BeginFrame({0, -1, 0.3f});
  std::vector<float> ldr(3 * n), d_log_hdr(3 * n);
  mapper.Map(log_hdr.data(), n, ldr.data());
  mapper.MapBackward(log_hdr.data(), n, dL.data(), d_log_hdr.data());
  const std::vector<double> params = DoubleParams(mapper);
  const std::vector<double> log_hdr_d(log_hdr.begin(), log_hdr.end()), dL_d(dL.begin(), dL.end());
  std::vector<double> ldr_d(3 * n), d_log_hdr_d(3 * n), d_params_d(params.size(), 0.0);
  StaticMlpForward(params.data(), double(0.3f), log_hdr_d.data(), n, ldr_d.data());
  StaticMlpBackward(params.data(), double(0.3f), log_hdr_d.data(), n, dL_d.data(),
                    d_log_hdr_d.data(), d_params_d.data());
  for (std::size_t k = 0; k < 3 * n; ++k) {
    EXPECT_NEAR(ldr[k], ldr_d[k], 1e-6);
    EXPECT_NEAR(d_log_hdr[k], d_log_hdr_d[k], 1e-5);
  }
  for (std::size_t k = 0; k < params.size(); ++k) {
    EXPECT_NEAR(mapper.grads()[k], d_params_d[k], 1e-4 * (1 + std::abs(d_params_d[k])));
  }
  // Parameter gradients are added, not overwritten; a null input gradient is allowed.
  const std::vector<float> once = mapper.grads();
  mapper.MapBackward(log_hdr.data(), n, dL.data(), nullptr);
  for (std::size_t k = 0; k < once.size(); ++k) {
    EXPECT_NEAR(mapper.grads()[k], 2 * once[k], 1e-5 * (1 + std::abs(once[k])));
  }
}

TEST(StaticMlpToneMapper, RadianceAndExposureEnterOnlyThroughTheirSum) {
  StaticMlpToneMapper mapper(Config());
  const std::vector<float> log_hdr = Uniform<float>(30, -5, 5, 8);
  std::vector<float> brighter(log_hdr), a(30), b(30);
  for (float& v : brighter) v += 1.5f;
  mapper.BeginFrame({0, -1, 1.5f});
  mapper.Map(log_hdr.data(), 10, a.data());
  mapper.BeginFrame({0, -1, 0.f});
  mapper.Map(brighter.data(), 10, b.data());
  for (int k = 0; k < 30; ++k) EXPECT_NEAR(a[k], b[k], 1e-6);
  // ... and it does respond to them (a tautology would pass with a constant curve).
  mapper.BeginFrame({0, -1, -2.f});
  mapper.Map(log_hdr.data(), 10, b.data());
  EXPECT_GT(std::abs(a[0] - b[0]), 1e-4);
}

TEST(StaticMlpToneMapper, ExtremeAndInfiniteInputsStayFiniteInUnitRange) {
  StaticMlpToneMapper mapper(Config());
  std::vector<float> log_hdr;
  for (double r = 1e-6; r <= 1e6 * 1.0001; r *= 10) {
    log_hdr.insert(log_hdr.end(), {float(std::log(r)), float(std::log(r)), 0.f});
  }
  const float inf = std::numeric_limits<float>::infinity();
  log_hdr.insert(log_hdr.end(), {-inf, inf, -inf});
  const std::size_t n = log_hdr.size() / 3;
  std::vector<float> ldr(3 * n), d_log_hdr(3 * n), dL(3 * n, 1.f);
  for (double exposure : {1e-4, 1e-2, 1.0, 1e2, 1e3}) {
    mapper.BeginFrame({0, -1, float(std::log(exposure))});
    mapper.Map(log_hdr.data(), n, ldr.data());
    mapper.MapBackward(log_hdr.data(), n, dL.data(), d_log_hdr.data());
    EXPECT_TRUE(AllFiniteIn01(ldr)) << exposure;
    EXPECT_TRUE(AllFinite(d_log_hdr)) << exposure;
    EXPECT_TRUE(AllFinite(mapper.grads())) << exposure;
    // log 0 is clamped: no gradient flows into an infinite input.
    EXPECT_EQ(d_log_hdr[3 * (n - 1)], 0.f);
    EXPECT_EQ(d_log_hdr[3 * (n - 1) + 1], 0.f);
  }
  // Saturated sigmoids: huge weights push every output to 0 or 1, still finite.
  for (float& p : mapper.params()) p *= 1e4f;
  mapper.ZeroGrad();
  mapper.Map(log_hdr.data(), n, ldr.data());
  mapper.MapBackward(log_hdr.data(), n, dL.data(), d_log_hdr.data());
  EXPECT_TRUE(AllFiniteIn01(ldr));
  EXPECT_TRUE(AllFinite(d_log_hdr));
  EXPECT_TRUE(AllFinite(mapper.grads()));
}

class StaticMlpThreads : public ::testing::TestWithParam<bool> {};

TEST_P(StaticMlpThreads, GradientsAreIdenticalAtAnyThreadCount) {
  StaticMlpToneMapper mapper(Config(3, GetParam()));
  const std::size_t n = 5000;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -6, 6, 1);
  const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 2);
  mapper.BeginFrame({0, -1, 0.1f});
  std::vector<std::vector<float>> grads, d_inputs;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    mapper.ZeroGrad();
    std::vector<float> d(3 * n);
    mapper.MapBackward(log_hdr.data(), n, dL.data(), d.data());
    grads.push_back(mapper.grads());
    d_inputs.push_back(d);
  }
  EXPECT_EQ(std::memcmp(grads[0].data(), grads[1].data(), grads[0].size() * sizeof(float)), 0);
  EXPECT_EQ(d_inputs[0], d_inputs[1]);
}

INSTANTIATE_TEST_SUITE_P(TabulatedAndDirect, StaticMlpThreads, ::testing::Bool());

// Free (as HDR-GS) or monotone, its gradient teaches it a camera curve: a few hundred Adam steps
// on a clipped gamma target.
class StaticMlpLearns : public ::testing::TestWithParam<bool> {};

TEST_P(StaticMlpLearns, ACameraCurveFromItsGradient) {
  StaticMlpToneMapper mapper(Config(7, true, GetParam()));
  const std::size_t n = 64;
  std::vector<float> log_hdr(3 * n), target(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const float x = -4.f + 8.f * float(i) / float(n - 1);
    for (int c = 0; c < 3; ++c) {
      log_hdr[3 * i + c] = x;
      target[3 * i + c] = std::pow(std::min(std::exp(x) * 0.1f, 1.f), 1.f / 2.2f);
    }
  }
  method::Adam adam;
  adam.AddGroup(
      {"tone", mapper.params().data(), mapper.grads().data(), mapper.params().size(), 0.01f});
  std::vector<float> ldr(3 * n), dL(3 * n);
  double mse = 0, initial_mse = 0;
  // 1500 steps: the monotone net needs more than the free one.
  for (int step = 0; step < 1500; ++step) {
    mapper.BeginFrame({0, -1, 0.f});  // the frame protocol: one frame per step
    mapper.Map(log_hdr.data(), n, ldr.data());
    mse = 0;
    for (std::size_t k = 0; k < 3 * n; ++k) {
      dL[k] = 2 * (ldr[k] - target[k]) / float(3 * n);
      mse += (ldr[k] - target[k]) * (ldr[k] - target[k]) / double(3 * n);
    }
    if (step == 0) initial_mse = mse;
    mapper.ZeroGrad();
    mapper.MapBackward(log_hdr.data(), n, dL.data(), nullptr);
    adam.Step();
  }
  // It learned: from its initial curve (the monotone one starts closer: an S over the range) to
  // the target, twenty times closer at least.
  EXPECT_GT(initial_mse, 5e-3);
  EXPECT_LT(mse, 2e-4);
  EXPECT_LT(mse, initial_mse / 20);
  // Monotonic in radiance (and so in exposure) over the trained range, on a finer grid.
  const std::size_t m = 400;
  std::vector<float> fine(3 * m), out(3 * m);
  for (std::size_t i = 0; i < m; ++i) {
    for (int c = 0; c < 3; ++c) fine[3 * i + c] = -3.5f + 7.f * float(i) / float(m - 1);
  }
  mapper.Map(fine.data(), m, out.data());
  for (std::size_t i = 1; i < m; ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_GE(out[3 * i + c], out[3 * (i - 1) + c] - 1e-3f) << i;
  }
}

// The trainer's check for a dead curve (method/train/tone_curve_watch.h): HDR-GS's free network
// with one channel's sigmoid driven far into saturation (every weight 0, the output bias 60) is
// flat at 1 over any range; a fresh network, free or monotone, is not.
TEST(StaticMlpToneMapper, FindFlatToneCurvesFindsTheSaturatedChannelsOnly) {
  for (bool monotone : {false, true}) {
    StaticMlpToneMapper fresh(Config(3, true, monotone));
    EXPECT_TRUE(method::FindFlatToneCurves(&fresh, 1, -8.0, 6.0).empty()) << monotone;
  }
  StaticMlpToneMapper mapper(FreeConfig());
  const std::size_t block = StaticMlpShape().NumParams();
  for (int c : {1, 2}) {  // green driven to 1, blue to 0
    std::fill_n(mapper.params().begin() + c * block, block, 0.0f);
    mapper.params()[(c + 1) * block - 1] = c == 1 ? 60.0f : -60.0f;  // the output bias
  }
  const std::vector<method::FlatToneCurve> flat =
      method::FindFlatToneCurves(&mapper, 1, -8.0, 6.0);
  ASSERT_EQ(flat.size(), 2u);
  EXPECT_EQ(flat[0].channel, 1);
  EXPECT_EQ(flat[0].time, 0.0);
  EXPECT_NEAR(flat[0].level, 1.0, 1e-6);
  EXPECT_LT(flat[0].spread, 1e-6);
  EXPECT_EQ(flat[1].channel, 2);
  EXPECT_NEAR(flat[1].level, 0.0, 1e-6);
  // An empty or reversed range judges nothing.
  EXPECT_TRUE(method::FindFlatToneCurves(&mapper, 1, 2.0, 2.0).empty());
  EXPECT_TRUE(method::FindFlatToneCurves(nullptr, 1, -8.0, 6.0).empty());
}

INSTANTIATE_TEST_SUITE_P(FreeAndMonotone, StaticMlpLearns, ::testing::Bool());

}  // namespace
}  // namespace hdr4d::baselines
