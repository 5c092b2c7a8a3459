// EWA splatting of a 3D Gaussian into a pinhole view, as 3DGS does it (ARCHITECTURE §4):
// local affine approximation of the projection, 2D covariance + dilation, conic,
// screen radius. Forward and backward side by side; matrix gradients follow the GRADIENT
// CONVENTION of method/gaussian/rotation4d.h. Pixel coordinates follow core/geometry/camera.h (top-left
// corner at (0,0), OpenCV camera axes).
#pragma once

#include <algorithm>
#include <cmath>

#include "core/geometry/camera.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/rotation4d.h"

namespace hdr4d::method {

template <typename T>
struct ViewParams {
  Mat3<T> rotation;  // cam_from_world in OpenCV axes: x_cam = rotation x_world + translation
  Vec3<T> translation;
  T fx, fy, cx, cy;
  int width, height;

  static ViewParams FromCamera(const Camera& camera) {
    const Eigen::Matrix4d cam_from_world = camera.CamFromWorldCv();
    const PinholeIntrinsics& k = camera.intrinsics;
    ViewParams v;
    v.rotation = cam_from_world.block<3, 3>(0, 0).cast<T>();
    v.translation = cam_from_world.block<3, 1>(0, 3).cast<T>();
    v.fx = static_cast<T>(k.fx);
    v.fy = static_cast<T>(k.fy);
    v.cx = static_cast<T>(k.cx);
    v.cy = static_cast<T>(k.cy);
    v.width = k.width;
    v.height = k.height;
    return v;
  }
  // Camera centre in world coordinates, -R^T t (the origin of view directions for colour).
  Vec3<T> Center() const { return -(rotation.transpose() * translation); }
  // tan of the half field of view as 3DGS derives it (principal point assumed centred).
  T TanFovX() const { return static_cast<T>(width) / (T(2) * fx); }
  T TanFovY() const { return static_cast<T>(height) / (T(2) * fy); }
};

template <typename T>
struct Splat2D {
  Vec2<T> mean = Vec2<T>::Zero();   // pixel coordinates
  Vec3<T> conic = Vec3<T>::Zero();  // inverse 2D covariance (a, b, c) of [[a,b],[b,c]]
  Vec3<T> cov2d = Vec3<T>::Zero();  // 2D covariance after dilation, (a, b, c)
  T depth = 0;                      // camera-space z
  int radius = 0;                   // pixels, ceil(kRadiusSigmas sqrt(lambda_max))
  // False behind the near plane, for a non-positive 2D determinant or a zero radius; then the
  // other fields are unspecified. Whether the radius square touches the image is left to the
  // tile binning (it decides with its own tile grid).
  bool visible = false;
};

namespace detail {

// Everything the forward and the backward share.
template <typename T>
struct EwaTerms {
  Vec3<T> p;                  // camera-space mean
  bool clamped_x, clamped_y;  // x/z, y/z outside the 3DGS guard band
  T jx, jy;                   // x/z, y/z after clamping
  Eigen::Matrix<T, 2, 3> J;   // Jacobian of the projection at the clamped point
  Eigen::Matrix<T, 2, 3> M;   // J R: camera Jacobian composed with the view rotation
  Mat2<T> C;                  // M cov3 M^T (no dilation)
  T a, b, c, det;             // dilated covariance (a, b; b, c) and its determinant
};

// p is the camera-space mean, already known to lie beyond the near plane.
template <typename T>
EwaTerms<T> ComputeEwaTerms(const Vec3<T>& p, const Mat3<T>& cov3, const ViewParams<T>& view) {
  EwaTerms<T> e;
  e.p = p;
  const T z = e.p.z();
  const T inv_z = T(1) / z;
  const T lim_x = static_cast<T>(kFrustumTanMargin) * view.TanFovX();
  const T lim_y = static_cast<T>(kFrustumTanMargin) * view.TanFovY();
  const T x_z = e.p.x() * inv_z, y_z = e.p.y() * inv_z;
  e.clamped_x = x_z < -lim_x || x_z > lim_x;
  e.clamped_y = y_z < -lim_y || y_z > lim_y;
  e.jx = std::clamp(x_z, -lim_x, lim_x);
  e.jy = std::clamp(y_z, -lim_y, lim_y);
  e.J << view.fx * inv_z, T(0), -view.fx * e.jx * inv_z,  //
      T(0), view.fy * inv_z, -view.fy * e.jy * inv_z;
  e.M = e.J * view.rotation;
  e.C = e.M * cov3 * e.M.transpose();
  const T dilation = static_cast<T>(kCov2dDilation);
  e.a = e.C(0, 0) + dilation;
  e.b = e.C(0, 1);
  e.c = e.C(1, 1) + dilation;
  e.det = e.a * e.c - e.b * e.b;
  return e;
}

// ceil(kRadiusSigmas sqrt(lambda_max)) as 3DGS computes it, 0 when it is not a positive number.
template <typename T>
int EwaRadius(const EwaTerms<T>& e) {
  const T mid = T(0.5) * (e.a + e.c);
  const T lambda_max = mid + std::sqrt(std::max(T(0.1), mid * mid - e.det));
  if (!(lambda_max > T(0))) return 0;
  const T r = std::ceil(static_cast<T>(kRadiusSigmas) * std::sqrt(lambda_max));
  return r < T(1 << 30) ? static_cast<int>(r) : (1 << 30);
}

}  // namespace detail

// Projects N(mean3, cov3) (world space) into the view. The Jacobian J of the perspective map is
// evaluated with x/z and y/z clamped to +-kFrustumTanMargin tan(fov/2), as 3DGS does, so
// Gaussians far outside the view do not get huge footprints; the projected mean is not clamped.
template <typename T>
Splat2D<T> ProjectEwa(const Vec3<T>& mean3, const Mat3<T>& cov3, const ViewParams<T>& view) {
  Splat2D<T> out;
  const Vec3<T> p = view.rotation * mean3 + view.translation;
  if (!(p.z() > static_cast<T>(kNearPlane))) return out;
  const detail::EwaTerms<T> e = detail::ComputeEwaTerms(p, cov3, view);
  if (!(e.det > T(0))) return out;
  const T inv_z = T(1) / e.p.z();
  out.mean = Vec2<T>(view.fx * e.p.x() * inv_z + view.cx, view.fy * e.p.y() * inv_z + view.cy);
  const T inv_det = T(1) / e.det;
  out.conic = Vec3<T>(e.c * inv_det, -e.b * inv_det, e.a * inv_det);
  out.cov2d = Vec3<T>(e.a, e.b, e.c);
  out.depth = e.p.z();
  out.radius = detail::EwaRadius(e);
  out.visible = out.radius > 0;
  return out;
}

// Gradients of the splat's mean and conic to the world-space mean and covariance. dL_dmean2d is
// per pixel coordinate (3DGS's densification statistic is per NDC unit: multiply x by width / 2
// and y by height / 2 to compare with its thresholds). dL_dconic(1) is the full derivative with
// respect to the stored off-diagonal b (the rasteriser's exponent reads -b dx dy); 3DGS passes
// half of it and doubles it inside, this function does neither. Through the mean
// projection, the conic inversion, the dilation and J's dependence on the mean. Writes zeros
// when the forward marks the splat invisible.
//
// Difference from 3DGS: where x/z is clamped, J(0,2) = -fx clamp(x/z) / z, so its exact
// derivative is zero in x and fx clamp(x/z) / z^2 in z. 3DGS zeroes the x part too, but its z
// term is 2 fx clamp(x/z) / z^2 (it differentiates -fx x / z^2 holding the clamped x fixed);
// we use the exact derivative of the forward so finite differences agree on both sides of the
// clamp. Unclamped, the two are identical.
template <typename T>
void ProjectEwaBackward(const Vec3<T>& mean3,
                        const Mat3<T>& cov3,
                        const ViewParams<T>& view,
                        const Vec2<T>& dL_dmean2d,
                        const Vec3<T>& dL_dconic,
                        Vec3<T>* dL_dmean3,
                        Mat3<T>* dL_dcov3) {
  dL_dmean3->setZero();
  dL_dcov3->setZero();
  const Vec3<T> p = view.rotation * mean3 + view.translation;
  if (!(p.z() > static_cast<T>(kNearPlane))) return;
  const detail::EwaTerms<T> e = detail::ComputeEwaTerms(p, cov3, view);
  if (!(e.det > T(0)) || detail::EwaRadius(e) <= 0) return;

  const T x = e.p.x(), y = e.p.y(), z = e.p.z();
  const T inv_z = T(1) / z, inv_z2 = inv_z * inv_z;

  // Conic (c, -b, a) / det to the dilated covariance entries.
  const T a = e.a, b = e.b, c = e.c;
  const T inv_det2 = T(1) / (e.det * e.det);
  const T gA = dL_dconic(0), gB = dL_dconic(1), gC = dL_dconic(2);
  const T d_a = (-c * c * gA + b * c * gB - b * b * gC) * inv_det2;
  const T d_b = (T(2) * b * c * gA - (e.det + T(2) * b * b) * gB + T(2) * a * b * gC) * inv_det2;
  const T d_c = (-b * b * gA + a * b * gB - a * a * gC) * inv_det2;
  // The dilation is a constant; b is read from C(0,1) only.
  Mat2<T> dC;
  dC << d_a, d_b, T(0), d_c;

  // C = M cov3 M^T: dL/dcov3 = M^T dC M, dL/dM = dC M cov3^T + dC^T M cov3.
  *dL_dcov3 = e.M.transpose() * dC * e.M;
  const Eigen::Matrix<T, 2, 3> dM = dC * e.M * cov3.transpose() + dC.transpose() * e.M * cov3;
  const Eigen::Matrix<T, 2, 3> dJ = dM * view.rotation.transpose();

  // J = [[fx/z, 0, -fx jx/z], [0, fy/z, -fy jy/z]] with jx = clamp(x/z) (likewise jy).
  Vec3<T> dp = Vec3<T>::Zero();
  dp.z() += -view.fx * inv_z2 * dJ(0, 0) - view.fy * inv_z2 * dJ(1, 1);
  if (e.clamped_x) {
    dp.z() += view.fx * e.jx * inv_z2 * dJ(0, 2);
  } else {  // J(0,2) = -fx x / z^2
    dp.x() += -view.fx * inv_z2 * dJ(0, 2);
    dp.z() += T(2) * view.fx * x * inv_z2 * inv_z * dJ(0, 2);
  }
  if (e.clamped_y) {
    dp.z() += view.fy * e.jy * inv_z2 * dJ(1, 2);
  } else {
    dp.y() += -view.fy * inv_z2 * dJ(1, 2);
    dp.z() += T(2) * view.fy * y * inv_z2 * inv_z * dJ(1, 2);
  }
  // Projected mean (fx x/z + cx, fy y/z + cy).
  dp.x() += view.fx * inv_z * dL_dmean2d(0);
  dp.y() += view.fy * inv_z * dL_dmean2d(1);
  dp.z() += -(view.fx * x * dL_dmean2d(0) + view.fy * y * dL_dmean2d(1)) * inv_z2;

  *dL_dmean3 = view.rotation.transpose() * dp;
}

}  // namespace hdr4d::method
