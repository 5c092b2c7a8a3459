// Per-Gaussian rotation and covariance of 4D Gaussian Splatting (ARCHITECTURE §4),
// forward and backward side by side. Header-only templates on the scalar type T: float
// for training, double for the finite-difference tests.
//
// GRADIENT CONVENTION (used by every *Backward in rotation4d.h, slice.h and projection.h).
// A matrix gradient dL_dM is the matrix of partial derivatives dL/dM(i,j) with all entries of
// M treated as independent variables, exactly as the forward reads them. A symmetric input such
// as Sigma is therefore NOT assumed to receive a symmetric gradient: a consumer that reads only
// Sigma(0,3) puts its gradient there and leaves Sigma(3,0) at zero. Each producer of a matrix
// (e.g. Covariance4DBackward for Sigma = R S^2 R^T) accepts such a general gradient and applies
// the exact chain rule (it folds G and G^T together), so chaining the backwards gives the exact
// gradient of the composed function.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace hdr4d::method {

template <typename T>
using Vec2 = Eigen::Matrix<T, 2, 1>;
template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Vec4 = Eigen::Matrix<T, 4, 1>;
template <typename T>
using Mat2 = Eigen::Matrix<T, 2, 2>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Mat4 = Eigen::Matrix<T, 4, 4>;

// A raw quaternion whose norm is at or below this is treated as the identity (and passes no
// gradient), instead of dividing by zero; the reference's F.normalize would return a zero
// vector there, i.e. a singular "rotation". Optimisation never gets near it in practice.
constexpr double kMinQuaternionNorm = 1e-12;

namespace detail {

// q / |q|, or the identity (1,0,0,0) when |q| <= kMinQuaternionNorm.
template <typename T>
Vec4<T> NormalizeQuaternion(const Vec4<T>& q) {
  const T norm = q.norm();
  if (!(norm > static_cast<T>(kMinQuaternionNorm))) return Vec4<T>(1, 0, 0, 0);
  return q / norm;
}

// Gradient through q / |q|: (g - n (n.g)) / |q|; zero for the identity fallback.
template <typename T>
Vec4<T> NormalizeQuaternionBackward(const Vec4<T>& q, const Vec4<T>& dL_dn) {
  const T norm = q.norm();
  if (!(norm > static_cast<T>(kMinQuaternionNorm))) return Vec4<T>::Zero();
  const Vec4<T> n = q / norm;
  return (dL_dn - n * n.dot(dL_dn)) / norm;
}

// M_l(q) for q = (a,b,c,d): left multiplication v -> q v on quaternions (1,i,j,k).
template <typename T>
Mat4<T> LeftIsoclinic(const Vec4<T>& q) {
  const T a = q(0), b = q(1), c = q(2), d = q(3);
  Mat4<T> m;
  m << a, -b, -c, -d,  //
      b, a, -d, c,     //
      c, d, a, -b,     //
      d, -c, b, a;
  return m;
}

// M_r(q) for q = (p,q,r,s): right multiplication by the conjugate, v -> v conj(q).
template <typename T>
Mat4<T> RightIsoclinic(const Vec4<T>& q) {
  const T p = q(0), x = q(1), y = q(2), z = q(3);
  Mat4<T> m;
  m << p, x, y, z,   //
      -x, p, -z, y,  //
      -y, z, p, -x,  //
      -z, -y, x, p;
  return m;
}

// Sigma = R diag(exp(2 s)) R^T for any N.
template <typename T, int N>
Eigen::Matrix<T, N, N> CovarianceFromRotation(const Eigen::Matrix<T, N, N>& R,
                                              const Eigen::Matrix<T, N, 1>& log_scales) {
  const Eigen::Matrix<T, N, N> L = R * log_scales.array().exp().matrix().asDiagonal();
  return L * L.transpose();
}

// With V = diag(exp(2 s)): dL/dR = (G + G^T) R V, dL/ds_k = 2 V_k (R^T G R)_kk.
template <typename T, int N>
void CovarianceFromRotationBackward(const Eigen::Matrix<T, N, N>& R,
                                    const Eigen::Matrix<T, N, 1>& log_scales,
                                    const Eigen::Matrix<T, N, N>& dL_dSigma,
                                    Eigen::Matrix<T, N, N>* dL_dR,
                                    Eigen::Matrix<T, N, 1>* dL_dlog_scales) {
  const Eigen::Matrix<T, N, 1> variance = (T(2) * log_scales).array().exp().matrix();
  const Eigen::Matrix<T, N, N> sym = dL_dSigma + dL_dSigma.transpose();
  const Eigen::Matrix<T, N, N> sym_r = sym * R;
  *dL_dR = sym_r * variance.asDiagonal();
  // (R^T G R)_kk = 0.5 (R^T (G + G^T) R)_kk = 0.5 R_.k . (sym R)_.k
  for (int k = 0; k < N; ++k) {
    (*dL_dlog_scales)(k) = variance(k) * R.col(k).dot(sym_r.col(k));
  }
}

}  // namespace detail

// 4D rotation from two quaternions q_l = (a,b,c,d), q_r = (p,q,r,s), each normalised first:
// A = M_l(q_l) M_r(q_r), i.e. v -> q_l v conj(q_r) on quaternions (1,i,j,k), and R is A with
// both row and column order reversed, as the reference does (A.flip(1,2)). The flip moves the
// quaternions' real axis to index 3 = time, so q_l == q_r gives a rotation of (x,y,z) only that
// leaves t fixed, and q_l = q_r = identity gives I.
template <typename T>
Mat4<T> Rotation4D(const Vec4<T>& ql_raw, const Vec4<T>& qr_raw) {
  const Mat4<T> A = detail::LeftIsoclinic<T>(detail::NormalizeQuaternion(ql_raw)) *
                    detail::RightIsoclinic<T>(detail::NormalizeQuaternion(qr_raw));
  return A.reverse();  // R(i,j) = A(3-i, 3-j)
}

// Gradient of Rotation4D with respect to the raw (unnormalised) quaternions; dL_dR follows the
// GRADIENT CONVENTION above (any 4x4 matrix).
template <typename T>
void Rotation4DBackward(const Vec4<T>& ql_raw,
                        const Vec4<T>& qr_raw,
                        const Mat4<T>& dL_dR,
                        Vec4<T>* dL_dql_raw,
                        Vec4<T>* dL_dqr_raw) {
  const Mat4<T> ml = detail::LeftIsoclinic<T>(detail::NormalizeQuaternion(ql_raw));
  const Mat4<T> mr = detail::RightIsoclinic<T>(detail::NormalizeQuaternion(qr_raw));
  const Mat4<T> dA = dL_dR.reverse();
  const Mat4<T> G = dA * mr.transpose();  // dL/dM_l
  const Mat4<T> H = ml.transpose() * dA;  // dL/dM_r
  // Each quaternion component appears in four entries of its matrix, with the signs above.
  const Vec4<T> dl(G(0, 0) + G(1, 1) + G(2, 2) + G(3, 3),   //
                   -G(0, 1) + G(1, 0) - G(2, 3) + G(3, 2),  //
                   -G(0, 2) + G(1, 3) + G(2, 0) - G(3, 1),  //
                   -G(0, 3) - G(1, 2) + G(2, 1) + G(3, 0));
  const Vec4<T> dr(H(0, 0) + H(1, 1) + H(2, 2) + H(3, 3),  //
                   H(0, 1) - H(1, 0) - H(2, 3) + H(3, 2),  //
                   H(0, 2) + H(1, 3) - H(2, 0) - H(3, 1),  //
                   H(0, 3) - H(1, 2) + H(2, 1) - H(3, 0));
  *dL_dql_raw = detail::NormalizeQuaternionBackward(ql_raw, dl);
  *dL_dqr_raw = detail::NormalizeQuaternionBackward(qr_raw, dr);
}

// Sigma = R S^2 R^T, S = diag(exp(log_scales)): log_scales are log standard deviations along
// the Gaussian's four principal axes (the columns of R).
template <typename T>
Mat4<T> Covariance4D(const Mat4<T>& R, const Vec4<T>& log_scales) {
  return detail::CovarianceFromRotation<T, 4>(R, log_scales);
}

// dL_dSigma is a general 4x4 gradient (GRADIENT CONVENTION): both G and G^T are folded in.
template <typename T>
void Covariance4DBackward(const Mat4<T>& R,
                          const Vec4<T>& log_scales,
                          const Mat4<T>& dL_dSigma,
                          Mat4<T>* dL_dR,
                          Vec4<T>* dL_dlog_scales) {
  detail::CovarianceFromRotationBackward<T, 4>(R, log_scales, dL_dSigma, dL_dR, dL_dlog_scales);
}

// 3D mode (static scenes): the 3DGS rotation of a quaternion q = (w,x,y,z), normalised first
// (identity below kMinQuaternionNorm), as the usual column-vector rotation matrix.
template <typename T>
Mat3<T> Rotation3D(const Vec4<T>& q_raw) {
  const Vec4<T> q = detail::NormalizeQuaternion(q_raw);
  const T w = q(0), x = q(1), y = q(2), z = q(3);
  Mat3<T> R;
  R << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return R;
}

template <typename T>
void Rotation3DBackward(const Vec4<T>& q_raw, const Mat3<T>& dL_dR, Vec4<T>* dL_dq_raw) {
  const Vec4<T> q = detail::NormalizeQuaternion(q_raw);
  const T w = q(0), x = q(1), y = q(2), z = q(3);
  const Mat3<T>& G = dL_dR;
  // Partial derivatives of the nine entries above, contracted with G.
  const T dw =
      2 * (-z * G(0, 1) + y * G(0, 2) + z * G(1, 0) - x * G(1, 2) - y * G(2, 0) + x * G(2, 1));
  const T dx = 2 * (y * G(0, 1) + z * G(0, 2) + y * G(1, 0) - 2 * x * G(1, 1) - w * G(1, 2) +
                    z * G(2, 0) + w * G(2, 1) - 2 * x * G(2, 2));
  const T dy = 2 * (-2 * y * G(0, 0) + x * G(0, 1) + w * G(0, 2) + x * G(1, 0) + z * G(1, 2) -
                    w * G(2, 0) + z * G(2, 1) - 2 * y * G(2, 2));
  const T dz = 2 * (-2 * z * G(0, 0) - w * G(0, 1) + x * G(0, 2) + w * G(1, 0) - 2 * z * G(1, 1) +
                    y * G(1, 2) + x * G(2, 0) + y * G(2, 1));
  *dL_dq_raw = detail::NormalizeQuaternionBackward(q_raw, Vec4<T>(dw, dx, dy, dz));
}

// 3D mode: Sigma3 = R S^2 R^T with S = diag(exp(log_scales3)).
template <typename T>
Mat3<T> Covariance3D(const Mat3<T>& R, const Vec3<T>& log_scales) {
  return detail::CovarianceFromRotation<T, 3>(R, log_scales);
}

template <typename T>
void Covariance3DBackward(const Mat3<T>& R,
                          const Vec3<T>& log_scales,
                          const Mat3<T>& dL_dSigma,
                          Mat3<T>* dL_dR,
                          Vec3<T>* dL_dlog_scales) {
  detail::CovarianceFromRotationBackward<T, 3>(R, log_scales, dL_dSigma, dL_dR, dL_dlog_scales);
}

}  // namespace hdr4d::method
