// How many views' worth of distinct content a static scene's training cameras hold, from its
// point cloud: the points seen by at least one camera over the mean number one camera sees.
// A ring of cameras round an object sees almost every point from every view (about 1); a
// walk-around capture of a room, where each view sees a fifth of the scene, about 5. The static
// Gaussian budget (optim/lr_schedule.h, StaticGaussianBudget) scales one view's pixels by it.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "core/geometry/camera.h"

namespace hdr4d::method {

// At most this many points are projected (an even stride over the cloud): the ratio is a mean
// over views, and 4096 points give it to about 1% (once per run, at set-up).
inline constexpr int kContentViewsMaxPoints = 4096;

// Seen: in front of the camera and inside its image (the pinhole projection, no occlusion: a
// point on the far side of an object counts as seen, which is what a camera circling it does
// see over the ring). nullopt when there are no cameras, no points, or no point is seen by any
// camera (a cloud that does not lie in the scene, e.g. random points far off): the caller then
// keeps the budget of every view's pixels.
std::optional<double> ContentViews(const std::vector<Eigen::Vector3f>& points,
                                   const std::vector<Camera>& cameras,
                                   int max_points = kContentViewsMaxPoints);

}  // namespace hdr4d::method
