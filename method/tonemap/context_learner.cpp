#include "method/tonemap/context_learner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/util/error.h"
#include "method/tonemap/context_learner_internal.h"
#include "method/tonemap/mlp.h"

namespace hdr4d::method {
using namespace context_internal;
namespace {

constexpr double kLayerNormEps = 1e-5;

// ---- small dense helpers (row-major W: rows x cols) ------------------------------------------

// out += W x
template <typename T>
void MatVecAdd(const T* W, int rows, int cols, const T* x, T* out) {
  for (int r = 0; r < rows; ++r) {
    T s = T(0);
    for (int c = 0; c < cols; ++c) s += W[r * cols + c] * x[c];
    out[r] += s;
  }
}

// out += W^T g
template <typename T>
void MatTVecAdd(const T* W, int rows, int cols, const T* g, T* out) {
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) out[c] += W[r * cols + c] * g[r];
  }
}

// dW += g x^T
template <typename T>
void OuterAdd(T* dW, int rows, int cols, const T* g, const T* x) {
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) dW[r * cols + c] += g[r] * x[c];
  }
}

int Gates(ContextKind kind) {
  switch (kind) {
    case ContextKind::kRnn:
      return 1;
    case ContextKind::kGru:
      return 3;
    case ContextKind::kLstm:
      return 4;
    case ContextKind::kTransformer:
      break;
  }
  return 0;
}

// Offsets of a recurrent learner's parameters (PyTorch order).
struct RecurrentLayout {
  int h, g;  // hidden size, gates
  std::size_t w_ih, w_hh, b_ih, b_hh, total;
  RecurrentLayout(int size, int gates) : h(size), g(gates) {
    w_ih = 0;
    w_hh = w_ih + std::size_t(g) * h * kIn;
    b_ih = w_hh + std::size_t(g) * h * h;
    b_hh = b_ih + std::size_t(g) * h;
    total = b_hh + std::size_t(g) * h;
  }
};

template <typename T>
T PositionCode(int position, int i) {
  const double rate = std::pow(10000.0, -double(2 * (i / 2)) / kD);
  return T(i % 2 == 0 ? std::sin(position * rate) : std::cos(position * rate));
}

// y = gamma * xhat + beta with xhat = (r - mean) / sqrt(var + eps); keeps xhat and 1/sigma.
template <typename T>
void LayerNorm(const T* r, const T* gamma, const T* beta, T* xhat, T* inv_sigma, T* y) {
  T mean = T(0);
  for (int i = 0; i < kD; ++i) mean += r[i];
  mean /= T(kD);
  T var = T(0);
  for (int i = 0; i < kD; ++i) var += (r[i] - mean) * (r[i] - mean);
  var /= T(kD);
  const T inv = T(1) / std::sqrt(var + T(kLayerNormEps));
  for (int i = 0; i < kD; ++i) {
    xhat[i] = (r[i] - mean) * inv;
    y[i] = gamma[i] * xhat[i] + beta[i];
  }
  *inv_sigma = inv;
}

// dr = dL/dr from dy; adds the gamma and beta gradients.
template <typename T>
void LayerNormBackward(
    const T* dy, const T* gamma, const T* xhat, T inv_sigma, T* dgamma, T* dbeta, T* dr) {
  T dxhat[kD];
  T mean_d = T(0), mean_dx = T(0);
  for (int i = 0; i < kD; ++i) {
    dgamma[i] += dy[i] * xhat[i];
    dbeta[i] += dy[i];
    dxhat[i] = dy[i] * gamma[i];
    mean_d += dxhat[i];
    mean_dx += dxhat[i] * xhat[i];
  }
  mean_d /= T(kD);
  mean_dx /= T(kD);
  for (int i = 0; i < kD; ++i) dr[i] = inv_sigma * (dxhat[i] - mean_d - xhat[i] * mean_dx);
}

// ---- recurrent kinds -------------------------------------------------------------------------

template <typename T>
int RecurrentTapeStride(ContextKind kind, int h) {
  switch (kind) {
    case ContextKind::kRnn:
      return 2 * h;  // h_prev, h
    case ContextKind::kGru:
      return 5 * h;  // h_prev, r, z, n, W_hn h + b_hn
    case ContextKind::kLstm:
      return 7 * h;  // h_prev, c_prev, i, f, g, o, tanh(c)
    case ContextKind::kTransformer:
      break;
  }
  return 0;
}

template <typename T>
void RecurrentForward(const ContextLearnerShape& shape,
                      const T* params,
                      const T* rows,
                      int length,
                      T* f,
                      ContextTape<T>* tape) {
  const int h = shape.size, g = Gates(shape.kind);
  const RecurrentLayout lay(h, g);
  const int stride = RecurrentTapeStride<T>(shape.kind, h);
  tape->length = length;
  tape->values.assign(std::size_t(length) * stride, T(0));
  std::vector<T> hs(h, T(0)), cs(h, T(0)), gi(g * h), gh(g * h);
  for (int t = 0; t < length; ++t) {
    const T* x = rows + std::size_t(t) * kIn;
    T* rec = tape->values.data() + std::size_t(t) * stride;
    std::copy(params + lay.b_ih, params + lay.b_ih + g * h, gi.begin());
    MatVecAdd(params + lay.w_ih, g * h, kIn, x, gi.data());
    std::copy(params + lay.b_hh, params + lay.b_hh + g * h, gh.begin());
    MatVecAdd(params + lay.w_hh, g * h, h, hs.data(), gh.data());
    std::copy(hs.begin(), hs.end(), rec);  // h_prev
    if (shape.kind == ContextKind::kRnn) {
      for (int j = 0; j < h; ++j) hs[j] = std::tanh(gi[j] + gh[j]);
      std::copy(hs.begin(), hs.end(), rec + h);
    } else if (shape.kind == ContextKind::kGru) {
      T* r = rec + h;
      T* z = rec + 2 * h;
      T* n = rec + 3 * h;
      T* ghn = rec + 4 * h;
      for (int j = 0; j < h; ++j) {
        r[j] = StableSigmoid(gi[j] + gh[j]);
        z[j] = StableSigmoid(gi[h + j] + gh[h + j]);
        ghn[j] = gh[2 * h + j];
        n[j] = std::tanh(gi[2 * h + j] + r[j] * ghn[j]);
        hs[j] = (T(1) - z[j]) * n[j] + z[j] * hs[j];
      }
    } else {  // LSTM
      T* cp = rec + h;
      T* ig = rec + 2 * h;
      T* fg = rec + 3 * h;
      T* gg = rec + 4 * h;
      T* og = rec + 5 * h;
      T* tc = rec + 6 * h;
      std::copy(cs.begin(), cs.end(), cp);
      for (int j = 0; j < h; ++j) {
        ig[j] = StableSigmoid(gi[j] + gh[j]);
        fg[j] = StableSigmoid(gi[h + j] + gh[h + j]);
        gg[j] = std::tanh(gi[2 * h + j] + gh[2 * h + j]);
        og[j] = StableSigmoid(gi[3 * h + j] + gh[3 * h + j]);
        cs[j] = fg[j] * cs[j] + ig[j] * gg[j];
        tc[j] = std::tanh(cs[j]);
        hs[j] = og[j] * tc[j];
      }
    }
  }
  std::copy(hs.begin(), hs.end(), f);
}

template <typename T>
void RecurrentBackward(const ContextLearnerShape& shape,
                       const T* params,
                       const T* rows,
                       const ContextTape<T>& tape,
                       const T* dL_df,
                       T* dp) {
  const int h = shape.size, g = Gates(shape.kind);
  const RecurrentLayout lay(h, g);
  const int stride = RecurrentTapeStride<T>(shape.kind, h);
  std::vector<T> dh(dL_df, dL_df + h), dc(h, T(0)), dgi(g * h), dgh(g * h), dh_prev(h);
  for (int t = tape.length - 1; t >= 0; --t) {
    const T* x = rows + std::size_t(t) * kIn;
    const T* rec = tape.values.data() + std::size_t(t) * stride;
    const T* hp = rec;
    std::fill(dh_prev.begin(), dh_prev.end(), T(0));
    if (shape.kind == ContextKind::kRnn) {
      const T* hn = rec + h;
      for (int j = 0; j < h; ++j) dgi[j] = dgh[j] = dh[j] * (T(1) - hn[j] * hn[j]);
    } else if (shape.kind == ContextKind::kGru) {
      const T* r = rec + h;
      const T* z = rec + 2 * h;
      const T* n = rec + 3 * h;
      const T* ghn = rec + 4 * h;
      for (int j = 0; j < h; ++j) {
        const T dn = dh[j] * (T(1) - z[j]);
        const T dz = dh[j] * (hp[j] - n[j]);
        dh_prev[j] = dh[j] * z[j];
        const T dan = dn * (T(1) - n[j] * n[j]);
        const T dar = dan * ghn[j] * r[j] * (T(1) - r[j]);
        const T daz = dz * z[j] * (T(1) - z[j]);
        dgi[j] = dgh[j] = dar;
        dgi[h + j] = dgh[h + j] = daz;
        dgi[2 * h + j] = dan;
        dgh[2 * h + j] = dan * r[j];
      }
    } else {  // LSTM
      const T* cp = rec + h;
      const T* ig = rec + 2 * h;
      const T* fg = rec + 3 * h;
      const T* gg = rec + 4 * h;
      const T* og = rec + 5 * h;
      const T* tc = rec + 6 * h;
      for (int j = 0; j < h; ++j) {
        const T dcj = dc[j] + dh[j] * og[j] * (T(1) - tc[j] * tc[j]);
        const T d_o = dh[j] * tc[j];
        const T d_i = dcj * gg[j];
        const T d_g = dcj * ig[j];
        const T d_f = dcj * cp[j];
        dc[j] = dcj * fg[j];
        dgi[j] = d_i * ig[j] * (T(1) - ig[j]);
        dgi[h + j] = d_f * fg[j] * (T(1) - fg[j]);
        dgi[2 * h + j] = d_g * (T(1) - gg[j] * gg[j]);
        dgi[3 * h + j] = d_o * og[j] * (T(1) - og[j]);
      }
      std::copy(dgi.begin(), dgi.end(), dgh.begin());
    }
    OuterAdd(dp + lay.w_ih, g * h, kIn, dgi.data(), x);
    OuterAdd(dp + lay.w_hh, g * h, h, dgh.data(), hp);
    for (int j = 0; j < g * h; ++j) {
      dp[lay.b_ih + j] += dgi[j];
      dp[lay.b_hh + j] += dgh[j];
    }
    MatTVecAdd(params + lay.w_hh, g * h, h, dgh.data(), dh_prev.data());
    dh.swap(dh_prev);
  }
}

// ---- transformer -----------------------------------------------------------------------------

template <typename T>
void TransformerForward(const ContextLearnerShape& shape,
                        const T* params,
                        const T* rows,
                        int length,
                        T* f,
                        ContextTape<T>* tape) {
  const TransformerLayout P(shape.size);
  const TransformerTape S(length);
  tape->length = length;
  tape->values.assign(S.total, T(0));
  T* v = tape->values.data();
  const T* wq = params + P.w_qkv;
  const T* wk = wq + kD * kD;
  const T* wv = wk + kD * kD;
  const T* bq = params + P.b_qkv;
  const T* bk = bq + kD;
  const T* bv = bk + kD;
  for (int t = 0; t < length; ++t) {
    T* x = v + S.x + std::size_t(t) * kD;
    for (int i = 0; i < kD; ++i) x[i] = params[P.b_e + i] + PositionCode<T>(t, i);
    MatVecAdd(params + P.e, kD, kIn, rows + std::size_t(t) * kIn, x);
    T* k = v + S.k + std::size_t(t) * kD;
    T* vv = v + S.v + std::size_t(t) * kD;
    std::copy(bk, bk + kD, k);
    std::copy(bv, bv + kD, vv);
    MatVecAdd(wk, kD, kD, x, k);
    MatVecAdd(wv, kD, kD, x, vv);
  }
  const T* x_last = v + S.x + std::size_t(length - 1) * kD;
  T* q = v + S.q;
  std::copy(bq, bq + kD, q);
  MatVecAdd(wq, kD, kD, x_last, q);
  // Attention row of the last query: softmax with the maximum subtracted (no overflow).
  T* p = v + S.p;
  const T scale = T(1) / std::sqrt(T(kD));
  T s_max = -std::numeric_limits<T>::infinity();
  for (int t = 0; t < length; ++t) {
    T s = T(0);
    for (int i = 0; i < kD; ++i) s += q[i] * v[S.k + std::size_t(t) * kD + i];
    p[t] = s * scale;
    s_max = std::max(s_max, p[t]);
  }
  T sum = T(0);
  for (int t = 0; t < length; ++t) {
    p[t] = std::exp(p[t] - s_max);
    sum += p[t];
  }
  for (int t = 0; t < length; ++t) p[t] /= sum;  // sum >= 1: the maximum contributes exp(0)
  T* a = v + S.a;
  for (int t = 0; t < length; ++t) {
    for (int i = 0; i < kD; ++i) a[i] += p[t] * v[S.v + std::size_t(t) * kD + i];
  }
  T r1[kD];
  for (int i = 0; i < kD; ++i) r1[i] = x_last[i] + params[P.b_o + i];
  MatVecAdd(params + P.w_o, kD, kD, a, r1);
  T* y1 = v + S.y1;
  LayerNorm(r1, params + P.g1, params + P.be1, v + S.xhat1, v + S.inv1, y1);
  T* hid = v + S.hid;
  std::copy(params + P.b1, params + P.b1 + kF, hid);
  MatVecAdd(params + P.w1, kF, kD, y1, hid);
  for (int j = 0; j < kF; ++j) hid[j] = hid[j] > T(0) ? hid[j] : T(0);
  T r2[kD];
  for (int i = 0; i < kD; ++i) r2[i] = y1[i] + params[P.b2 + i];
  MatVecAdd(params + P.w2, kD, kF, hid, r2);
  T* y2 = v + S.y2;
  LayerNorm(r2, params + P.g2, params + P.be2, v + S.xhat2, v + S.inv2, y2);
  std::copy(params + P.b_head, params + P.b_head + shape.size, f);
  MatVecAdd(params + P.w_head, shape.size, kD, y2, f);
}

}  // namespace

namespace context_internal {

// TransformerBackward's stages (declared, with what each does, in context_learner_internal.h).
template <typename T>
void FeedForwardBackward(const ContextLearnerShape& shape,
                         const TransformerLayout& P,
                         const TransformerTape& S,
                         const T* params,
                         const T* v,
                         const T* dL_df,
                         T* dp,
                         T* dy1) {
  // Head.
  OuterAdd(dp + P.w_head, shape.size, kD, dL_df, v + S.y2);
  for (int j = 0; j < shape.size; ++j) dp[P.b_head + j] += dL_df[j];
  T dy2[kD] = {};
  MatTVecAdd(params + P.w_head, shape.size, kD, dL_df, dy2);
  // Second norm and the feed-forward with its residual.
  T dr2[kD];
  LayerNormBackward(dy2, params + P.g2, v + S.xhat2, v[S.inv2], dp + P.g2, dp + P.be2, dr2);
  const T* hid = v + S.hid;
  OuterAdd(dp + P.w2, kD, kF, dr2, hid);
  for (int i = 0; i < kD; ++i) dp[P.b2 + i] += dr2[i];
  T dhid[kF] = {};
  MatTVecAdd(params + P.w2, kD, kF, dr2, dhid);
  for (int j = 0; j < kF; ++j) dhid[j] = hid[j] > T(0) ? dhid[j] : T(0);
  OuterAdd(dp + P.w1, kF, kD, dhid, v + S.y1);
  for (int j = 0; j < kF; ++j) dp[P.b1 + j] += dhid[j];
  std::copy(dr2, dr2 + kD, dy1);
  MatTVecAdd(params + P.w1, kF, kD, dhid, dy1);
}

// The first norm and the attention's output projection: dL/dy1 to dL/dr1 (also the residual's
// gradient at the last row's x) and dL/da.
template <typename T>
void OutputProjectionBackward(const TransformerLayout& P,
                              const TransformerTape& S,
                              const T* params,
                              const T* v,
                              const T* dy1,
                              T* dp,
                              T* dr1,
                              T* da) {
  LayerNormBackward(dy1, params + P.g1, v + S.xhat1, v[S.inv1], dp + P.g1, dp + P.be1, dr1);
  OuterAdd(dp + P.w_o, kD, kD, dr1, v + S.a);
  for (int i = 0; i < kD; ++i) dp[P.b_o + i] += dr1[i];
  MatTVecAdd(params + P.w_o, kD, kD, dr1, da);
}

// The attention of the last query over every row: dL/da to the q, k and v projections'
// gradients and dL/dx of every row (ADDED to dx, length x kD).
template <typename T>
void AttentionBackward(const TransformerLayout& P,
                       const TransformerTape& S,
                       const T* params,
                       const T* v,
                       int length,
                       const T* da,
                       T* dp,
                       T* dx) {
  T* dx_last = dx + std::size_t(length - 1) * kD;
  const T* p = v + S.p;
  const T* q = v + S.q;
  const T scale = T(1) / std::sqrt(T(kD));
  std::vector<T> dpt(length);
  T p_dot = T(0);
  for (int t = 0; t < length; ++t) {
    T s = T(0);
    for (int i = 0; i < kD; ++i) s += da[i] * v[S.v + std::size_t(t) * kD + i];
    dpt[t] = s;
    p_dot += p[t] * s;
  }
  const T* wq = params + P.w_qkv;
  const T* wk = wq + kD * kD;
  const T* wv = wk + kD * kD;
  T* dwq = dp + P.w_qkv;
  T* dwk = dwq + kD * kD;
  T* dwv = dwk + kD * kD;
  T* dbq = dp + P.b_qkv;
  T* dbk = dbq + kD;
  T* dbv = dbk + kD;
  T dq[kD] = {};
  for (int t = 0; t < length; ++t) {
    const T ds = p[t] * (dpt[t] - p_dot) * scale;  // through the softmax and the 1/sqrt(D)
    const T* x = v + S.x + std::size_t(t) * kD;
    const T* k = v + S.k + std::size_t(t) * kD;
    T dk[kD], dv[kD];
    for (int i = 0; i < kD; ++i) {
      dq[i] += ds * k[i];
      dk[i] = ds * q[i];
      dv[i] = p[t] * da[i];
      dbk[i] += dk[i];
      dbv[i] += dv[i];
    }
    OuterAdd(dwk, kD, kD, dk, x);
    OuterAdd(dwv, kD, kD, dv, x);
    T* dxt = dx + std::size_t(t) * kD;
    MatTVecAdd(wk, kD, kD, dk, dxt);
    MatTVecAdd(wv, kD, kD, dv, dxt);
  }
  const T* x_last = v + S.x + std::size_t(length - 1) * kD;
  OuterAdd(dwq, kD, kD, dq, x_last);
  for (int i = 0; i < kD; ++i) dbq[i] += dq[i];
  MatTVecAdd(wq, kD, kD, dq, dx_last);
}

#define HDR4D_INSTANTIATE_STAGES(T)                                                            \
  template void FeedForwardBackward<T>(const ContextLearnerShape&, const TransformerLayout&,  \
                                       const TransformerTape&, const T*, const T*, const T*, \
                                       T*, T*);                                              \
  template void OutputProjectionBackward<T>(const TransformerLayout&, const TransformerTape&, \
                                            const T*, const T*, const T*, T*, T*, T*);        \
  template void AttentionBackward<T>(const TransformerLayout&, const TransformerTape&,        \
                                     const T*, const T*, int, const T*, T*, T*);
HDR4D_INSTANTIATE_STAGES(float)
HDR4D_INSTANTIATE_STAGES(double)
#undef HDR4D_INSTANTIATE_STAGES

}  // namespace context_internal

namespace {

template <typename T>
void TransformerBackward(const ContextLearnerShape& shape,
                         const T* params,
                         const T* rows,
                         const ContextTape<T>& tape,
                         const T* dL_df,
                         T* dp) {
  const int length = tape.length;
  const TransformerLayout P(shape.size);
  const TransformerTape S(length);
  const T* v = tape.values.data();
  T dy1[kD];
  FeedForwardBackward(shape, P, S, params, v, dL_df, dp, dy1);
  T dr1[kD];
  T da[kD] = {};
  OutputProjectionBackward(P, S, params, v, dy1, dp, dr1, da);
  // The residual around the attention reaches the last row's x.
  std::vector<T> dx(std::size_t(length) * kD, T(0));
  T* dx_last = dx.data() + std::size_t(length - 1) * kD;
  for (int i = 0; i < kD; ++i) dx_last[i] += dr1[i];
  AttentionBackward(P, S, params, v, length, da, dp, dx.data());
  // Embedding.
  for (int t = 0; t < length; ++t) {
    const T* dxt = dx.data() + std::size_t(t) * kD;
    OuterAdd(dp + P.e, kD, kIn, dxt, rows + std::size_t(t) * kIn);
    for (int i = 0; i < kD; ++i) dp[P.b_e + i] += dxt[i];
  }
}

}  // namespace

std::optional<ContextKind> ParseContextKind(std::string_view name) {
  if (name == "gru") return ContextKind::kGru;
  if (name == "rnn") return ContextKind::kRnn;
  if (name == "lstm") return ContextKind::kLstm;
  if (name == "transformer") return ContextKind::kTransformer;
  return std::nullopt;
}

const char* ContextKindName(ContextKind kind) {
  switch (kind) {
    case ContextKind::kGru:
      return "gru";
    case ContextKind::kRnn:
      return "rnn";
    case ContextKind::kLstm:
      return "lstm";
    case ContextKind::kTransformer:
      return "transformer";
  }
  return "?";
}

std::size_t ContextLearnerShape::NumParams() const {
  if (kind == ContextKind::kTransformer) return TransformerLayout(size).total;
  return RecurrentLayout(size, Gates(kind)).total;
}

template <typename T>
void ContextLearnerInit(const ContextLearnerShape& shape, std::uint64_t seed, T* params) {
  std::mt19937_64 rng(seed);
  auto uniform = [&rng](T* out, std::size_t n, double bound) {
    std::uniform_real_distribution<double> u(-bound, bound);
    for (std::size_t i = 0; i < n; ++i) out[i] = T(u(rng));
  };
  if (shape.kind != ContextKind::kTransformer) {
    uniform(params, shape.NumParams(), 1.0 / std::sqrt(double(shape.size)));
    return;
  }
  const TransformerLayout P(shape.size);
  auto fill = [params](std::size_t at, std::size_t n, double value) {
    std::fill(params + at, params + at + n, T(value));
  };
  uniform(params + P.e, kD * kIn + kD, 1.0 / std::sqrt(double(kIn)));  // E and b_E
  uniform(params + P.w_qkv, 3 * kD * kD, std::sqrt(6.0 / (kD + 3 * kD)));
  fill(P.b_qkv, 3 * kD, 0.0);
  uniform(params + P.w_o, kD * kD, 1.0 / std::sqrt(double(kD)));
  fill(P.b_o, kD, 0.0);
  fill(P.g1, kD, 1.0);
  fill(P.be1, kD, 0.0);
  uniform(params + P.w1, kF * kD + kF, 1.0 / std::sqrt(double(kD)));  // W_1 and b_1
  uniform(params + P.w2, kD * kF + kD, 1.0 / std::sqrt(double(kF)));  // W_2 and b_2
  fill(P.g2, kD, 1.0);
  fill(P.be2, kD, 0.0);
  uniform(params + P.w_head, std::size_t(shape.size) * kD + shape.size,
          1.0 / std::sqrt(double(kD)));
}

template <typename T>
void ContextLearnerForward(const ContextLearnerShape& shape,
                           const T* params,
                           const T* rows,
                           int length,
                           T* f,
                           ContextTape<T>* tape) {
  HDR4D_CHECK(length >= 1);
  if (shape.kind == ContextKind::kTransformer) {
    TransformerForward(shape, params, rows, length, f, tape);
  } else {
    RecurrentForward(shape, params, rows, length, f, tape);
  }
}

template <typename T>
void ContextLearnerBackward(const ContextLearnerShape& shape,
                            const T* params,
                            const T* rows,
                            const ContextTape<T>& tape,
                            const T* dL_df,
                            T* dL_dparams) {
  HDR4D_CHECK(tape.length >= 1);
  if (shape.kind == ContextKind::kTransformer) {
    TransformerBackward(shape, params, rows, tape, dL_df, dL_dparams);
  } else {
    RecurrentBackward(shape, params, rows, tape, dL_df, dL_dparams);
  }
}

#define HDR4D_INSTANTIATE(T)                                                                      \
  template void ContextLearnerInit<T>(const ContextLearnerShape&, std::uint64_t, T*);             \
  template void ContextLearnerForward<T>(const ContextLearnerShape&, const T*, const T*, int, T*, \
                                         ContextTape<T>*);                                        \
  template void ContextLearnerBackward<T>(const ContextLearnerShape&, const T*, const T*,         \
                                          const ContextTape<T>&, const T*, T*);
HDR4D_INSTANTIATE(float)
HDR4D_INSTANTIATE(double)
#undef HDR4D_INSTANTIATE

}  // namespace hdr4d::method
