// A small fully connected network, forward and backward side by side, templated on the scalar
// so finite-difference tests run it in double. Used by the tone curves of the Dynamic Tone
// Mapper (per channel 1+d -> 64 -> 64 -> 1) and by the static MLP of HDR-GS (1 -> 128 -> 1):
// ReLU on hidden layers, and a chosen activation on the output.
//
// Parameters are one flat array, per layer l (in order): W_l (out x in, row-major), then b_l.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "core/util/sigmoid.h"

namespace hdr4d::method {

enum class MlpOutput { kLinear, kSigmoid };

struct MlpShape {
  std::vector<int> widths;  // input width first, output width last (at least 2 entries)
  MlpOutput output = MlpOutput::kSigmoid;

  int inputs() const { return widths.front(); }
  int outputs() const { return widths.back(); }
  int layers() const { return static_cast<int>(widths.size()) - 1; }
  std::size_t NumParams() const {
    std::size_t n = 0;
    for (int l = 0; l < layers(); ++l) n += std::size_t(widths[l + 1]) * (widths[l] + 1);
    return n;
  }
  // Floats of the activation cache: every layer's output (the input is not copied).
  std::size_t CacheSize() const {
    std::size_t n = 0;
    for (int l = 1; l <= layers(); ++l) n += widths[l];
    return n;
  }
  // The widest layer (scratch size for the backward's running gradient).
  int MaxWidth() const { return *std::max_element(widths.begin(), widths.end()); }
};

// PyTorch's default nn.Linear initialisation: W and b uniform in +-1/sqrt(fan_in).
template <typename T>
void MlpInit(const MlpShape& shape, std::uint64_t seed, T* params) {
  std::mt19937_64 rng(seed);
  std::size_t o = 0;
  for (int l = 0; l < shape.layers(); ++l) {
    const int in = shape.widths[l], out = shape.widths[l + 1];
    const double bound = 1.0 / std::sqrt(double(in));
    std::uniform_real_distribution<double> u(-bound, bound);
    for (int i = 0; i < out * in + out; ++i) params[o++] = T(u(rng));
  }
}

// out = f(x); cache (shape.CacheSize()) keeps each layer's activated output for the backward.
template <typename T>
void MlpForward(const MlpShape& shape, const T* params, const T* x, T* out, T* cache) {
  const T* in = x;
  T* act = cache;
  const T* p = params;
  for (int l = 0; l < shape.layers(); ++l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    const T* W = p;
    const T* b = p + std::size_t(no) * ni;
    const bool last = l + 1 == shape.layers();
    for (int o = 0; o < no; ++o) {
      T z = b[o];
      const T* w = W + std::size_t(o) * ni;
      for (int i = 0; i < ni; ++i) z += w[i] * in[i];
      if (!last) {
        act[o] = z > T(0) ? z : T(0);
      } else {
        act[o] = shape.output == MlpOutput::kSigmoid ? StableSigmoid(z) : z;
      }
    }
    p = b + no;
    in = act;
    act += no;
  }
  std::copy(in, in + shape.outputs(), out);
}

// Backward of MlpForward for the same x and cache: dL_dx (may be null) is overwritten,
// dL_dparams is ADDED to. scratch: 2 x shape.MaxWidth() values.
template <typename T>
void MlpBackward(const MlpShape& shape,
                 const T* params,
                 const T* x,
                 const T* cache,
                 const T* dL_dout,
                 T* dL_dx,
                 T* dL_dparams,
                 T* scratch) {
  const int L = shape.layers();
  // Offsets of the current layer's parameters and cached outputs, walked from the end (no
  // allocation: this runs once per value on the tone mapper's direct path).
  std::size_t poff = shape.NumParams(), coff = shape.CacheSize();
  const int w_max = shape.MaxWidth();
  T* dz = scratch;           // dL/d(pre-activation) of the current layer
  T* din = scratch + w_max;  // dL/d(its input)
  {
    const int no = shape.outputs();
    const T* y = cache + shape.CacheSize() - no;
    for (int o = 0; o < no; ++o) {
      dz[o] = shape.output == MlpOutput::kSigmoid ? dL_dout[o] * y[o] * (T(1) - y[o]) : dL_dout[o];
    }
  }
  for (int l = L - 1; l >= 0; --l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    poff -= std::size_t(no) * (ni + 1);
    coff -= no;
    const T* in = l == 0 ? x : cache + coff - ni;
    const T* W = params + poff;
    T* dW = dL_dparams + poff;
    T* db = dW + std::size_t(no) * ni;
    std::fill(din, din + ni, T(0));
    for (int o = 0; o < no; ++o) {
      const T g = dz[o];
      if (g == T(0)) continue;
      db[o] += g;
      const T* w = W + std::size_t(o) * ni;
      T* dw = dW + std::size_t(o) * ni;
      for (int i = 0; i < ni; ++i) {
        dw[i] += g * in[i];
        din[i] += g * w[i];
      }
    }
    if (l == 0) {
      if (dL_dx) std::copy(din, din + ni, dL_dx);
    } else {
      // Through the ReLU of the layer below: its cached output is 0 where it was cut.
      for (int i = 0; i < ni; ++i) dz[i] = in[i] > T(0) ? din[i] : T(0);
    }
  }
}

}  // namespace hdr4d::method
