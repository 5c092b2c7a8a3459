// HexPlane's appearance regressor (the reference's General_MLP with its D-NeRF settings): the
// input is the appearance feature f, its positional encoding with `fea_pe` frequencies, the view
// direction d and its encoding with `view_pe` frequencies; then Linear-ReLU layers of `hidden`
// units and a Linear to 3 outputs (sigmoid for LDR colour; linear for HDR-HexPlane's log
// radiance). The last bias starts at zero (the reference's zero_init).
//
// Evaluated for a whole batch of samples at once as matrix products: the MLP is where most of
// an iteration's arithmetic goes. The templates below (Eigen) are the reference, in double for
// the finite-difference tests; training and rendering run AppMlpForward/AppMlpBackward, the same
// maths in float on the wide SIMD kernel of dense_simd.h (Eigen is built for the baseline ISA).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "method/tonemap/mlp.h"

namespace hdr4d::baselines::hexplane {

template <typename T>
using RowMatrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct AppMlpShape {
  int feature = 27, fea_pe = 2, view_pe = 2, hidden = 128, layers = 3;
  bool sigmoid_output = true;
  int Inputs() const { return feature * (1 + 2 * fea_pe) + 3 * (1 + 2 * view_pe); }
  // The same flat parameter layout as method/tonemap/mlp.h: per layer W (out x in), then b.
  method::MlpShape Layers() const {
    std::vector<int> widths = {Inputs()};
    for (int l = 0; l + 1 < layers; ++l) widths.push_back(hidden);
    widths.push_back(3);
    return {widths, sigmoid_output ? method::MlpOutput::kSigmoid : method::MlpOutput::kLinear};
  }
};

// PyTorch's default Linear initialisation, then the last bias zeroed.
std::vector<float> InitAppMlp(const AppMlpShape& shape, std::uint64_t seed);

// positional_encoding of the reference: x_i * 2^f for i, then f (i major), sines then cosines.
template <typename T>
void EncodeInput(const AppMlpShape& s, const T* feature, const T* dir, T* out) {
  auto encode = [&out](const T* x, int n, int freqs) {
    for (int i = 0; i < n; ++i) *out++ = x[i];
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < n; ++i)
        for (int f = 0; f < freqs; ++f) {
          const T a = x[i] * T(1 << f);
          *out++ = pass == 0 ? std::sin(a) : std::cos(a);
        }
  };
  encode(feature, s.feature, s.fea_pe);
  encode(dir, 3, s.view_pe);
}

// dL/dfeature from dL/d(encoded input) (the direction is a constant).
template <typename T>
void EncodeInputBackward(const AppMlpShape& s, const T* feature, const T* dL_din, T* dL_dfeature) {
  const int n = s.feature, F = s.fea_pe;
  for (int i = 0; i < n; ++i) {
    T g = dL_din[i];
    for (int f = 0; f < F; ++f) {
      const T k = T(1 << f), a = feature[i] * k;
      g += dL_din[n + i * F + f] * std::cos(a) * k;
      g -= dL_din[n + n * F + i * F + f] * std::sin(a) * k;
    }
    dL_dfeature[i] = g;
  }
}

// Forward for N rows of x (N x inputs). acts[l] keeps layer l's activated output (N x width).
template <typename T>
void BatchMlpForward(const method::MlpShape& shape, const T* params, const RowMatrix<T>& x,
                     std::vector<RowMatrix<T>>* acts) {
  acts->resize(shape.layers());
  const T* p = params;
  for (int l = 0; l < shape.layers(); ++l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    Eigen::Map<const RowMatrix<T>> W(p, no, ni);
    Eigen::Map<const Eigen::Matrix<T, 1, Eigen::Dynamic>> b(p + std::size_t(no) * ni, no);
    const RowMatrix<T>& in = l == 0 ? x : (*acts)[l - 1];
    RowMatrix<T>& out = (*acts)[l];
    out.noalias() = in * W.transpose();
    out.rowwise() += b;
    const bool last = l + 1 == shape.layers();
    if (!last) {
      out = out.cwiseMax(T(0));
    } else if (shape.output == method::MlpOutput::kSigmoid) {
      out = out.unaryExpr([](T z) { return StableSigmoid(z); });
    }
    p += std::size_t(no) * (ni + 1);
  }
}

// Backward: dL_dparams ADDED to, dL_dx overwritten (N x inputs; may be null).
template <typename T>
void BatchMlpBackward(const method::MlpShape& shape, const T* params, const RowMatrix<T>& x,
                      const std::vector<RowMatrix<T>>& acts, const RowMatrix<T>& dL_dout,
                      T* dL_dparams, RowMatrix<T>* dL_dx) {
  const int L = shape.layers();
  RowMatrix<T> dz = dL_dout;
  if (shape.output == method::MlpOutput::kSigmoid)
    dz = dz.cwiseProduct(acts[L - 1].unaryExpr([](T y) { return y * (T(1) - y); }));
  std::size_t poff = shape.NumParams();
  for (int l = L - 1; l >= 0; --l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    poff -= std::size_t(no) * (ni + 1);
    Eigen::Map<const RowMatrix<T>> W(params + poff, no, ni);
    Eigen::Map<RowMatrix<T>> dW(dL_dparams + poff, no, ni);
    Eigen::Map<Eigen::Matrix<T, 1, Eigen::Dynamic>> db(dL_dparams + poff + std::size_t(no) * ni,
                                                       no);
    const RowMatrix<T>& in = l == 0 ? x : acts[l - 1];
    dW.noalias() += dz.transpose() * in;
    db += dz.colwise().sum();
    if (l == 0 && !dL_dx) break;
    RowMatrix<T> din = dz * W;
    if (l == 0) {
      *dL_dx = std::move(din);
    } else {
      // Through the ReLU below: its output is 0 where it cut.
      dz = din.cwiseProduct(in.unaryExpr([](T a) { return a > T(0) ? T(1) : T(0); }));
    }
  }
}

// BatchMlpForward and BatchMlpBackward in float with their products on DenseProduct
// (dense_simd.h): same arguments and results, to float rounding.
void AppMlpForward(const method::MlpShape& shape, const float* params, const RowMatrix<float>& x,
                   std::vector<RowMatrix<float>>* acts);
void AppMlpBackward(const method::MlpShape& shape, const float* params, const RowMatrix<float>& x,
                    const std::vector<RowMatrix<float>>& acts, const RowMatrix<float>& dL_dout,
                    float* dL_dparams, RowMatrix<float>* dL_dx);

}  // namespace hdr4d::baselines::hexplane
