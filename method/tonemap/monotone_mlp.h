// Tone curves that cannot decrease (issue 12 §2). A camera response is non-decreasing in
// exposure. An unconstrained curve MLP is not, and on multi-exposure data it learns a
// sawtooth: one rising branch per exposure, ln(16) apart for brackets 16x apart, so that a
// log-HDR squeezed into one exposure step (the truth to the power ~0.25) still reproduces every
// bracket (BENCHMARKS.md, "Why the learned HDR had the wrong shape"). A monotone curve cannot
// do that: two exposures of one pixel must then keep their order on one branch, which pins the
// log-HDR's scale to the exposures'.
//
// Construction: a ReLU network is non-decreasing in its input 0 when every weight on a path from
// that input to the output is >= 0: the column of input 0 in the first layer and every weight of
// the later layers. Those weights are used as |p| of the stored parameter p (the stored value
// keeps PyTorch's initialisation; |U(-b, b)| = U(0, b)); biases and the other inputs' weights
// (the Dynamic Tone Mapper's context) stay free. The pre-activation output is then also convex
// in input 0, and the sigmoid makes the curve an S: the logit of every usual response (gamma,
// filmic logistic, Naka-Rushton) is convex in log exposure. The gradient of |p| at p = 0 is
// taken as +1 so no weight can stick there.
#pragma once

#include <cstddef>

#include "method/tonemap/mlp.h"

namespace hdr4d::method {

// Whether flat parameter `index` of `shape` is a constrained (path-to-input-0) weight.
inline bool IsMonotoneWeight(const MlpShape& shape, std::size_t index) {
  std::size_t o = 0;
  for (int l = 0; l < shape.layers(); ++l) {
    const std::size_t in = shape.widths[l], out = shape.widths[l + 1];
    if (index < o + out * in) return l > 0 || (index - o) % in == 0;
    if (index < o + out * in + out) return false;  // a bias
    o += out * in + out;
  }
  return false;
}

// eff = raw with |.| on the constrained weights (shape.NumParams() values each).
template <typename T>
void MonotoneEffective(const MlpShape& shape, const T* raw, T* eff) {
  std::size_t o = 0;
  for (int l = 0; l < shape.layers(); ++l) {
    const int in = shape.widths[l], out = shape.widths[l + 1];
    for (int r = 0; r < out; ++r) {
      for (int i = 0; i < in; ++i, ++o) {
        eff[o] = (l > 0 || i == 0) && raw[o] < T(0) ? -raw[o] : raw[o];
      }
    }
    for (int r = 0; r < out; ++r, ++o) eff[o] = raw[o];
  }
}

// d_raw += d_eff, times sign(raw) (+1 at 0) on the constrained weights.
template <typename T, typename G>
void MonotoneGradientAdd(const MlpShape& shape, const T* raw, const G* d_eff, T* d_raw) {
  std::size_t o = 0;
  for (int l = 0; l < shape.layers(); ++l) {
    const int in = shape.widths[l], out = shape.widths[l + 1];
    for (int r = 0; r < out; ++r) {
      for (int i = 0; i < in; ++i, ++o) {
        const bool flip = (l > 0 || i == 0) && raw[o] < T(0);
        d_raw[o] += flip ? -T(d_eff[o]) : T(d_eff[o]);
      }
    }
    for (int r = 0; r < out; ++r, ++o) d_raw[o] += T(d_eff[o]);
  }
}

}  // namespace hdr4d::method
