#include "baselines/hexplane/scene_bounds.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/geometry/ply.h"

namespace hdr4d::baselines::hexplane {

std::optional<SceneBox> BoxAroundPoints(const std::vector<Eigen::Vector3f>& points) {
  if (points.size() < 8) return std::nullopt;
  SceneBox box;
  float half = 0;
  std::vector<float> axis(points.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < points.size(); ++i) axis[i] = points[i][a];
    const std::size_t lo_k = points.size() / 100, hi_k = points.size() - 1 - points.size() / 100;
    std::nth_element(axis.begin(), axis.begin() + lo_k, axis.end());
    const float lo = axis[lo_k];
    std::nth_element(axis.begin(), axis.begin() + hi_k, axis.end());
    const float hi = axis[hi_k];
    if (!std::isfinite(lo) || !std::isfinite(hi)) return std::nullopt;
    box.center[a] = 0.5f * (lo + hi);
    half = std::max(half, 0.5f * (hi - lo) * 1.2f);
  }
  if (!(half > 1e-6f)) return std::nullopt;
  box.half = half;
  return box;
}

std::pair<float, float> DepthRangeOf(const SceneBox& box, const std::vector<Eigen::Vector3d>& centres) {
  const double reach = std::sqrt(3.0) * box.half;
  double nearest = 1e30, farthest = 0;
  for (const Eigen::Vector3d& c : centres) {
    const double d = (c - Eigen::Vector3d(box.center[0], box.center[1], box.center[2])).norm();
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
  }
  if (centres.empty()) return {0.01f * box.half, float(2 * reach)};
  return {float(std::max(nearest - reach, 0.01 * box.half)), float(farthest + reach)};
}

std::vector<Eigen::Vector3f> PointsInAnyView(const std::vector<Eigen::Vector3f>& points,
                                             const std::vector<Camera>& cameras) {
  std::vector<Eigen::Vector3f> seen;
  for (const Eigen::Vector3f& p : points) {
    for (const Camera& c : cameras) {
      const std::optional<Eigen::Vector3d> uvd = c.Project(p.cast<double>());
      if (uvd && (*uvd)[0] >= 0 && (*uvd)[0] <= c.intrinsics.width && (*uvd)[1] >= 0 &&
          (*uvd)[1] <= c.intrinsics.height) {
        seen.push_back(p);
        break;
      }
    }
  }
  return seen;
}

void ApplySceneBounds(const Dataset& dataset, HexPlaneConfig* config) {
  std::optional<SceneBox> box;
  if (dataset.point_cloud_path) {
    // At most 32 training cameras, spread over the split: enough to tell the seen points.
    std::vector<Camera> cameras;
    const std::size_t n = dataset.train.size(), step = std::max<std::size_t>(1, n / 32);
    for (std::size_t i = 0; i < n; i += step) cameras.push_back(dataset.train[i].camera);
    const std::vector<Eigen::Vector3f> points = ReadPly(*dataset.point_cloud_path).positions;
    box = BoxAroundPoints(PointsInAnyView(points, cameras));
    if (!box) box = BoxAroundPoints(points);
  }
  if (box) {
    std::vector<Eigen::Vector3d> centres;
    for (const Frame& f : dataset.train) centres.push_back(f.camera.Center());
    const auto [near, far] = DepthRangeOf(*box, centres);
    config->center = box->center;
    config->box = box->half;
    config->near = near;
    config->far = far;
  }
  if (dataset.near) config->near = float(*dataset.near);
  if (dataset.far) config->far = float(*dataset.far);
  spdlog::info("hexplane: scene box centre ({:.3g}, {:.3g}, {:.3g}), half side {:.3g} ({}); "
               "depths {:.3g}..{:.3g}",
               config->center[0], config->center[1], config->center[2], config->box,
               box ? "around point3d.ply" : "the reference's D-NeRF cube", config->near, config->far);
}

}  // namespace hdr4d::baselines::hexplane
