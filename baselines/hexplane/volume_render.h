// Alpha compositing along one ray, as the reference (TensoRF's raw2alpha): at sample i the
// density is sigma_i = softplus(f_i + shift) of the density feature f_i, the opacity
// alpha_i = 1 - exp(-sigma_i delta_i) with delta_i the step (times the distance scale), the
// transmittance T_i = prod_{j<i} (1 - alpha_j) and the weight w_i = alpha_i T_i. A pixel is
// sum_i w_i c_i + T_n b (colour c_i of K channels, background b). HDR-HexPlane composites its
// LDR and HDR colours with the same weights: K = 6.
#pragma once

#include <algorithm>
#include <cmath>

namespace hdr4d::baselines::hexplane {

template <typename T>
T Softplus(T x) {
  return std::max(x, T(0)) + std::log1p(std::exp(-std::abs(x)));
}

// alpha and weight of n samples; returns the transmittance left behind the last one.
template <typename T>
T CompositeWeights(const T* feature, const T* delta, int n, T shift, T* alpha, T* weight) {
  T transmittance = 1;
  for (int i = 0; i < n; ++i) {
    const T sigma = Softplus(feature[i] + shift);
    alpha[i] = -std::expm1(-sigma * delta[i]);
    weight[i] = alpha[i] * transmittance;
    transmittance *= T(1) - alpha[i];
  }
  return transmittance;
}

// out (K) = sum_i weight_i colour_i + transmittance * background.
template <typename T>
void Composite(const T* weight, const T* colour, int n, int K, T transmittance, const T* background,
               T* out) {
  for (int k = 0; k < K; ++k) out[k] = transmittance * background[k];
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < K; ++k) out[k] += weight[i] * colour[i * K + k];
}

// Backward of CompositeWeights + Composite for dL_dout (K): dL_dcolour (n x K) and dL_dfeature
// (n) overwritten. With R_i the colour seen behind sample i (R_{n-1} = b,
// R_{i-1} = alpha_i c_i + (1 - alpha_i) R_i), dout/dalpha_i = T_i (c_i - R_i): no division by
// 1 - alpha, which may be 0.
template <typename T>
void CompositeBackward(const T* feature, const T* delta, const T* alpha, const T* weight,
                       const T* colour, int n, int K, T shift, const T* background,
                       const T* dL_dout, T* dL_dcolour, T* dL_dfeature) {
  T behind[8];  // R, K <= 8
  for (int k = 0; k < K; ++k) behind[k] = background[k];
  // T_i = weight_i / alpha_i is unsafe at alpha 0: recompute it forwards first.
  T transmittance = 1;
  for (int i = 0; i < n; ++i) {
    dL_dfeature[i] = transmittance;  // T_i, kept here until the backward sweep
    transmittance *= T(1) - alpha[i];
  }
  for (int i = n - 1; i >= 0; --i) {
    const T t_i = dL_dfeature[i];
    T dalpha = 0;
    for (int k = 0; k < K; ++k) {
      const T c = colour[i * K + k];
      dL_dcolour[i * K + k] = weight[i] * dL_dout[k];
      dalpha += t_i * (c - behind[k]) * dL_dout[k];
      behind[k] = alpha[i] * c + (T(1) - alpha[i]) * behind[k];
    }
    const T x = feature[i] + shift;
    const T sig = x >= T(0) ? T(1) / (T(1) + std::exp(-x)) : std::exp(x) / (T(1) + std::exp(x));
    // dalpha/dsigma = (1 - alpha) delta; dsigma/df = sigmoid(f + shift).
    dL_dfeature[i] = dalpha * (T(1) - alpha[i]) * delta[i] * sig;
  }
}

}  // namespace hdr4d::baselines::hexplane
