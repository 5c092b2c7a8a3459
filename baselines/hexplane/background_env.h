// A learned background for the grid family that does not depend on time (issue 53): what a ray
// sees behind the box. Not in the references: HexPlane and HDR-HexPlane composite over a fixed
// white background (random colours in training on some datasets: HexPlane_Base.py, `white_bg`),
// which fits D-NeRF's objects on white. The datagen scenes have a sky at infinity; with a fixed
// background the model paints it as density on the box's far faces per training time, and a
// held-out time interpolates painted and empty faces (docs/history/hexplane.md). Here the sky
// is a function of the view direction alone: real spherical harmonics of degree 0 ("learned":
// one colour) or 2 ("environment": 9 coefficients per channel) give a pre-activation p_k(d);
// the LDR model's background is sigmoid(p_k), the log-HDR model's p_k is ln radiance: HDR
// exp(p_k), LDR the same sigmoid tone mapper as the samples (the image's exposure and offset),
// so one sky serves every exposure.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "baselines/sigmoid_tone_mapper.h"

namespace hdr4d::baselines::hexplane {

// Coefficients per channel for a background model ("fixed", "learned", "environment"); -1 for
// an unknown name.
inline int BackgroundBasisSize(const std::string& model) {
  return model == "fixed" ? 0 : model == "learned" ? 1 : model == "environment" ? 9 : -1;
}

// The first n (1 or 9) real spherical harmonics at the unit direction d.
template <typename T>
void BackgroundBasis(const float d[3], int n, T* y) {
  const T x = d[0], v = d[1], z = d[2];
  y[0] = T(0.28209479177387814);
  if (n == 1) return;
  y[1] = T(-0.4886025119029199) * v;
  y[2] = T(0.4886025119029199) * z;
  y[3] = T(-0.4886025119029199) * x;
  y[4] = T(1.0925484305920792) * x * v;
  y[5] = T(-1.0925484305920792) * v * z;
  y[6] = T(0.31539156525252005) * (T(2) * z * z - x * x - v * v);
  y[7] = T(-1.0925484305920792) * x * z;
  y[8] = T(0.5462742152960396) * (x * x - v * v);
}

// The background of one ray: K = 3 (LDR model: sigmoid of the pre-activation) or K = 6 (log-HDR
// model: LDR through the sigmoid tone mapper, then HDR = exp). coef: n x 3; pre (3) is kept for
// the backward.
template <typename T>
void BackgroundForward(const T* coef, int n, const float dir[3], int K, T offset, T log_exposure,
                       T max_log, T* pre, T* out) {
  T y[9];
  BackgroundBasis(dir, n, y);
  for (int k = 0; k < 3; ++k) {
    pre[k] = 0;
    for (int j = 0; j < n; ++j) pre[k] += y[j] * coef[j * 3 + k];
  }
  if (K == 3) {
    for (int k = 0; k < 3; ++k) out[k] = T(1) / (T(1) + std::exp(-pre[k]));
    return;
  }
  SigmoidForward(offset, log_exposure, pre, 1, out);
  for (int k = 0; k < 3; ++k) out[3 + k] = std::exp(std::min(pre[k], max_log));
}

// Adds dL/dcoef (n x 3) and, for K = 6, dL/doffset for the background's dL_dout (K).
template <typename T>
void BackgroundBackward(int n, const float dir[3], int K, T offset, T log_exposure, T max_log,
                        const T* pre, const T* dL_dout, T* dL_dcoef, T* dL_doffset) {
  T dpre[3];
  if (K == 3) {
    for (int k = 0; k < 3; ++k) {
      const T s = T(1) / (T(1) + std::exp(-pre[k]));
      dpre[k] = dL_dout[k] * s * (T(1) - s);
    }
  } else {
    SigmoidBackward(offset, log_exposure, pre, 1, dL_dout, dpre, dL_doffset);
    for (int k = 0; k < 3; ++k)
      if (pre[k] < max_log) dpre[k] += dL_dout[3 + k] * std::exp(pre[k]);
  }
  T y[9];
  BackgroundBasis(dir, n, y);
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < 3; ++k) dL_dcoef[j * 3 + k] += y[j] * dpre[k];
}

}  // namespace hdr4d::baselines::hexplane
