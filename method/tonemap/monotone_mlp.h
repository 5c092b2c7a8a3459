// Tone curves that cannot decrease (issue 12 §2), opt-in (--monotone-tone-curves). A camera
// response is non-decreasing in exposure; an unconstrained curve MLP need not be, and with log
// colours learning at the reference's rate it learned a sawtooth: one rising branch per
// exposure, so that a squeezed log-HDR still reproduced every bracket. A monotone curve, though,
// learned a staircase that squeezes the same way (docs/history/accuracy.md, "Why the learned HDR
// had the wrong shape"): the cause was the colours' learning rate, not the curve's freedom.
//
// Construction: a ReLU network is non-decreasing in its input 0 when the product of the weights
// along every path from that input to the output is >= 0. Each hidden unit gets a fixed sign,
// + for even and - for odd units of every hidden layer (+ for the output and for input 0); a
// constrained weight is used as sign(unit) * sign(its input unit) * |p| of the stored parameter
// p, so every path's signs cancel. Constrained are the column of input 0 in the first layer and
// every weight of the later layers (the stored value keeps PyTorch's initialisation; |U(-b, b)|
// = U(0, b)); biases and the other inputs' weights (the Dynamic Tone Mapper's context) stay
// free. With both signs, rising (convex) and falling (concave) units combine into any
// non-decreasing piecewise-linear logit, unbounded at both ends, so the curve reaches 0 and 1.
// (An earlier all-positive form was convex: flat, a floor, left of its first kink.) The
// gradient of |p| at p = 0 is taken as +1 so no weight can stick there.
#pragma once

#include <cstddef>

#include "method/tonemap/mlp.h"

namespace hdr4d::method {

// The fixed sign of unit r of layer l's output (l = shape.layers() - 1 is the output layer).
inline int MonotoneUnitSign(const MlpShape& shape, int l, int r) {
  return l + 1 < shape.layers() && r % 2 == 1 ? -1 : 1;
}

// The sign a weight (row r, column i) of layer l is used with: 0 when unconstrained, else +-1.
inline int MonotoneWeightSign(const MlpShape& shape, int l, int r, int i) {
  if (l == 0) return i == 0 ? MonotoneUnitSign(shape, 0, r) : 0;
  return MonotoneUnitSign(shape, l, r) * MonotoneUnitSign(shape, l - 1, i);
}

// Calls visit(flat index, sign) for every weight and bias of `shape` (sign 0: unconstrained).
template <typename Visit>
void ForEachMonotoneSign(const MlpShape& shape, Visit&& visit) {
  std::size_t o = 0;
  for (int l = 0; l < shape.layers(); ++l) {
    const int in = shape.widths[l], out = shape.widths[l + 1];
    for (int r = 0; r < out; ++r) {
      for (int i = 0; i < in; ++i) visit(o++, MonotoneWeightSign(shape, l, r, i));
    }
    for (int r = 0; r < out; ++r) visit(o++, 0);
  }
}

// Whether flat parameter `index` of `shape` is a constrained (path-to-input-0) weight.
inline bool IsMonotoneWeight(const MlpShape& shape, std::size_t index) {
  bool constrained = false;
  ForEachMonotoneSign(shape, [&](std::size_t o, int sign) {
    if (o == index) constrained = sign != 0;
  });
  return constrained;
}

// eff = raw, with sign * |raw| on the constrained weights (shape.NumParams() values each).
template <typename T>
void MonotoneEffective(const MlpShape& shape, const T* raw, T* eff) {
  ForEachMonotoneSign(shape, [&](std::size_t o, int sign) {
    eff[o] = sign == 0 ? raw[o] : T(sign) * (raw[o] < T(0) ? -raw[o] : raw[o]);
  });
}

// d_raw += d_eff, times sign * sign(raw) (sign(0) = +1) on the constrained weights.
template <typename T, typename G>
void MonotoneGradientAdd(const MlpShape& shape, const T* raw, const G* d_eff, T* d_raw) {
  ForEachMonotoneSign(shape, [&](std::size_t o, int sign) {
    const int factor = sign == 0 ? 1 : (raw[o] < T(0) ? -sign : sign);
    d_raw[o] += factor < 0 ? -T(d_eff[o]) : T(d_eff[o]);
  });
}

}  // namespace hdr4d::method
