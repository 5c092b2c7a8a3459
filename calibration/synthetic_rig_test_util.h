// Shared by the calibration tests that build synthetic rigs: a camera on an arc around the
// origin, looking at it.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

namespace hdr4d {

// cam_from_world (OpenCV axes) of a camera at `angle` radians on a circle of `radius` around the
// y axis, `height` up, looking at the origin.
inline Eigen::Isometry3d CameraOnArc(double angle, double radius, double height) {
  const Eigen::Vector3d centre(radius * std::sin(angle), height, -radius * std::cos(angle));
  const Eigen::Vector3d z = -centre.normalized(), x = Eigen::Vector3d::UnitY().cross(z).normalized();
  Eigen::Matrix3d r;
  r << x.transpose(), z.cross(x).transpose(), z.transpose();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = -r * centre;
  return t;
}

}  // namespace hdr4d
