// Coarse-to-fine images (`hdr4d train --coarse-to-fine N`, issue 55): the first N iterations
// render and supervise at a reduced size, 1/4 over the first half of them and 1/2 over the rest
// (each only where the factor divides the view's width and height; else the next smaller one).
// The camera's intrinsics are those of the reduced image (DownscaledIntrinsics), and the targets
// are box averages of the full ones, so a step at 1/f costs about 1/f^2 of a full one.
#pragma once

#include <vector>

namespace hdr4d::method {

// The reduction of iteration `iteration` (1-based) of a run with `coarse_iterations` coarse
// ones for a width x height view: 4, 2 or 1.
int CoarseFactor(int iteration, int coarse_iterations, int width, int height);

// `image` (H x W x channels, row-major) reduced in place by `factor` (dividing W and H; checked):
// each output value is the mean of the factor x factor block it covers. Factor 1 leaves it.
void BoxReduceInPlace(std::vector<float>* image, int width, int height, int channels, int factor);

}  // namespace hdr4d::method
