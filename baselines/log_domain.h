// Log-domain arithmetic shared by the baseline tone mappers. Their inputs are natural logs of
// radiance spanning many decades, so every mapper works on logs and never forms a radiance, a
// square of one or a ratio of two: each step below is written so that no input in the clamped
// range can overflow, underflow to a 0/0 or take the log of 0.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/util/sigmoid.h"

namespace hdr4d::baselines {

// Log-radiance inputs are clamped to +-kMaxAbsLogInput before the exposure is added: e^60 is
// about 1e26, far outside any physical scene, yet e^(60 + log of the longest exposure) still fits
// a float. So log 0 = -inf maps like radiance e^-60 (black), +inf like e^60 (white). Outside the
// clamp the input's gradient is 0 (the clamp's own derivative). NaN is not clamped: it propagates,
// so a bug upstream stays visible (the convention of core/radiometry/crf.h).
inline constexpr double kMaxAbsLogInput = 60.0;
// Learned log-parameters (key, white point, gamma, compression) are clamped to +-kMaxAbsLogParam
// where they are used (a box constraint: zero gradient outside), so no optimiser step can drive
// a scale to 0 or infinity.
inline constexpr double kMaxAbsLogParam = 20.0;

// Rec. 709 / sRGB relative luminance of linear RGB.
inline constexpr double kLuminanceWeights[3] = {0.2126, 0.7152, 0.0722};

template <typename T>
inline T ClampAbs(T x, double bound) {
  return x < T(-bound) ? T(-bound) : (x > T(bound) ? T(bound) : x);
}

// d ClampAbs / dx: 1 strictly inside, 0 outside (and at the bound, where it is a kink).
template <typename T>
inline T ClampAbsSlope(T x, double bound) {
  return (x > T(-bound) && x < T(bound)) ? T(1) : T(0);
}

// log(1 + e^z) for any finite z (core/util/sigmoid.h).
using hdr4d::Softplus;

// Logistic function; never the exponential of a large positive number (core/util/sigmoid.h).
template <typename T>
inline T Logistic(T z) {
  return StableSigmoid(z);
}

// log of the luminance sum_c w_c e^{x_c} of three log-RGB values, by log-sum-exp around the
// largest term. share (optional, 3 values) receives each channel's fraction of the luminance,
// w_c e^{x_c} / L, which is also d log L / d x_c.
template <typename T>
inline T LogLuminance(const T* x, T* share = nullptr) {
  T t[3];
  for (int c = 0; c < 3; ++c) t[c] = x[c] + T(std::log(kLuminanceWeights[c]));
  const T m = std::max(t[0], std::max(t[1], t[2]));
  T e[3], sum = T(0);
  for (int c = 0; c < 3; ++c) sum += (e[c] = std::exp(t[c] - m));  // the largest term is 1
  if (share) {
    for (int c = 0; c < 3; ++c) share[c] = e[c] / sum;
  }
  return m + std::log(sum);
}

// Display encoding of a log colour: y = min(C, 1)^(1 / gamma) = exp(min(log C, 0) / gamma).
// Finite and in [0, 1] for every finite log C and finite 1/gamma > 0.
template <typename T>
inline T DisplayEncode(T log_c, T inv_gamma) {
  return std::exp(std::min(log_c, T(0)) * inv_gamma);
}

// Backward of DisplayEncode given its output y: dy/dlog_c (0 where the colour is clipped at 1)
// and dy/d(inv_gamma).
template <typename T>
inline void DisplayEncodeSlopes(T log_c, T inv_gamma, T y, T* dy_dlog_c, T* dy_dinv_gamma) {
  const bool lit = log_c < T(0);
  *dy_dlog_c = lit ? y * inv_gamma : T(0);
  *dy_dinv_gamma = lit ? y * log_c : T(0);
}

}  // namespace hdr4d::baselines
