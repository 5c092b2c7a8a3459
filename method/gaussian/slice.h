// The 3D Gaussian a 4D Gaussian shows at time t (ARCHITECTURE §4): condition
// the 4D normal on t. Forward and backward side by side; gradients follow the GRADIENT
// CONVENTION of method/gaussian/rotation4d.h (every matrix entry an independent variable).
#pragma once

#include <cmath>
#include <limits>

#include "method/gaussian/constants.h"
#include "method/gaussian/rotation4d.h"

namespace hdr4d::method {

// Sigma_tt is floored at kSliceRelativeVarianceFloor * trace(Sigma) + kSliceAbsoluteVarianceFloor
// before dividing by it. The relative part keeps the floor scale-free (it only bites when the
// time variance is a trillionth of the overall size, i.e. the Gaussian is degenerate in time);
// the absolute part handles an all-zero Sigma and is a normal number in float. Below the floor
// Sigma_tt is treated as the constant floor: no gradient reaches it (or the trace).
constexpr double kSliceRelativeVarianceFloor = 1e-12;
constexpr double kSliceAbsoluteVarianceFloor = 1e-30;

template <typename T>
struct Slice {
  Vec3<T> mean;  // conditional mean at time t
  Mat3<T> cov;   // conditional covariance (exactly symmetric when Sigma_11 is)
  T marginal;    // p(t) = exp(-0.5 (t - mu_t)^2 / Sigma_tt), unnormalised: 1 at t = mu_t
};

namespace detail {

// Sigma_tt after the floor, and whether the floor replaced it.
template <typename T>
T SliceTimeVariance(const Mat4<T>& Sigma, bool* floored) {
  const T floor = static_cast<T>(kSliceRelativeVarianceFloor) * Sigma.trace() +
                  static_cast<T>(kSliceAbsoluteVarianceFloor);
  const T stt = Sigma(3, 3);
  *floored = !(stt > floor);  // also catches NaN
  return *floored ? floor : stt;
}

}  // namespace detail

// Conditional Gaussian at time t of N(mean4, Sigma). Reads Sigma_11 = Sigma(0..2, 0..2),
// Sigma_12 = Sigma(0..2, 3) (the column; Sigma(3, 0..2) is not read) and Sigma_tt = Sigma(3,3):
//   mean = mu_xyz + Sigma_12 (t - mu_t) / Sigma_tt
//   cov = Sigma_11 - Sigma_12 Sigma_12^T / Sigma_tt
// Finite for any finite PSD Sigma (|Sigma_12|^2 <= Sigma_ii Sigma_tt bounds every quotient).
template <typename T>
Slice<T> SliceAtTime(const Vec4<T>& mean4, const Mat4<T>& Sigma, T t) {
  bool floored;
  const T stt = detail::SliceTimeVariance(Sigma, &floored);
  const T inv = T(1) / stt;
  const T dt = t - mean4(3);
  const Vec3<T> s = Sigma.template block<3, 1>(0, 3);
  Slice<T> out;
  out.mean = mean4.template head<3>() + s * (dt * inv);
  out.cov = Sigma.template block<3, 3>(0, 0) - (s * s.transpose()) * inv;
  out.marginal = std::exp(T(-0.5) * dt * dt * inv);
  return out;
}

// Gradients to mean4 (all four entries) and Sigma (only the entries the forward reads; zero
// elsewhere). No gradient to t. Writes (does not accumulate) both outputs.
template <typename T>
void SliceAtTimeBackward(const Vec4<T>& mean4,
                         const Mat4<T>& Sigma,
                         T t,
                         const Vec3<T>& dL_dmean3,
                         const Mat3<T>& dL_dcov3,
                         T dL_dmarginal,
                         Vec4<T>* dL_dmean4,
                         Mat4<T>* dL_dSigma) {
  bool floored;
  const T stt = detail::SliceTimeVariance(Sigma, &floored);
  const T inv = T(1) / stt;
  const T dt = t - mean4(3);
  const T dt_inv = dt * inv;
  const Vec3<T> s = Sigma.template block<3, 1>(0, 3);
  const Vec3<T> k = s * inv;  // regression coefficient of xyz on t, |k_i| <= sqrt(S_ii / stt)
  const T marginal = std::exp(T(-0.5) * dt * dt_inv);

  const T gm_dot_k = dL_dmean3.dot(k);
  dL_dmean4->template head<3>() = dL_dmean3;
  // d mean / d mu_t = -k; d p / d mu_t = p dt / stt
  (*dL_dmean4)(3) = -gm_dot_k + dL_dmarginal * marginal * dt_inv;

  dL_dSigma->setZero();
  dL_dSigma->template block<3, 3>(0, 0) = dL_dcov3;
  dL_dSigma->template block<3, 1>(0, 3) =
      dL_dmean3 * dt_inv - (dL_dcov3 + dL_dcov3.transpose()) * k;
  if (!floored) {
    // mean: -(g.k) dt / stt; cov: k^T G k; marginal: p 0.5 (dt / stt)^2 (skipped once p has
    // underflowed, where (dt / stt)^2 alone could overflow).
    T d_stt = -gm_dot_k * dt_inv + k.dot(dL_dcov3 * k);
    if (marginal > T(0)) d_stt += dL_dmarginal * marginal * T(0.5) * dt_inv * dt_inv;
    (*dL_dSigma)(3, 3) = d_stt;
  }
}

// The reference culls a Gaussian at time t when p(t) <= 0.05.
template <typename T>
bool TemporallyVisible(T marginal) {
  return marginal > static_cast<T>(kTemporalCullMarginal);
}

}  // namespace hdr4d::method
