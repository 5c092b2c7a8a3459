#include "method/train/view_directions.h"

#include <cmath>
#include <numbers>

namespace hdr4d::method {

int DistinctViewDirections(const std::vector<Camera>& cameras, double min_angle_degrees) {
  const double cos_min = std::cos(min_angle_degrees * std::numbers::pi / 180.0);
  std::vector<Eigen::Vector3d> counted;
  for (const Camera& camera : cameras) {
    const Eigen::Vector3d d = camera.ViewDirection();
    if (!d.allFinite() || d.norm() == 0) continue;
    const Eigen::Vector3d u = d.normalized();
    bool near = false;
    for (const Eigen::Vector3d& c : counted) {
      if (u.dot(c) > cos_min) {  // closer than the angle
        near = true;
        break;
      }
    }
    if (!near) counted.push_back(u);
  }
  return static_cast<int>(counted.size());
}

}  // namespace hdr4d::method
