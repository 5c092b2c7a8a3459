#include "method/tonemap/dynamic_tone_mapper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/files/binary_stream.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/tonemap/dtm_core.h"
#include "tests/finite_difference.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using testing::ErrorOf;
using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

ToneMapperConfig Config(int num_times = 8) {
  ToneMapperConfig c;
  c.num_times = num_times;
  c.seed = 5;
  return c;
}

std::vector<float> RandomValues(std::size_t n, unsigned seed, float lo, float hi) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// A bank with rows written for every timestamp.
void FillBank(DynamicToneMapper& m, unsigned seed) {
  const std::vector<float> rows = RandomValues(3 * m.bank().size(), seed, -3, 2);
  for (int i = 0; i < m.bank().size(); ++i) m.ObserveMeanLogHdr(i, rows.data() + 3 * i);
}

// ---- The whole chain in double: window -> context learner -> f -> curves -> LDR ---------------

struct Chain {
  DtmShape shape;
  std::vector<double> params, window, log_hdr, weights;
  int length;
  double log_e = std::log(0.5);
};

// Log-HDR values whose x = log_hdr + log_e sits in the middle of a table interval (so a small
// step never crosses a node), plus a few outside the table (the direct fallback).
Chain MakeChain(
    ContextKind kind, int hidden, int nodes, int length, unsigned seed, bool monotone = false) {
  Chain c;
  c.shape.context = {kind, 2};
  c.shape.curve = {2, hidden, monotone};
  c.shape.window = 20;
  c.shape.table_nodes = nodes;
  c.length = length;
  DtmCore<double> core(c.shape);
  c.params.resize(c.shape.NumParams());
  core.Init(seed, c.params.data());
  for (std::size_t i = c.shape.CurveOffset(0); i < c.params.size(); ++i) c.params[i] *= 2.0;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.1, 0.9), row(-2, 1), w(-1, 1);
  for (int i = 0; i < 3 * length; ++i) c.window.push_back(row(rng));
  const int intervals = nodes >= 2 ? nodes - 1 : 200;
  const double step = (kTableXMax - kTableXMin) / intervals;
  for (int i = 0; i < 3 * 20; ++i) {
    // Most values in [-8, 6] where curves have their shape; a few anywhere in the table.
    const double lo = i % 7 == 0 ? kTableXMin : -8.0, hi = i % 7 == 0 ? kTableXMax : 6.0;
    const int j0 = int((lo - kTableXMin) / step), j1 = int((hi - kTableXMin) / step) - 1;
    const int j = j0 + int(u(rng) * (j1 - j0));
    c.log_hdr.push_back(kTableXMin + (j + u(rng)) * step - c.log_e);
  }
  for (double x : {25.0, -30.0, 40.0}) c.log_hdr.push_back(x - c.log_e);  // outside the table
  for (std::size_t i = 0; i < c.log_hdr.size(); ++i) c.weights.push_back(w(rng));
  return c;
}

double ChainLoss(const Chain& c, const std::vector<double>& params, const std::vector<double>& lh) {
  DtmCore<double> core(c.shape);
  core.BeginFrame(params.data(), c.window.data(), c.length, c.log_e);
  std::vector<double> ldr(lh.size());
  core.Map(lh.data(), lh.size() / 3, ldr.data());
  double l = 0;
  for (std::size_t i = 0; i < ldr.size(); ++i) l += c.weights[i] * ldr[i];
  return l;
}

// Analytic gradients; the backward is called twice with half the weights (as the 3D and 2D
// branches both add to one view's gradient).
void ChainGradients(const Chain& c, std::vector<double>* dp, std::vector<double>* dlh) {
  DtmCore<double> core(c.shape);
  core.BeginFrame(c.params.data(), c.window.data(), c.length, c.log_e);
  std::vector<double> half(c.weights.size());
  for (std::size_t i = 0; i < half.size(); ++i) half[i] = 0.5 * c.weights[i];
  dlh->assign(c.log_hdr.size(), 0.0);
  core.MapBackward(c.log_hdr.data(), c.log_hdr.size() / 3, half.data(), dlh->data());
  core.MapBackward(c.log_hdr.data(), c.log_hdr.size() / 3, half.data(), nullptr);
  for (double& v : *dlh) v *= 2;
  dp->assign(c.params.size(), 0.0);
  core.EndFrameBackward(dp->data());
}

FdVector Map(const std::vector<double>& v) {
  return Eigen::Map<const FdVector>(v.data(), v.size());
}
std::vector<double> Vec(const FdVector& v) { return {v.data(), v.data() + v.size()}; }

void CheckChain(const Chain& c, const std::vector<std::size_t>& indices) {
  std::vector<double> dp, dlh;
  ChainGradients(c, &dp, &dlh);
  FdVector analytic(indices.size()), p0(indices.size());
  for (std::size_t k = 0; k < indices.size(); ++k) {
    analytic(k) = dp[indices[k]];
    p0(k) = c.params[indices[k]];
  }
  const FdVector numeric = NumericGradient(
      [&](const FdVector& sub) {
        std::vector<double> p = c.params;
        for (std::size_t k = 0; k < indices.size(); ++k) p[indices[k]] = sub(k);
        return ChainLoss(c, p, c.log_hdr);
      },
      p0, 1e-6);
  ExpectGradientsMatch(analytic, numeric, 1e-6);
  ExpectGradientsMatch(
      Map(dlh),
      NumericGradient([&](const FdVector& v) { return ChainLoss(c, c.params, Vec(v)); },
                      Map(c.log_hdr), 1e-7),
      1e-6);
}

std::vector<std::size_t> AllIndices(std::size_t n) {
  std::vector<std::size_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = i;
  return v;
}

// The whole chain in double, tabulated and direct: the direct case checks
// DtmCore::DirectValueBackward, the tabulated one DtmCore::ScalarChunkBackward (which
// dtm_chunk_backward_test.cpp also checks alone, over several chunks).
TEST(DynamicToneMapperChain, GradientsMatchFiniteDifferencesEveryLearner) {
  for (ContextKind kind :
       {ContextKind::kGru, ContextKind::kRnn, ContextKind::kLstm, ContextKind::kTransformer}) {
    for (int nodes : {40, 0}) {  // tabulated, direct
      for (bool monotone : {false, true}) {
        SCOPED_TRACE(::testing::Message() << ContextKindName(kind) << " nodes=" << nodes
                                          << " monotone=" << monotone);
        const Chain c = MakeChain(kind, 6, nodes, 5, 3, monotone);
        CheckChain(c, AllIndices(c.params.size()));
      }
    }
  }
}

// The default shape (64 hidden, 1024 nodes, GRU, k = 20): every context-learner parameter and a
// sample of curve parameters, windows of 1 and 20 rows.
TEST(DynamicToneMapperChain, DefaultShapeGradientsMatchFiniteDifferences) {
  for (int length : {1, 20}) {
    const Chain c = MakeChain(ContextKind::kGru, 64, 1024, length, 7 + length, length == 20);
    std::vector<std::size_t> indices = AllIndices(c.shape.context.NumParams());
    std::mt19937 rng(length);
    std::uniform_int_distribution<std::size_t> u(c.shape.CurveOffset(0), c.params.size() - 1);
    for (int k = 0; k < 40; ++k) indices.push_back(u(rng));
    for (int ch = 0; ch < 3; ++ch) {  // every curve's output bias and first x-weight
      indices.push_back(c.shape.CurveOffset(ch));
      indices.push_back(c.shape.CurveOffset(ch) + c.shape.curve.NumParams() - 1);
    }
    CheckChain(c, indices);
  }
}

// ---- The ToneMapper ------------------------------------------------------------------------

TEST(DynamicToneMapper, ConstructorRejectsBadConfigurations) {
  ToneMapperConfig c = Config();
  c.context_size = 0;
  EXPECT_NE(ErrorOf([&] { DynamicToneMapper m(c); }).find("context_size"), std::string::npos);
  c = Config();
  c.kind = "mlp";
  EXPECT_NE(ErrorOf([&] { DynamicToneMapper m(c); }).find("'mlp'"), std::string::npos);
  EXPECT_EQ(ErrorOf([&] { DynamicToneMapper m(Config()); }), "");
}

TEST(DynamicToneMapper, ParametersAreContextLearnerThenThreeCurves) {
  DynamicToneMapper m(Config());
  // GRU(3, 2): 42; per curve 3->64->64->1: 256 + 4160 + 65.
  EXPECT_EQ(m.params().size(), 42u + 3 * 4481u);
  EXPECT_EQ(m.grads().size(), m.params().size());
  EXPECT_EQ(m.shape().CurveOffset(1), 42u + 4481u);
  EXPECT_TRUE(m.pointwise());
  EXPECT_FLOAT_EQ(m.learning_rate(), 5e-4f);
  for (float g : m.grads()) EXPECT_EQ(g, 0.0f);
  // The same seed gives the same weights; another seed others.
  DynamicToneMapper same(Config()), other([] {
    ToneMapperConfig c = Config();
    c.seed = 6;
    return c;
  }());
  EXPECT_EQ(same.params(), m.params());
  EXPECT_NE(other.params(), m.params());
}

TEST(DynamicToneMapper, RejectsBadTimeIndexAndExposure) {
  DynamicToneMapper m(Config(4));
  const float mean[3] = {0, 0, 0};
  for (int bad : {-1, 4, 100}) {
    EXPECT_NE(ErrorOf([&] {
                m.BeginFrame({bad, -1, 0.0f});
              }).find("time index"),
              std::string::npos);
    EXPECT_NE(ErrorOf([&] { m.ObserveMeanLogHdr(bad, mean); }).find("radiance bank's 4 rows"),
              std::string::npos);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(ErrorOf([&] { m.BeginFrame({0, -1, nan}); }).find("log exposure"), std::string::npos);
  EXPECT_EQ(ErrorOf([&] { m.BeginFrame({3, -1, 0.0f}); }), "");
}

// The context follows the reference's window: at time 0 the row just written, at time i < k the
// rows before it.
TEST(DynamicToneMapper, ContextReadsTheBankWindow) {
  DynamicToneMapper m(Config(5));
  FillBank(m, 1);
  const ContextLearnerShape shape = m.shape().context;
  auto expected = [&](int begin, int length) {
    std::vector<float> f(2);
    ContextTape<float> tape;
    ContextLearnerForward(shape, m.params().data(), m.bank().rows().data() + 3 * begin, length,
                          f.data(), &tape);
    return f;
  };
  m.BeginFrame({0, -1, 0.0f});
  EXPECT_EQ(m.context(), expected(0, 1));
  m.BeginFrame({3, -1, 0.0f});
  EXPECT_EQ(m.context(), expected(0, 3));
  const float bright[3] = {4, 4, 4};
  m.ObserveMeanLogHdr(3, bright);  // the view's own row is not in its window
  m.BeginFrame({3, -1, 0.0f});
  EXPECT_EQ(m.context(), expected(0, 3));
  m.ObserveMeanLogHdr(1, bright);
  m.BeginFrame({3, -1, 0.0f});
  EXPECT_NE(m.context(), expected(0, 1));
  EXPECT_EQ(m.context(), expected(0, 3));
}

// One timestamp: the bank has one row and every view reads it.
TEST(DynamicToneMapper, OneTimestampScene) {
  DynamicToneMapper m(Config(1));
  const float mean[3] = {-1.0f, 0.5f, 0.2f};
  m.ObserveMeanLogHdr(0, mean);
  m.BeginFrame({0, 0, std::log(2.0f)});
  std::vector<float> f(2);
  ContextTape<float> tape;
  ContextLearnerForward(m.shape().context, m.params().data(), mean, 1, f.data(), &tape);
  EXPECT_EQ(m.context(), f);
  const std::vector<float> lh = RandomValues(300, 2, -4, 4);
  std::vector<float> ldr(lh.size()), dL(lh.size(), 1.0f), dlh(lh.size());
  m.Map(lh.data(), 100, ldr.data());
  m.MapBackward(lh.data(), 100, dL.data(), dlh.data());
  m.EndFrameBackward();
  double norm = 0;
  for (float g : m.grads()) norm += std::abs(g);
  EXPECT_GT(norm, 0.0);
}

// The exposure enters as a shift of x: log e + log HDR.
TEST(DynamicToneMapper, ExposureShiftsTheInput) {
  DynamicToneMapper m(Config());
  FillBank(m, 3);
  const std::vector<float> lh = RandomValues(30, 4, -3, 3);
  std::vector<float> a(lh.size()), b(lh.size());
  m.BeginFrame({2, -1, std::log(4.0f)});
  m.Map(lh.data(), 10, a.data());
  std::vector<float> shifted = lh;
  for (float& v : shifted) v += std::log(4.0f);
  m.BeginFrame({2, -1, 0.0f});
  m.Map(shifted.data(), 10, b.data());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-6f);
}

// x = log HDR + log e over [-60, 60] (and radiance 1e-6..1e6) at exposures 1e-4..1e3 s, for
// fresh and steep weights, both paths: outputs finite in [0, 1], gradients finite.
TEST(DynamicToneMapper, StableAtExtremes) {
  for (bool tabulated : {true, false}) {
    for (double scale : {1.0, 6.0}) {
      ToneMapperConfig c = Config(3);
      c.tabulated = tabulated;
      DynamicToneMapper m(c);
      for (std::size_t i = m.shape().CurveOffset(0); i < m.params().size(); ++i) {
        m.params()[i] *= float(scale);
      }
      const float extreme_rows[9] = {1e6f, -1e6f, 30.0f, -30.0f, 0.0f, 1e6f, 0, 0, 0};
      m.ObserveMeanLogHdr(0, extreme_rows);
      m.ObserveMeanLogHdr(1, extreme_rows + 3);
      for (double exposure : {1e-4, 1e-2, 1.0, 1e3}) {
        const float log_e = float(std::log(exposure));
        std::vector<float> lh;
        for (int i = 0; i <= 240; ++i) lh.push_back(float(-60.0 + 0.5 * i) - log_e);
        for (double r : {1e-6, 1e-3, 1.0, 1e3, 1e6}) lh.push_back(float(std::log(r)));
        lh.push_back(-1e30f);
        lh.push_back(1e30f);
        while (lh.size() % 3) lh.push_back(0.0f);
        const std::size_t n = lh.size() / 3;
        std::vector<float> ldr(lh.size()), dlh(lh.size());
        const std::vector<float> dL = RandomValues(lh.size(), 5, -1, 1);
        m.BeginFrame({2, -1, log_e});
        m.Map(lh.data(), n, ldr.data());
        m.MapBackward(lh.data(), n, dL.data(), dlh.data());
        m.EndFrameBackward();
        for (std::size_t i = 0; i < ldr.size(); ++i) {
          ASSERT_TRUE(ldr[i] >= 0.0f && ldr[i] <= 1.0f) << lh[i] << " -> " << ldr[i];
          ASSERT_TRUE(std::isfinite(dlh[i])) << lh[i];
        }
        EXPECT_EQ(dlh[246], 0.0f);  // clamped far outside: no gradient
        EXPECT_EQ(dlh[247], 0.0f);
        EXPECT_NE(dlh[120], 0.0f);  // x = 0
      }
      for (float g : m.grads()) ASSERT_TRUE(std::isfinite(g));
    }
  }
}

TEST(DynamicToneMapper, TabulatedAgreesWithDirect) {
  ToneMapperConfig c = Config();
  DynamicToneMapper tab(c);
  c.tabulated = false;
  DynamicToneMapper direct(c);
  ASSERT_EQ(tab.params(), direct.params());
  FillBank(tab, 6);
  FillBank(direct, 6);
  const std::vector<float> lh = RandomValues(3 * 2000, 7, -12, 10);
  std::vector<float> a(lh.size()), b(lh.size());
  tab.BeginFrame({5, -1, std::log(0.125f)});
  direct.BeginFrame({5, -1, std::log(0.125f)});
  tab.Map(lh.data(), 2000, a.data());
  direct.Map(lh.data(), 2000, b.data());
  float worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  EXPECT_LT(worst, 2e-3f);
  EXPECT_EQ(tab.context(), direct.context());
  // Their parameter gradients agree too (the table's differ only within kink intervals).
  const std::vector<float> dL = RandomValues(lh.size(), 8, -1, 1);
  tab.MapBackward(lh.data(), 2000, dL.data(), nullptr);
  direct.MapBackward(lh.data(), 2000, dL.data(), nullptr);
  tab.EndFrameBackward();
  direct.EndFrameBackward();
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < tab.grads().size(); ++i) {
    diff += std::abs(tab.grads()[i] - direct.grads()[i]);
    norm += std::abs(direct.grads()[i]);
  }
  EXPECT_LT(diff, 0.02 * norm);
}

// The float SIMD loop of the tabulated path (detail::ToneTableBackward and its forward, and the
// scatter of SimdChunkTableBackward) against the scalar loop, whose gradients the
// finite-difference tests above check (same maths, another exp), on the default target;
// dtm_chunk_backward_test.cpp checks SimdChunkTableBackward against finite differences on every
// compiled target.
TEST(DynamicToneMapperChain, SimdMatchesScalar) {
  DtmShape shape;  // the defaults: GRU, 64 hidden, 1024 nodes
  DtmCore<float> simd(shape), scalar(shape);
  scalar.set_simd(false);
  std::vector<float> params(shape.NumParams());
  simd.Init(3, params.data());
  for (std::size_t i = shape.CurveOffset(0); i < params.size(); ++i) params[i] *= 3.0f;
  const std::vector<float> window = RandomValues(3 * 20, 1, -2, 1);
  const std::size_t n = 3 * kDtmChunk + 7;                  // several chunks and a SIMD tail
  std::vector<float> lh = RandomValues(3 * n, 2, -25, 25);  // some outside the table
  lh[5] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> dL = RandomValues(3 * n, 3, -1, 1);
  std::vector<float> y1(lh.size()), y2(lh.size()), d1(lh.size()), d2(lh.size());
  std::vector<float> g1(params.size(), 0.0f), g2(params.size(), 0.0f);
  for (DtmCore<float>* core : {&simd, &scalar}) {
    const bool s = core == &simd;
    core->BeginFrame(params.data(), window.data(), 20, -0.7f);
    core->Map(lh.data(), n, (s ? y1 : y2).data());
    core->MapBackward(lh.data(), n, dL.data(), (s ? d1 : d2).data());
    core->EndFrameBackward((s ? g1 : g2).data());
  }
  // A NaN colour maps to NaN, its gradient is NaN, the parameters' gradients stay finite.
  EXPECT_TRUE(std::isnan(y1[5]) && std::isnan(y2[5]));
  EXPECT_TRUE(std::isnan(d1[5]) && std::isnan(d2[5]));
  for (float g : g1) ASSERT_TRUE(std::isfinite(g));
  y1[5] = y2[5] = d1[5] = d2[5] = 0;
  int outside = 0;
  for (std::size_t i = 0; i < lh.size(); ++i) {
    ASSERT_NEAR(y1[i], y2[i], 2e-6f) << i;
    ASSERT_NEAR(d1[i], d2[i], 1e-4f * (1 + std::abs(d2[i]))) << i;
    outside += std::abs(lh[i] - 0.7f) > 22;
  }
  EXPECT_GT(outside, 100);
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < g1.size(); ++i) {
    diff += std::abs(g1[i] - g2[i]);
    norm += std::abs(g2[i]);
  }
  EXPECT_LT(diff, 1e-4 * norm);
  EXPECT_GT(norm, 0.0);
}

// Bit-identical outputs and gradients at 1 and 2 threads (several chunks, some values outside
// the table).
TEST(DynamicToneMapper, DeterministicAtAnyThreadCount) {
  for (bool tabulated : {true, false}) {
    ToneMapperConfig c = Config();
    c.tabulated = tabulated;
    const std::size_t n = tabulated ? 5 * kDtmChunk + 17 : kDtmChunk + 300;
    std::vector<float> lh = RandomValues(3 * n, 9, -10, 8);
    for (std::size_t i = 0; i < lh.size(); i += 97) lh[i] = 30.0f;  // the direct fallback
    const std::vector<float> dL = RandomValues(3 * n, 10, -1, 1);
    auto run = [&](int threads, std::vector<float>* ldr, std::vector<float>* dlh) {
      ThreadLimit limit(threads);
      DynamicToneMapper m(c);
      FillBank(m, 11);
      ldr->resize(lh.size());
      dlh->resize(lh.size());
      m.BeginFrame({6, -1, 0.3f});
      m.Map(lh.data(), n, ldr->data());
      m.MapBackward(lh.data(), n, dL.data(), dlh->data());
      m.EndFrameBackward();
      return m.grads();
    };
    std::vector<float> l1, l2, d1, d2;
    const std::vector<float> g1 = run(1, &l1, &d1);
    const std::vector<float> g2 = run(2, &l2, &d2);
    EXPECT_EQ(l1, l2);
    EXPECT_EQ(d1, d2);
    EXPECT_EQ(g1, g2);
  }
}

// The 3D and 2D branches add to one view's gradient; a BeginFrame flushes a pending one; an
// EndFrameBackward without a backward adds nothing.
TEST(DynamicToneMapper, FrameProtocolAccumulates) {
  const std::vector<float> lh = RandomValues(600, 12, -5, 5);
  const std::vector<float> dL = RandomValues(600, 13, -1, 1);
  auto make = [] {
    auto m = std::make_unique<DynamicToneMapper>(Config());
    FillBank(*m, 14);
    m->BeginFrame({4, -1, 0.0f});
    return m;
  };
  auto once = make();
  once->MapBackward(lh.data(), 200, dL.data(), nullptr);
  once->EndFrameBackward();
  auto twice = make();
  twice->MapBackward(lh.data(), 200, dL.data(), nullptr);
  twice->MapBackward(lh.data(), 200, dL.data(), nullptr);
  twice->EndFrameBackward();
  twice->EndFrameBackward();  // nothing pending: adds nothing
  auto flushed = make();
  flushed->MapBackward(lh.data(), 200, dL.data(), nullptr);
  flushed->BeginFrame({1, -1, 0.0f});  // flushes the pending view
  float largest = 0;
  for (std::size_t i = 0; i < once->grads().size(); ++i) {
    EXPECT_NEAR(twice->grads()[i], 2 * once->grads()[i], 1e-5f * (1 + std::abs(once->grads()[i])));
    EXPECT_EQ(flushed->grads()[i], once->grads()[i]);
    largest = std::max(largest, std::abs(once->grads()[i]));
  }
  EXPECT_GT(largest, 1e-3f);
  // The context learner's parameters get a gradient too (through f).
  float context_norm = 0;
  for (std::size_t i = 0; i < once->shape().context.NumParams(); ++i) {
    context_norm += std::abs(once->grads()[i]);
  }
  EXPECT_GT(context_norm, 0.0f);
}

// ---- Checkpoints ---------------------------------------------------------------------------

std::string Saved(const DynamicToneMapper& m) {
  std::stringstream s;
  m.Save(s);
  return s.str();
}

std::string LoadError(DynamicToneMapper& m, const std::string& bytes) {
  std::stringstream s(bytes);
  return ErrorOf([&] { m.Load(s, "run/tone_mapper.bin"); });
}

TEST(DynamicToneMapper, SaveLoadRoundTrip) {
  DynamicToneMapper a(Config());
  FillBank(a, 15);
  for (float& p : a.params()) p *= 1.1f;  // not what any seed gives
  ToneMapperConfig other = Config();
  other.seed = 99;
  DynamicToneMapper b(other);
  ASSERT_EQ(LoadError(b, Saved(a)), "");
  EXPECT_EQ(b.params(), a.params());
  EXPECT_EQ(b.bank().rows(), a.bank().rows());
  const std::vector<float> lh = RandomValues(300, 16, -6, 6);
  std::vector<float> ya(lh.size()), yb(lh.size());
  a.BeginFrame({7, 2, 0.5f});
  b.BeginFrame({7, 2, 0.5f});
  a.Map(lh.data(), 100, ya.data());
  b.Map(lh.data(), 100, yb.data());
  EXPECT_EQ(ya, yb);
  // The speed option may differ between save and load.
  other.tabulated = false;
  DynamicToneMapper direct(other);
  EXPECT_EQ(LoadError(direct, Saved(a)), "");
  EXPECT_EQ(direct.params(), a.params());
}

// A held-out frame's timestamp on a monocular scene: rows 0, 2 and 4.. are never written. With
// unseen_rows "interpolate" the context is that of a bank holding, there, the interpolation in
// time of the written rows (the nearest one past an end); with "zero", of the bank as it is.
TEST(DynamicToneMapper, UnwrittenRowsReadAsTheConfigSays) {
  ToneMapperConfig c = Config(6);
  ASSERT_EQ(c.unseen_rows, "interpolate");  // the default
  DynamicToneMapper interpolate(c);
  c.unseen_rows = "zero";
  DynamicToneMapper zero(c);
  const float r1[3] = {1, 2, 3}, r3[3] = {3, -2, 5}, r2[3] = {2, 0, 4}, none[3] = {0, 0, 0};
  for (DynamicToneMapper* m : {&interpolate, &zero}) {
    m->ObserveMeanLogHdr(1, r1);
    m->ObserveMeanLogHdr(3, r3);
    m->BeginFrame({4, -1, 0.0f});
  }
  DynamicToneMapper filled(Config(6)), zeros(Config(6));
  for (auto [row, v, z] : {std::tuple{0, r1, none}, {1, r1, r1}, {2, r2, none}, {3, r3, r3}}) {
    filled.ObserveMeanLogHdr(row, v);
    zeros.ObserveMeanLogHdr(row, z);
  }
  filled.BeginFrame({4, -1, 0.0f});
  zeros.BeginFrame({4, -1, 0.0f});
  EXPECT_EQ(interpolate.context(), filled.context());
  EXPECT_EQ(zero.context(), zeros.context());
  EXPECT_NE(interpolate.context(), zero.context());

  // The flags travel with the state: a loaded mapper reads the same context.
  DynamicToneMapper loaded(Config(6));
  ASSERT_EQ(LoadError(loaded, Saved(interpolate)), "");
  EXPECT_EQ(loaded.bank().written_rows(), (std::vector<std::uint8_t>{0, 1, 0, 1, 0, 0}));
  loaded.BeginFrame({4, -1, 0.0f});
  EXPECT_EQ(loaded.context(), interpolate.context());
  // A state saved with one policy does not load into the other.
  EXPECT_NE(LoadError(zero, Saved(interpolate)).find("unseen_rows = interpolate"),
            std::string::npos);
}

// A version-1 state (no written flags, no unseen_rows key) loads with rows written where they
// are not all zero.
TEST(DynamicToneMapper, LoadsAVersionOneState) {
  ToneMapperConfig c = Config(4);
  c.unseen_rows = "zero";  // what a version-1 config without the key means
  DynamicToneMapper source(c);
  const float r[3] = {1, 2, 3};
  source.ObserveMeanLogHdr(2, r);
  const std::string v2 = Saved(source);
  // Version 1: the same bytes without the flags (4 rows), the config without the key.
  std::string body = v2.substr(12, v2.size() - 12 - 4 - 8);
  const std::string key = ",\"unseen_rows\":\"zero\"";
  const std::size_t at = body.find(key);
  ASSERT_NE(at, std::string::npos);
  body.erase(at, key.size());
  const std::uint32_t json_size = *reinterpret_cast<const std::uint32_t*>(body.data()) - key.size();
  std::memcpy(body.data(), &json_size, sizeof(json_size));
  std::stringstream v1;
  HashingWriter w(v1);
  w.Bytes("HDR4DDTM", 8);
  w.Value(std::uint32_t{1});
  w.ResetHash();
  w.Bytes(body.data(), body.size());
  w.Value(w.hash());
  DynamicToneMapper m(c);
  std::stringstream in(v1.str());
  ASSERT_EQ(ErrorOf([&] { m.Load(in, "old/tone_mapper.bin"); }), "");
  EXPECT_EQ(m.bank().written_rows(), (std::vector<std::uint8_t>{0, 0, 1, 0}));
  EXPECT_EQ(m.params(), source.params());
}

TEST(DynamicToneMapper, LoadRejectsBadStateAndKeepsTheMapper) {
  DynamicToneMapper source(Config());
  FillBank(source, 17);
  const std::string good = Saved(source);
  DynamicToneMapper m(Config());
  const float row[3] = {1, 2, 3};
  m.ObserveMeanLogHdr(2, row);
  const std::vector<float> params = m.params(), bank = m.bank().rows();
  const float* address = m.params().data();

  for (std::size_t cut : {std::size_t{0}, std::size_t{7}, std::size_t{11}, std::size_t{40},
                          good.size() / 2, good.size() - 9, good.size() - 1}) {
    const std::string e = LoadError(m, good.substr(0, cut));
    EXPECT_NE(e.find("run/tone_mapper.bin"), std::string::npos) << cut;
    EXPECT_NE(e.find("truncated"), std::string::npos) << cut << ": " << e;
  }
  std::string corrupt = good;
  corrupt[good.size() / 2] ^= 0x01;
  EXPECT_NE(LoadError(m, corrupt).find("checksum"), std::string::npos);
  std::string magic = good;
  magic[3] = 'x';
  EXPECT_NE(LoadError(m, magic).find("bad magic"), std::string::npos);
  std::string version = good;
  version[8] = 3;
  EXPECT_NE(LoadError(m, version).find("version 3"), std::string::npos);

  ToneMapperConfig c = Config();
  c.context_window = 10;  // same sizes, another structure
  DynamicToneMapper window10(c);
  EXPECT_NE(LoadError(window10, good).find("context_window = 20"), std::string::npos);
  c = Config();
  c.context_learner = "lstm";
  DynamicToneMapper lstm(c);
  EXPECT_NE(LoadError(lstm, good).find("parameters"), std::string::npos);
  DynamicToneMapper fewer_times(Config(3));
  EXPECT_NE(LoadError(fewer_times, good).find("3 timestamps"), std::string::npos);

  EXPECT_EQ(m.params(), params);
  EXPECT_EQ(m.bank().rows(), bank);
  EXPECT_EQ(LoadError(m, good), "");
  EXPECT_EQ(m.params().data(), address);  // loaded in place
  EXPECT_EQ(m.params(), source.params());
}

}  // namespace
}  // namespace hdr4d::method
