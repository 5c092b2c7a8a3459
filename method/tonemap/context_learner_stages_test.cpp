// The transformer context learner's backward, stage by stage (context_learner_internal.h):
// FeedForwardBackward, OutputProjectionBackward and AttentionBackward, each driven alone from a
// random upstream gradient and compared, in double, with central differences of the forward's
// own intermediate (f, y1 or the attention output a, read from the tape). The layer has one
// attention head (context_learner.h); the attention is checked over windows of 2 to 12 rows.
// Every output of a stage is checked: its parameter blocks directly, and the gradient it passes
// down through a parameter that receives exactly that gradient (y1 = g1 xhat1 + be1, so
// dL/dbe1 = dL/dy1; r1 = x_last + b_o + W_o a, so dL/db_o = dL/dr1; a = sum_t p_t (W_v x_t + b_v)
// with sum_t p_t = 1, so dL/db_v = dL/da).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "method/tonemap/context_learner.h"
#include "method/tonemap/context_learner_internal.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using context_internal::kD;
using context_internal::kIn;
using context_internal::TransformerLayout;
using context_internal::TransformerTape;
using testing::FdCheck;
using testing::FdVector;

// Steps of 1e-6 on smooth double functions of size ~1: truncation and rounding both ~1e-10.
constexpr FdCheck kFd{1e-6, 1e-6};
constexpr int kSize = 3;  // d

std::vector<double> Uniform(std::size_t n, unsigned seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-scale, scale);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

// A transformer with its norms and attention biases moved off their init values, and a window.
struct Transformer {
  ContextLearnerShape shape{ContextKind::kTransformer, kSize};
  TransformerLayout P{kSize};
  int length;
  std::vector<double> params, rows;
  explicit Transformer(int length_) : length(length_) {
    params.resize(shape.NumParams());
    ContextLearnerInit(shape, 40 + length, params.data());
    const std::vector<double> noise = Uniform(params.size(), length, 0.3);
    for (std::size_t i = 0; i < params.size(); ++i) params[i] += noise[i];
    rows = Uniform(std::size_t(length) * kIn, 7 + length, 1.5);
  }
  // The forward's tape at `p`, and f.
  ContextTape<double> Tape(const std::vector<double>& p, std::vector<double>* f = nullptr) const {
    std::vector<double> out(kSize);
    ContextTape<double> tape;
    ContextLearnerForward(shape, p.data(), rows.data(), length, out.data(), &tape);
    if (f) *f = out;
    return tape;
  }
  // dot(g, the tape's g.size() values from `offset`) at parameters p.
  double Dot(const std::vector<double>& p, std::size_t offset, const std::vector<double>& g) const {
    const ContextTape<double> t = Tape(p);
    double l = 0;
    for (std::size_t i = 0; i < g.size(); ++i) l += g[i] * t.values[offset + i];
    return l;
  }
  // Central differences of loss over params[first, first + count), the rest held.
  FdVector Numeric(const std::function<double(const std::vector<double>&)>& loss,
                   std::size_t first,
                   std::size_t count) const {
    const FdVector x0 = Eigen::Map<const FdVector>(params.data() + first, count);
    return kFd.Gradient(
        [&](const FdVector& x) {
          std::vector<double> p = params;
          for (std::size_t k = 0; k < count; ++k) p[first + k] = x(k);
          return loss(p);
        },
        x0);
  }
};

FdVector Slice(const std::vector<double>& v, std::size_t first, std::size_t count) {
  return Eigen::Map<const FdVector>(v.data() + first, count);
}

// The stage wrote nothing outside [first, last).
void ExpectZeroOutside(const std::vector<double>& dp, std::size_t first, std::size_t last) {
  for (std::size_t i = 0; i < dp.size(); ++i) {
    if (i < first || i >= last) {
      ASSERT_EQ(dp[i], 0.0) << "parameter " << i;
    }
  }
}

TEST(ContextLearnerStages, FeedForwardBackwardMatchesFiniteDifferences) {
  for (int length : {1, 5}) {
    SCOPED_TRACE(length);
    const Transformer s(length);
    const TransformerTape S(length);
    const std::vector<double> w = Uniform(kSize, 3, 1.0);  // dL/df
    const ContextTape<double> tape = s.Tape(s.params);
    std::vector<double> dp(s.params.size(), 0.0), dy1(kD, 0.0);
    context_internal::FeedForwardBackward(s.shape, s.P, S, s.params.data(), tape.values.data(),
                                          w.data(), dp.data(), dy1.data());
    const auto loss = [&](const std::vector<double>& p) {
      std::vector<double> f;
      s.Tape(p, &f);
      double l = 0;
      for (int j = 0; j < kSize; ++j) l += w[j] * f[j];
      return l;
    };
    // W1, b1, W2, b2, LN2 gamma and beta, the head: the layout's last blocks.
    const std::size_t first = s.P.w1, count = s.P.total - s.P.w1;
    kFd.ExpectMatch(Slice(dp, first, count), s.Numeric(loss, first, count));
    ExpectZeroOutside(dp, first, s.P.total);
    kFd.ExpectMatch(Slice(dy1, 0, kD), s.Numeric(loss, s.P.be1, kD));  // dL/dy1 = dL/dbe1
  }
}

TEST(ContextLearnerStages, OutputProjectionBackwardMatchesFiniteDifferences) {
  for (int length : {1, 5}) {
    SCOPED_TRACE(length);
    const Transformer s(length);
    const TransformerTape S(length);
    const std::vector<double> g = Uniform(kD, 4, 1.0);  // dL/dy1
    const ContextTape<double> tape = s.Tape(s.params);
    std::vector<double> dp(s.params.size(), 0.0), dr1(kD, 0.0), da(kD, 0.0);
    context_internal::OutputProjectionBackward(s.P, S, s.params.data(), tape.values.data(),
                                               g.data(), dp.data(), dr1.data(), da.data());
    const auto loss = [&](const std::vector<double>& p) { return s.Dot(p, S.y1, g); };
    // W_o, b_o, LN1 gamma and beta: contiguous in the layout.
    const std::size_t first = s.P.w_o, count = s.P.w1 - s.P.w_o;
    kFd.ExpectMatch(Slice(dp, first, count), s.Numeric(loss, first, count));
    ExpectZeroOutside(dp, first, s.P.w1);
    kFd.ExpectMatch(Slice(dr1, 0, kD), s.Numeric(loss, s.P.b_o, kD));            // dL/dr1 = dL/db_o
    kFd.ExpectMatch(Slice(da, 0, kD), s.Numeric(loss, s.P.b_qkv + 2 * kD, kD));  // = dL/db_v
  }
}

// The attention output of the last query from the rows' embeddings x (length x kD), written out
// here in double as the reference for dL/dx: q = W_q x_last + b_q, k_t, v_t likewise,
// a = sum_t softmax_t(q . k_t / sqrt(D)) v_t.
std::vector<double> AttentionOutput(const Transformer& s, const std::vector<double>& x) {
  const double* w = s.params.data() + s.P.w_qkv;
  const double* b = s.params.data() + s.P.b_qkv;
  auto project = [&](int which, const double* xt, int i) {
    double acc = b[which * kD + i];
    for (int c = 0; c < kD; ++c) acc += w[(which * kD + i) * kD + c] * xt[c];
    return acc;
  };
  const double* x_last = x.data() + std::size_t(s.length - 1) * kD;
  std::vector<double> scores(s.length), a(kD, 0.0);
  double largest = -1e300, sum = 0;
  for (int t = 0; t < s.length; ++t) {
    double dot = 0;
    for (int i = 0; i < kD; ++i) dot += project(0, x_last, i) * project(1, &x[t * kD], i);
    scores[t] = dot / std::sqrt(double(kD));
    largest = std::max(largest, scores[t]);
  }
  for (double& v : scores) sum += (v = std::exp(v - largest));
  for (int t = 0; t < s.length; ++t)
    for (int i = 0; i < kD; ++i) a[i] += scores[t] / sum * project(2, &x[t * kD], i);
  return a;
}

TEST(ContextLearnerStages, AttentionBackwardMatchesFiniteDifferencesOverSeveralRows) {
  for (int length : {2, 5, 12}) {
    SCOPED_TRACE(length);
    const Transformer s(length);
    const TransformerTape S(length);
    const std::vector<double> g = Uniform(kD, 5, 1.0);  // dL/da
    const ContextTape<double> tape = s.Tape(s.params);
    std::vector<double> dp(s.params.size(), 0.0), dx(std::size_t(length) * kD, 0.0);
    context_internal::AttentionBackward(s.P, S, s.params.data(), tape.values.data(), length,
                                        g.data(), dp.data(), dx.data());
    const auto loss = [&](const std::vector<double>& p) { return s.Dot(p, S.a, g); };
    // W_qkv and b_qkv.
    const std::size_t first = s.P.w_qkv, count = s.P.w_o - s.P.w_qkv;
    kFd.ExpectMatch(Slice(dp, first, count), s.Numeric(loss, first, count));
    ExpectZeroOutside(dp, first, s.P.w_o);
    // dL/dx of every row against the reference above on the tape's embeddings.
    const std::vector<double> x(tape.values.begin() + S.x,
                                tape.values.begin() + S.x + std::size_t(length) * kD);
    const auto a_x = [&](const FdVector& xv) {
      const std::vector<double> a = AttentionOutput(s, {xv.data(), xv.data() + xv.size()});
      double l = 0;
      for (int i = 0; i < kD; ++i) l += g[i] * a[i];
      return l;
    };
    ASSERT_NEAR(a_x(Slice(x, 0, x.size())), loss(s.params), 1e-12);  // the reference is a
    kFd.ExpectMatch(Slice(dx, 0, dx.size()), kFd.Gradient(a_x, Slice(x, 0, x.size())));
    // And through the production forward: x_t = E row_t + b_E + P_t, so dL/dE = sum_t dx_t
    // row_t^T and dL/db_E = sum_t dx_t.
    std::vector<double> d_embed(std::size_t(kD) * kIn + kD, 0.0);
    for (int t = 0; t < length; ++t)
      for (int i = 0; i < kD; ++i) {
        for (int c = 0; c < kIn; ++c) d_embed[i * kIn + c] += dx[t * kD + i] * s.rows[t * kIn + c];
        d_embed[kD * kIn + i] += dx[t * kD + i];
      }
    kFd.ExpectMatch(Slice(d_embed, 0, d_embed.size()), s.Numeric(loss, s.P.e, d_embed.size()));
  }
}

}  // namespace
}  // namespace hdr4d::method
