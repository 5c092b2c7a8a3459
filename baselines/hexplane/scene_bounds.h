// The box a HexPlane model covers and the depth range its rays sample, from the dataset: the
// reference sets both per dataset by hand (D-NeRF: the cube [-1.5, 1.5]^3, near 2, far 6); here
// a scene with point3d.ply (every datagen scene) gets a cube around its points that the training
// cameras see (all of them when none is seen) and a depth range
// from its cameras, and one without keeps the reference's D-NeRF values. near/far in the
// dataset's transforms win over either.
#pragma once

#include <array>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "baselines/hexplane/hexplane_config.h"
#include "core/dataset/dataset.h"
#include "core/geometry/camera.h"

namespace hdr4d::baselines::hexplane {

struct SceneBox {
  std::array<float, 3> center{0, 0, 0};
  float half = 1.5f;  // half the cube's side
};

// A cube around the points: per axis from the 1st to the 99th percentile (a few stray points do
// not stretch it), widened by 10% of that extent on each side, its side the largest axis's.
// nullopt for fewer than 8 points or a degenerate extent.
std::optional<SceneBox> BoxAroundPoints(const std::vector<Eigen::Vector3f>& points);

// The points that some camera sees (they project inside its image): a datagen scene's ground
// reaches far beyond its views, and a box around all of it would spend the grid on unseen floor.
std::vector<Eigen::Vector3f> PointsInAnyView(const std::vector<Eigen::Vector3f>& points,
                                             const std::vector<Camera>& cameras);

// The depth range that holds the box from every camera centre: the nearest centre's distance to
// the box centre minus the half diagonal (at least 1% of the half side), the farthest's plus it.
std::pair<float, float> DepthRangeOf(const SceneBox& box, const std::vector<Eigen::Vector3d>& centres);

// Sets config->center, box, near and far for the dataset (see above); logs what it chose.
void ApplySceneBounds(const Dataset& dataset, HexPlaneConfig* config);

}  // namespace hdr4d::baselines::hexplane
