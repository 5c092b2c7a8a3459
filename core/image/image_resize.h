// Integer downsampling for training and scoring at 1/R of the images' size (`hdr4d train
// --resolution`, `hdr4d eval --resolution`).
#pragma once

#include <string>

#include "core/image/image.h"

namespace hdr4d {

// The image reduced by an integer `factor` (>= 1, dividing width and height; checked): each
// output pixel is the mean of the factor x factor block it covers, per channel, in the image's
// own encoding. An area filter, exact for integer factors: the output pixel covers exactly
// those input pixels (no ringing, no neighbour leaking in). factor 1 returns a copy.
Image DownsampleBox(const Image& image, int factor);

// "" when `resolution` can reduce a width x height image, else the problem.
std::string ResolutionProblem(int width, int height, int resolution);

}  // namespace hdr4d
