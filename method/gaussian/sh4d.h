// The 4D colour basis of 4DGS (ARCHITECTURE §4): real spherical harmonics of
// the view direction (degree <= 3, 3DGS constants and signs) times a cosine basis in time,
//   value = sum_{n, lm} Y_lm(d) cos(2 pi n dt / T) k_{lm + F n},  F = (Dmax+1)^2,
// plus kColorOffset. Colour is linear in the coefficients, so the whole kernel is a weight
// vector w (EvalColorBasisWeights) dotted with each channel's coefficients.
//
// DETACHED INPUTS: the reference detaches both the view direction (normalised conditional mean
// minus camera centre) and dt = mu_t - t before evaluating the basis, so the backward gives
// gradients to the coefficients only; none flows to the mean, the camera or mu_t.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/gaussian_model.h"
#include "method/gaussian/rotation4d.h"

namespace hdr4d::method {

// Spatial degree <= 3 (16 functions) times temporal degree <= 2 (3 blocks).
constexpr int kMaxColorCoefficients = 48;

// 3DGS real-SH constants per degree: the orthonormal real SH with the Condon-Shortley sign
// (-1)^m, ordered m = -l..l. C0 is constants.h's kShC0 at full double precision (the float
// constant would cap double evaluations at 5e-8 relative error).
constexpr double kShC0Double = 0.28209479177387814;
static_assert(static_cast<float>(kShC0Double) == kShC0);
constexpr double kShC1 = 0.4886025119029199;
constexpr double kShC2[5] = {1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                             -1.0925484305920792, 0.5462742152960396};
constexpr double kShC3[7] = {-0.5900435899266435, 2.890611442640554,   -0.4570457994644658,
                             0.3731763325901154,  -0.4570457994644658, 1.445305721320277,
                             -0.5900435899266435};

// The lowest spatial and time degrees that give a model's colours exactly: those of its highest
// non-zero coefficients. Colour bands never switched on (--color-bands-by-need) stay zero, and a
// render at these degrees skips their terms: the same image up to float rounding, less work.
template <typename T>
std::pair<int, int> UsedColorDegrees(const GaussianModelT<T>& model) {
  const int functions = model.basis.sh_functions();
  const std::size_t channels = static_cast<std::size_t>(model.channels);
  const std::size_t stride = model.rest_stride();
  int sh = 0, time = 0;
  for (std::size_t f = 0; f < model.color_rest.size(); ++f) {
    if (model.color_rest[f] == T(0)) continue;
    const int k = static_cast<int>((f % stride) / channels) + 1;  // coefficient k = n F + lm
    const int lm = k % functions;
    int degree = 0;
    while ((degree + 1) * (degree + 1) <= lm) ++degree;
    sh = std::max(sh, degree);
    time = std::max(time, k / functions);
  }
  return {sh, time};
}

// Y_lm(d) for l <= degree (0..3) at the unit direction d, in 3DGS order: (degree+1)^2 values.
template <typename T>
void EvalShBasis(const Vec3<T>& d, int degree, T* y) {
  y[0] = static_cast<T>(kShC0Double);
  if (degree < 1) return;
  const T x = d.x(), yy_ = d.y(), z = d.z();
  const T c1 = static_cast<T>(kShC1);
  y[1] = -c1 * yy_;
  y[2] = c1 * z;
  y[3] = -c1 * x;
  if (degree < 2) return;
  const T xx = x * x, yy = yy_ * yy_, zz = z * z;
  const T xy = x * yy_, yz = yy_ * z, xz = x * z;
  y[4] = static_cast<T>(kShC2[0]) * xy;
  y[5] = static_cast<T>(kShC2[1]) * yz;
  y[6] = static_cast<T>(kShC2[2]) * (T(2) * zz - xx - yy);
  y[7] = static_cast<T>(kShC2[3]) * xz;
  y[8] = static_cast<T>(kShC2[4]) * (xx - yy);
  if (degree < 3) return;
  y[9] = static_cast<T>(kShC3[0]) * yy_ * (T(3) * xx - yy);
  y[10] = static_cast<T>(kShC3[1]) * xy * z;
  y[11] = static_cast<T>(kShC3[2]) * yy_ * (T(4) * zz - xx - yy);
  y[12] = static_cast<T>(kShC3[3]) * z * (T(2) * zz - T(3) * xx - T(3) * yy);
  y[13] = static_cast<T>(kShC3[4]) * x * (T(4) * zz - xx - yy);
  y[14] = static_cast<T>(kShC3[5]) * z * (xx - yy);
  y[15] = static_cast<T>(kShC3[6]) * x * (xx - T(3) * yy);
}

namespace detail {

inline void CheckColorDegrees(const ColorBasis& basis, int sh_degree, int time_degree) {
  HDR4D_CHECK(basis.max_sh_degree >= 0 && basis.max_sh_degree <= 3);
  HDR4D_CHECK(basis.max_time_degree >= 0 && basis.max_time_degree <= 2);
  HDR4D_CHECK(sh_degree >= 0 && sh_degree <= basis.max_sh_degree);
  HDR4D_CHECK(time_degree >= 0 && time_degree <= basis.max_time_degree);
}

}  // namespace detail

// The K = basis.coefficients() weights of one Gaussian's colour: weights[lm + F n] =
// Y_lm(d) cos(2 pi n dt / duration) for l <= sh_degree and n <= time_degree, 0 beyond the
// active degrees. d = dir_unnormalised / |dir_unnormalised| (a zero vector leaves only Y_00,
// like a normalisation with an epsilon, instead of NaN). duration must be positive when
// time_degree > 0.
template <typename T>
void EvalColorBasisWeights(const Vec3<T>& dir_unnormalised,
                           T dt,
                           T duration,
                           const ColorBasis& basis,
                           int sh_degree,
                           int time_degree,
                           T* weights) {
  detail::CheckColorDegrees(basis, sh_degree, time_degree);
  const int functions = basis.sh_functions();
  const int active = (sh_degree + 1) * (sh_degree + 1);
  const int total = basis.coefficients();
  for (int k = 0; k < total; ++k) weights[k] = T(0);

  const T norm = dir_unnormalised.norm();
  const Vec3<T> d = norm > T(0) ? Vec3<T>(dir_unnormalised / norm) : Vec3<T>::Zero();
  EvalShBasis(d, sh_degree, weights);
  if (time_degree == 0) return;
  HDR4D_CHECK(duration > T(0));
  // cos(n phase) by the Chebyshev recurrence cos(n x) = 2 cos x cos((n-1) x) - cos((n-2) x).
  const T c1 = std::cos(T(2) * std::numbers::pi_v<T> * dt / duration);
  T prev = T(1), cn = c1;
  for (int n = 1; n <= time_degree; ++n) {
    for (int lm = 0; lm < active; ++lm) weights[n * functions + lm] = weights[lm] * cn;
    const T next = T(2) * c1 * cn - prev;
    prev = cn;
    cn = next;
  }
}

// out[c] = sum_k w_k coeffs[k * channels + c] + kColorOffset for c < channels, with w from
// EvalColorBasisWeights. No clamp: the caller clamps at 0 (LDR) or reads it as log-HDR.
template <typename T>
void EvalColor4D(const T* coeffs,
                 const ColorBasis& basis,
                 int channels,
                 const Vec3<T>& dir_unnormalised,
                 T dt,
                 T duration,
                 int sh_degree,
                 int time_degree,
                 T* out) {
  T w[kMaxColorCoefficients];
  EvalColorBasisWeights(dir_unnormalised, dt, duration, basis, sh_degree, time_degree, w);
  const int functions = basis.sh_functions();
  const int active = (sh_degree + 1) * (sh_degree + 1);
  for (int c = 0; c < channels; ++c) out[c] = static_cast<T>(kColorOffset);
  for (int n = 0; n <= time_degree; ++n) {
    for (int lm = 0; lm < active; ++lm) {
      const int k = n * functions + lm;
      const T* ck = coeffs + k * channels;
      for (int c = 0; c < channels; ++c) out[c] += w[k] * ck[c];
    }
  }
}

// Accumulates dL_dcoeffs[k * channels + c] += w_k dL_dout[c] for the active coefficients;
// the others are left untouched (their gradient is zero). `coeffs` is not needed (the colour is
// linear in it) and kept for a uniform signature; direction and dt are detached (see top).
template <typename T>
void EvalColor4DBackward(const T* coeffs,
                         const ColorBasis& basis,
                         int channels,
                         const Vec3<T>& dir_unnormalised,
                         T dt,
                         T duration,
                         int sh_degree,
                         int time_degree,
                         const T* dL_dout,
                         T* dL_dcoeffs) {
  T w[kMaxColorCoefficients];
  EvalColorBasisWeights(dir_unnormalised, dt, duration, basis, sh_degree, time_degree, w);
  const int functions = basis.sh_functions();
  const int active = (sh_degree + 1) * (sh_degree + 1);
  for (int n = 0; n <= time_degree; ++n) {
    for (int lm = 0; lm < active; ++lm) {
      const int k = n * functions + lm;
      T* gk = dL_dcoeffs + k * channels;
      for (int c = 0; c < channels; ++c) gk[c] += w[k] * dL_dout[c];
    }
  }
}

}  // namespace hdr4d::method
