// Coarse-to-fine images (`hdr4d train --coarse-to-fine N`, issue 55): the first N iterations
// render and supervise at a reduced size, 1/4 over the first half of them and 1/2 over the rest.
// A view whose width or height the factor does not divide is reduced over its top-left
// floor(W / f) f x floor(H / f) f pixels: the last W mod f columns and H mod f rows (at most 3)
// are left out of a coarse step, so real captures of any size take the coarse part too.
// The camera's intrinsics are those of the reduced image (CoarseIntrinsics), and the targets
// are box averages of the full ones, so a step at 1/f costs about 1/f^2 of a full one.
#pragma once

#include <vector>

#include "core/geometry/camera.h"

namespace hdr4d::method {

// The reduction of iteration `iteration` (1-based) of a run with `coarse_iterations` coarse
// ones for a width x height view: 4, 2 or 1 (the largest of those up to the schedule's that
// leaves at least one pixel each way).
int CoarseFactor(int iteration, int coarse_iterations, int width, int height);

// The intrinsics of the reduced image: floor(W / f) x floor(H / f) pixels. Output pixel i covers
// input [i f, (i + 1) f) (pixel centres at i + 0.5, core/geometry/camera.h), so focal lengths
// and principal point divide by f exactly; the left-out columns and rows move nothing.
PinholeIntrinsics CoarseIntrinsics(const PinholeIntrinsics& intrinsics, int factor);

// `image` (H x W x channels, row-major) reduced in place by `factor` to floor(W / f) x
// floor(H / f): each output value is the mean of the f x f block it covers. Factor 1 leaves it.
void BoxReduceInPlace(std::vector<float>* image, int width, int height, int channels, int factor);

}  // namespace hdr4d::method
