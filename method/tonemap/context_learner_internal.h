// Internal to the context learner (context_learner.cpp) and its tests: the transformer's
// parameter and tape layouts and the three stages of its backward, exposed so that each stage can
// be checked alone against finite differences (context_learner_stages_test.cpp).
#pragma once

#include <cstddef>

#include "method/tonemap/context_learner.h"

namespace hdr4d::method::context_internal {

inline constexpr int kIn = ContextLearnerShape::kInputs;
inline constexpr int kD = ContextLearnerShape::kModelWidth;
inline constexpr int kF = ContextLearnerShape::kFeedForwardWidth;

// Offsets of the transformer's parameters (the layout in context_learner.h).
struct TransformerLayout {
  std::size_t e, b_e, w_qkv, b_qkv, w_o, b_o, g1, be1, w1, b1, w2, b2, g2, be2, w_head, b_head,
      total;
  explicit TransformerLayout(int d) {
    std::size_t o = 0;
    auto take = [&o](std::size_t n) {
      const std::size_t at = o;
      o += n;
      return at;
    };
    e = take(kD * kIn);
    b_e = take(kD);
    w_qkv = take(3 * kD * kD);
    b_qkv = take(3 * kD);
    w_o = take(kD * kD);
    b_o = take(kD);
    g1 = take(kD);
    be1 = take(kD);
    w1 = take(kF * kD);
    b1 = take(kF);
    w2 = take(kD * kF);
    b2 = take(kD);
    g2 = take(kD);
    be2 = take(kD);
    w_head = take(std::size_t(d) * kD);
    b_head = take(d);
    total = o;
  }
};

// Tape offsets of the transformer for a window of `length` rows.
struct TransformerTape {
  std::size_t x, k, v, q, p, a, xhat1, inv1, y1, hid, xhat2, inv2, y2, total;
  explicit TransformerTape(int length) {
    std::size_t o = 0;
    auto take = [&o](std::size_t n) {
      const std::size_t at = o;
      o += n;
      return at;
    };
    x = take(std::size_t(length) * kD);
    k = take(std::size_t(length) * kD);
    v = take(std::size_t(length) * kD);
    q = take(kD);
    p = take(length);
    a = take(kD);
    xhat1 = take(kD);
    inv1 = take(1);
    y1 = take(kD);
    hid = take(kF);
    xhat2 = take(kD);
    inv2 = take(1);
    y2 = take(kD);
    total = o;
  }
};

// The stages of the transformer's backward, last layer first; v: the forward's tape values
// (TransformerTape offsets), dp: parameter gradients, ADDED to.
// The head, the second norm and the feed-forward with its residual: dL/df to dL/dy1 (written).
template <typename T>
void FeedForwardBackward(const ContextLearnerShape& shape,
                         const TransformerLayout& P,
                         const TransformerTape& S,
                         const T* params,
                         const T* v,
                         const T* dL_df,
                         T* dp,
                         T* dy1);

// The first norm and the attention's output projection: dL/dy1 to dL/dr1 (written; also the
// residual's gradient at the last row's x) and dL/da (ADDED to).
template <typename T>
void OutputProjectionBackward(const TransformerLayout& P,
                              const TransformerTape& S,
                              const T* params,
                              const T* v,
                              const T* dy1,
                              T* dp,
                              T* dr1,
                              T* da);

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
                       T* dx);

}  // namespace hdr4d::method::context_internal
