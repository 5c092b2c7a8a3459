// How many distinct directions a scene's training cameras look along: what decides whether the
// colours' view-dependent bands are constrained early (the many-view schedule, issue 55;
// optim/lr_schedule.h, ManyViewSchedule). A ring of 20 cameras round an object looks along 20
// directions; a rig of four, along four whatever its number of frames; a forward-facing capture,
// along about one however far the camera walks.
#pragma once

#include <vector>

#include "core/geometry/camera.h"

namespace hdr4d::method {

// Two cameras whose optical axes are closer than this constrain a degree-3 colour band (whose
// lobes are some 60 degrees wide) about as one camera does.
inline constexpr double kDistinctViewAngleDegrees = 10.0;

// A greedy cover, in the cameras' order: a camera's view direction counts when it is at least
// min_angle_degrees from every direction counted before it. Deterministic; a camera whose
// direction is not finite is skipped. O(cameras x count).
int DistinctViewDirections(const std::vector<Camera>& cameras,
                           double min_angle_degrees = kDistinctViewAngleDegrees);

}  // namespace hdr4d::method
