// Each rig camera's vignetting from the sparse points that several cameras saw (issue 54;
// vignetting_correction.h decides where it is divided out). The model is datagen's: radiance
// times 1 - v (r / r_corner)^2,
// r the distance from the principal point. It is identifiable without a flat field because one
// point lands at different radii in different cameras: the log radiance of point p in camera c is
// l_p + a_c + ln(1 - v_c r_pc^2), and with radius pairs that vary over the points the gain a_c
// and the falloff v_c separate (the common part of v too). Solved by alternating the points'
// means with a Gauss-Newton fit of (a_c, v_c) per camera; samples whose residual exceeds 30% are
// left out of each fit (occlusions, highlights).
#pragma once

#include <vector>

namespace hdr4d {

struct VignettingSample {
  int camera = 0;
  double log_radiance = 0;  // mean over the colour channels
  double r2 = 0;            // (r / r_corner)^2, in [0, 1]
};

// points[p] = the cameras that saw point p. Returns v per camera (0 where a camera has fewer
// than 20 samples), clamped to [-0.5, 0.9]; with `standard_error`, each v's standard error there
// (infinite where no estimate was made).
std::vector<double> EstimateVignetting(const std::vector<std::vector<VignettingSample>>& points, int cameras,
                                       std::vector<double>* standard_error = nullptr);

}  // namespace hdr4d
