#include "method/tonemap/context_learner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

constexpr ContextKind kKinds[] = {ContextKind::kGru, ContextKind::kRnn, ContextKind::kLstm,
                                  ContextKind::kTransformer};

template <typename T>
std::vector<T> RandomRows(int length, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<T> rows(std::size_t(length) * 3);
  for (T& v : rows) v = T(u(rng));
  return rows;
}

TEST(ContextLearner, KindNamesRoundTrip) {
  for (ContextKind k : kKinds) EXPECT_EQ(ParseContextKind(ContextKindName(k)), k);
  EXPECT_FALSE(ParseContextKind("GRU").has_value());
  EXPECT_FALSE(ParseContextKind("").has_value());
}

TEST(ContextLearner, ParameterCountsMatchTorch) {
  // nn.GRU(3, 2): 6x3 + 6x2 + 6 + 6; nn.RNN(3, 2): 2x3 + 2x2 + 2 + 2; nn.LSTM(3, 2): 8x(3+2+2).
  EXPECT_EQ((ContextLearnerShape{ContextKind::kGru, 2}.NumParams()), 42u);
  EXPECT_EQ((ContextLearnerShape{ContextKind::kRnn, 2}.NumParams()), 14u);
  EXPECT_EQ((ContextLearnerShape{ContextKind::kLstm, 2}.NumParams()), 56u);
  EXPECT_EQ((ContextLearnerShape{ContextKind::kGru, 5}.NumParams()), 15u * 10);
  // Transformer, D = 16, F = 32, d = 2: 64 + 816 + 272 + 32 + 544 + 528 + 32 + 34.
  EXPECT_EQ((ContextLearnerShape{ContextKind::kTransformer, 2}.NumParams()), 2322u);
}

TEST(ContextLearner, RecurrentInitIsUniformInTorchBounds) {
  for (ContextKind k : {ContextKind::kGru, ContextKind::kRnn, ContextKind::kLstm}) {
    const ContextLearnerShape shape{k, 4};
    std::vector<double> p(shape.NumParams()), q(p.size());
    ContextLearnerInit(shape, 3, p.data());
    ContextLearnerInit(shape, 3, q.data());
    EXPECT_EQ(p, q);
    double largest = 0;
    for (double v : p) largest = std::max(largest, std::abs(v));
    EXPECT_LE(largest, 0.5);  // 1 / sqrt(4)
    EXPECT_GT(largest, 0.4);
  }
}

// GRU equations of torch.nn.GRU, written out for one step with hidden size 1: b_hn sits inside
// r * (...), and the gate rows are ordered r, z, n.
TEST(ContextLearner, GruMatchesTorchEquations) {
  const ContextLearnerShape shape{ContextKind::kGru, 1};
  std::vector<double> p(shape.NumParams());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double& v : p) v = u(rng);
  const std::vector<double> rows = {0.3, -0.7, 1.1, -0.2, 0.5, 0.9};
  double f;
  ContextTape<double> tape;
  ContextLearnerForward(shape, p.data(), rows.data(), 2, &f, &tape);
  // Layout: W_ih (3x3) 0..8, W_hh (3x1) 9..11, b_ih 12..14, b_hh 15..17.
  auto sig = [](double z) { return 1 / (1 + std::exp(-z)); };
  double h = 0;
  for (int t = 0; t < 2; ++t) {
    const double* x = rows.data() + 3 * t;
    auto in = [&](int g) { return p[3 * g] * x[0] + p[3 * g + 1] * x[1] + p[3 * g + 2] * x[2]; };
    const double r = sig(in(0) + p[12] + p[9] * h + p[15]);
    const double z = sig(in(1) + p[13] + p[10] * h + p[16]);
    const double n = std::tanh(in(2) + p[14] + r * (p[11] * h + p[17]));
    h = (1 - z) * n + z * h;
  }
  EXPECT_NEAR(f, h, 1e-14);
}

// LSTM of torch.nn.LSTM with hidden size 1 (gates i, f, g, o), two steps.
TEST(ContextLearner, LstmMatchesTorchEquations) {
  const ContextLearnerShape shape{ContextKind::kLstm, 1};
  std::vector<double> p(shape.NumParams());
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double& v : p) v = u(rng);
  const std::vector<double> rows = {0.3, -0.7, 1.1, -0.2, 0.5, 0.9};
  double f;
  ContextTape<double> tape;
  ContextLearnerForward(shape, p.data(), rows.data(), 2, &f, &tape);
  // Layout: W_ih (4x3) 0..11, W_hh (4x1) 12..15, b_ih 16..19, b_hh 20..23.
  auto sig = [](double z) { return 1 / (1 + std::exp(-z)); };
  double h = 0, c = 0;
  for (int t = 0; t < 2; ++t) {
    const double* x = rows.data() + 3 * t;
    auto a = [&](int g) {
      return p[3 * g] * x[0] + p[3 * g + 1] * x[1] + p[3 * g + 2] * x[2] + p[16 + g] +
             p[12 + g] * h + p[20 + g];
    };
    const double i = sig(a(0)), fg = sig(a(1)), g = std::tanh(a(2)), o = sig(a(3));
    c = fg * c + i * g;
    h = o * std::tanh(c);
  }
  EXPECT_NEAR(f, h, 1e-14);
}

TEST(ContextLearner, RnnMatchesTorchEquations) {
  const ContextLearnerShape shape{ContextKind::kRnn, 1};
  const std::vector<double> p = {0.2, -0.4, 0.6, 0.8, 0.1, -0.3};  // W_ih, W_hh, b_ih, b_hh
  const std::vector<double> rows = {1.0, 2.0, 3.0, -1.0, 0.5, 0.0};
  double f;
  ContextTape<double> tape;
  ContextLearnerForward(shape, p.data(), rows.data(), 2, &f, &tape);
  double h = std::tanh(0.2 * 1 - 0.4 * 2 + 0.6 * 3 + 0.1 - 0.3);
  h = std::tanh(0.2 * -1 - 0.4 * 0.5 + 0.8 * h + 0.1 - 0.3);
  EXPECT_NEAR(f, h, 1e-15);
}

// Every kind sees the whole window: changing the oldest row changes f.
TEST(ContextLearner, ContextDependsOnEveryRow) {
  for (ContextKind k : kKinds) {
    const ContextLearnerShape shape{k, 2};
    std::vector<double> p(shape.NumParams());
    ContextLearnerInit(shape, 9, p.data());
    std::vector<double> rows = RandomRows<double>(5, 1, 1.0), f1(2), f2(2);
    ContextTape<double> tape;
    ContextLearnerForward(shape, p.data(), rows.data(), 5, f1.data(), &tape);
    rows[0] += 0.5;
    ContextLearnerForward(shape, p.data(), rows.data(), 5, f2.data(), &tape);
    EXPECT_GT(std::abs(f1[0] - f2[0]) + std::abs(f1[1] - f2[1]), 1e-6) << ContextKindName(k);
  }
}

// Back-propagation through time against central differences, every kind, L = 1, 5 and 20: the
// public backward dispatches to RecurrentBackward (gru, rnn, lstm) and TransformerBackward
// (whose LayerNormBackward runs twice), so this checks each of them in double.
TEST(ContextLearner, GradientsMatchFiniteDifferences) {
  for (ContextKind k : kKinds) {
    for (int length : {1, 5, 20}) {
      for (int size : {2, 3}) {
        SCOPED_TRACE(::testing::Message()
                     << ContextKindName(k) << " L=" << length << " d=" << size);
        const ContextLearnerShape shape{k, size};
        std::vector<double> p(shape.NumParams());
        ContextLearnerInit(shape, 100 + length, p.data());
        if (k == ContextKind::kTransformer) {  // move the norms off their init values
          std::mt19937 rng(length);
          std::uniform_real_distribution<double> u(-0.3, 0.3);
          for (double& v : p) v += u(rng);
        }
        const std::vector<double> rows = RandomRows<double>(length, 7 + length, 1.5);
        const std::vector<double> w = RandomRows<double>(1, 3, 1.0);  // dL/df
        ContextTape<double> tape;
        auto loss = [&](const FdVector& v) {
          std::vector<double> f(size);
          ContextTape<double> t;
          ContextLearnerForward(shape, v.data(), rows.data(), length, f.data(), &t);
          double l = 0;
          for (int j = 0; j < size; ++j) l += w[j] * f[j];
          return l;
        };
        std::vector<double> f(size), dp(p.size(), 0.0);
        ContextLearnerForward(shape, p.data(), rows.data(), length, f.data(), &tape);
        ContextLearnerBackward(shape, p.data(), rows.data(), tape, w.data(), dp.data());
        const FdVector p0 = Eigen::Map<const FdVector>(p.data(), p.size());
        ExpectGradientsMatch(Eigen::Map<const FdVector>(dp.data(), dp.size()),
                             NumericGradient(loss, p0, 1e-6), 1e-6);
      }
    }
  }
}

// Rows of +-1e6 and +-30 saturate gates and the softmax: f and the gradients stay finite.
TEST(ContextLearner, ExtremeInputsStayFinite) {
  for (ContextKind k : kKinds) {
    for (double scale : {1e6, 30.0, 0.0}) {
      const ContextLearnerShape shape{k, 2};
      std::vector<float> p(shape.NumParams());
      ContextLearnerInit(shape, 4, p.data());
      std::vector<float> rows = RandomRows<float>(20, 11, 1.0);
      for (float& v : rows) v = float(v > 0 ? scale : -scale);
      std::vector<float> f(2), dp(p.size(), 0.0f);
      const float w[2] = {1.0f, -1.0f};
      ContextTape<float> tape;
      ContextLearnerForward(shape, p.data(), rows.data(), 20, f.data(), &tape);
      ContextLearnerBackward(shape, p.data(), rows.data(), tape, w, dp.data());
      for (float v : f) EXPECT_TRUE(std::isfinite(v)) << ContextKindName(k) << " " << scale;
      for (float v : dp) ASSERT_TRUE(std::isfinite(v)) << ContextKindName(k) << " " << scale;
      if (k != ContextKind::kTransformer) {
        for (float v : f) EXPECT_LE(std::abs(v), 1.0f);  // a tanh or o * tanh(c)
      }
    }
  }
}

TEST(ContextLearner, BackwardAddsToGradients) {
  const ContextLearnerShape shape{ContextKind::kGru, 2};
  std::vector<double> p(shape.NumParams());
  ContextLearnerInit(shape, 1, p.data());
  const std::vector<double> rows = RandomRows<double>(4, 2, 1.0);
  std::vector<double> f(2), once(p.size(), 0.0), twice(p.size(), 0.0);
  const double w[2] = {0.7, -0.2};
  ContextTape<double> tape;
  ContextLearnerForward(shape, p.data(), rows.data(), 4, f.data(), &tape);
  ContextLearnerBackward(shape, p.data(), rows.data(), tape, w, once.data());
  ContextLearnerBackward(shape, p.data(), rows.data(), tape, w, twice.data());
  ContextLearnerBackward(shape, p.data(), rows.data(), tape, w, twice.data());
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(twice[i], 2 * once[i], 1e-14);
}

}  // namespace
}  // namespace hdr4d::method
