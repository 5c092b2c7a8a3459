#include "core/geometry/camera.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "core/util/error.h"

namespace hdr4d {

PinholeIntrinsics PinholeIntrinsics::FromFovX(double camera_angle_x, int width, int height) {
  if (!(camera_angle_x > 0.0 && camera_angle_x < std::numbers::pi)) {
    Fail("camera_angle_x = {} radians: must be in (0, pi)", camera_angle_x);
  }
  if (width <= 0 || height <= 0) Fail("image size {}x{}: must be positive", width, height);
  PinholeIntrinsics k;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * camera_angle_x);
  k.cx = 0.5 * width;
  k.cy = 0.5 * height;
  k.width = width;
  k.height = height;
  return k;
}

double PinholeIntrinsics::FovX() const { return 2.0 * std::atan(0.5 * width / fx); }
double PinholeIntrinsics::FovY() const { return 2.0 * std::atan(0.5 * height / fy); }

std::string PinholeIntrinsics::Problem() const {
  if (!(std::isfinite(fx) && fx > 0) || !(std::isfinite(fy) && fy > 0)) {
    return fmt::format("focal length fx={} fy={}: must be positive and finite", fx, fy);
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    return fmt::format("principal point cx={} cy={}: must be finite", cx, cy);
  }
  if (width <= 0 || height <= 0)
    return fmt::format("image size {}x{}: must be positive", width, height);
  return {};
}

void PinholeIntrinsics::Validate() const {
  if (std::string problem = Problem(); !problem.empty()) throw Error(problem);
}

Eigen::Matrix4d GlFromCv() { return Eigen::Vector4d(1, -1, -1, 1).asDiagonal(); }
Eigen::Matrix4d CvFromGl() { return GlFromCv(); }

Eigen::Matrix4d WorldFromCamCvFromGl(const Eigen::Matrix4d& world_from_cam_gl) {
  return world_from_cam_gl * GlFromCv();
}

Eigen::Matrix4d WorldFromCamGlFromCv(const Eigen::Matrix4d& world_from_cam_cv) {
  return world_from_cam_cv * CvFromGl();
}

Eigen::Matrix4d RigidInverse(const Eigen::Matrix4d& target_from_source) {
  const Eigen::Matrix3d r_t = target_from_source.topLeftCorner<3, 3>().transpose();
  Eigen::Matrix4d source_from_target = Eigen::Matrix4d::Identity();
  source_from_target.topLeftCorner<3, 3>() = r_t;
  source_from_target.topRightCorner<3, 1>() = -r_t * target_from_source.topRightCorner<3, 1>();
  return source_from_target;
}

std::string PoseProblem(const Eigen::Matrix4d& pose) {
  if (!pose.allFinite()) return "matrix has a non-finite (NaN or Inf) entry";
  const Eigen::RowVector4d bottom = pose.row(3);
  if ((bottom - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) {
    return fmt::format("bottom row is [{}, {}, {}, {}], expected [0, 0, 0, 1]", bottom(0),
                       bottom(1), bottom(2), bottom(3));
  }
  const Eigen::Matrix3d r = pose.topLeftCorner<3, 3>();
  const double det = r.determinant();
  if (std::abs(det) < 1e-9) return fmt::format("singular matrix (det of the 3x3 part = {:g})", det);
  if (det < 0) {
    return fmt::format("3x3 part is a reflection (det = {:g}), expected a rotation", det);
  }
  const double ortho_error =
      (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho_error > kRotationTolerance || std::abs(det - 1.0) > kRotationTolerance) {
    return fmt::format(
        "3x3 part is not a rotation (max |R^T R - I| = {:g}, det = {:g}; scale or shear is not "
        "allowed)",
        ortho_error, det);
  }
  return {};
}

Eigen::Matrix4d LookAtWorldFromCamGl(const Eigen::Vector3d& eye,
                                     const Eigen::Vector3d& target,
                                     const Eigen::Vector3d& up) {
  const Eigen::Vector3d back = eye - target;  // GL cameras look down -Z, so +Z points back
  HDR4D_CHECK(back.norm() > 0);
  const Eigen::Vector3d z = back.normalized();
  const Eigen::Vector3d x_raw = up.cross(z);
  HDR4D_CHECK(x_raw.norm() > 1e-12);
  const Eigen::Vector3d x = x_raw.normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix4d world_from_cam = Eigen::Matrix4d::Identity();
  world_from_cam.block<3, 1>(0, 0) = x;
  world_from_cam.block<3, 1>(0, 1) = y;
  world_from_cam.block<3, 1>(0, 2) = z;
  world_from_cam.block<3, 1>(0, 3) = eye;
  return world_from_cam;
}

Camera Camera::FromWorldFromCamCv(const PinholeIntrinsics& intrinsics,
                                  const Eigen::Matrix4d& world_from_cam_cv) {
  return Camera{intrinsics, WorldFromCamGlFromCv(world_from_cam_cv)};
}

Eigen::Matrix4d Camera::WorldFromCamCv() const { return WorldFromCamCvFromGl(world_from_cam_gl); }
Eigen::Matrix4d Camera::CamFromWorldCv() const { return RigidInverse(WorldFromCamCv()); }
Eigen::Matrix4d Camera::CamFromWorldGl() const { return RigidInverse(world_from_cam_gl); }
Eigen::Vector3d Camera::Center() const { return world_from_cam_gl.topRightCorner<3, 1>(); }
Eigen::Vector3d Camera::ViewDirection() const {
  return -world_from_cam_gl.block<3, 1>(0, 2).normalized();
}

std::optional<Eigen::Vector3d> Camera::Project(const Eigen::Vector3d& point_world) const {
  const Eigen::Matrix4d cam_from_world = CamFromWorldCv();
  const Eigen::Vector3d p =
      cam_from_world.topLeftCorner<3, 3>() * point_world + cam_from_world.topRightCorner<3, 1>();
  if (!(p.z() > 0.0)) return std::nullopt;
  const PinholeIntrinsics& k = intrinsics;
  return Eigen::Vector3d(k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy, p.z());
}

Eigen::Vector3d Camera::Unproject(double u, double v, double depth) const {
  const PinholeIntrinsics& k = intrinsics;
  const Eigen::Vector3d p((u - k.cx) / k.fx * depth, (v - k.cy) / k.fy * depth, depth);
  const Eigen::Matrix4d world_from_cam = WorldFromCamCv();
  return world_from_cam.topLeftCorner<3, 3>() * p + world_from_cam.topRightCorner<3, 1>();
}

void Camera::Validate() const {
  intrinsics.Validate();
  if (std::string problem = PoseProblem(world_from_cam_gl); !problem.empty()) {
    Fail("transform_matrix: {}", problem);
  }
}

}  // namespace hdr4d
