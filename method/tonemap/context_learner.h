// The dynamic radiance context learner of the Dynamic Tone Mapper (paper §3.3, Table 7): a
// sequence of L rows of 3 values (the radiance-bank window, oldest first, 1 <= L <= k) -> the
// context vector f of size d. Its input is detached (the reference calls .detach() on the
// window), so the backward gives parameter gradients only, through time.
//
// Kinds, all with one layer and a zero initial state, parameters in PyTorch's order:
//   gru   nn.GRU(3, d): r = s(W_ir x + b_ir + W_hr h + b_hr), z = s(W_iz x + b_iz + W_hz h + b_hz),
//         n = tanh(W_in x + b_in + r * (W_hn h + b_hn)), h' = (1 - z) * n + z * h; f = final h.
//         Layout: W_ih (3d x 3, rows r|z|n), W_hh (3d x d), b_ih (3d), b_hh (3d).
//   rnn   nn.RNN(3, d), tanh: h' = tanh(W_ih x + b_ih + W_hh h + b_hh); f = final h.
//         Layout: W_ih (d x 3), W_hh (d x d), b_ih (d), b_hh (d).
//   lstm  nn.LSTM(3, d): gates i, f, g, o (sigmoid, sigmoid, tanh, sigmoid) of
//         W_ih x + b_ih + W_hh h + b_hh; c' = f * c + i * g, h' = o * tanh(c'); f = final h.
//         Layout: W_ih (4d x 3, rows i|f|g|o), W_hh (4d x d), b_ih (4d), b_hh (4d).
//   PyTorch's recurrent init: every parameter uniform in +-1/sqrt(d).
//
//   transformer  One post-norm encoder layer (the paper gives no more detail; this is what we
//         built): X_t = E x_t + b_E + P_t (E: D x 3, model width D = kModelWidth, P_t the
//         sinusoidal position code of position t in the window: P[2i] = sin(t / 10000^(2i/D)),
//         P[2i+1] = cos(same)); single-head self-attention without mask, softmax(q K^T / sqrt(D))
//         V with q, K, V = W_q|k|v X + b_q|k|v, then the output projection W_o + b_o; residual and
//         LayerNorm (eps 1e-5, affine); a ReLU feed-forward D -> kFeedForwardWidth -> D;
//         residual and LayerNorm; the last position's vector -> linear D -> d = f.
//         Only the last position is read and there is one layer, so only its query, attention
//         row, feed-forward and norms are computed (the other positions enter as keys and
//         values): exactly the last output of the full layer.
//         Layout: E, b_E | W_qkv (3D x D, rows q|k|v), b_qkv (3D) | W_o (D x D), b_o (D) |
//         LN1 gamma, beta (D each) | W_1 (F x D), b_1 (F) | W_2 (D x F), b_2 (D) |
//         LN2 gamma, beta | W_head (d x D), b_head (d).
//         PyTorch's init per module: Linear U(+-1/sqrt(fan_in)) for weight and bias;
//         attention in-projection Xavier uniform, its biases and the output projection's bias 0;
//         LayerNorm gamma 1, beta 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hdr4d::method {

enum class ContextKind { kGru, kRnn, kLstm, kTransformer };

// "gru" | "rnn" | "lstm" | "transformer"; nullopt for any other name.
std::optional<ContextKind> ParseContextKind(std::string_view name);
const char* ContextKindName(ContextKind kind);

struct ContextLearnerShape {
  static constexpr int kInputs = 3;             // one radiance-bank row (mean log-HDR RGB)
  static constexpr int kModelWidth = 16;        // transformer D
  static constexpr int kFeedForwardWidth = 32;  // transformer F
  ContextKind kind = ContextKind::kGru;
  int size = 2;  // d

  std::size_t NumParams() const;
};

// Forward intermediates the backward needs (sized by the forward, reused across frames).
template <typename T>
struct ContextTape {
  int length = 0;
  std::vector<T> values;
};

template <typename T>
void ContextLearnerInit(const ContextLearnerShape& shape, std::uint64_t seed, T* params);

// rows: length x 3 (oldest first), length >= 1. f: shape.size values.
template <typename T>
void ContextLearnerForward(const ContextLearnerShape& shape,
                           const T* params,
                           const T* rows,
                           int length,
                           T* f,
                           ContextTape<T>* tape);

// Back-propagation through time of dL/df for the forward that filled `tape` (same params and
// rows); ADDS to dL_dparams.
template <typename T>
void ContextLearnerBackward(const ContextLearnerShape& shape,
                            const T* params,
                            const T* rows,
                            const ContextTape<T>& tape,
                            const T* dL_df,
                            T* dL_dparams);

}  // namespace hdr4d::method
