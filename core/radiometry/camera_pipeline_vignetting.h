// Vignetting: the lens passes less light towards the image's corners. Modelled as
//   v(r) = 1 - s r^2,   r = distance of the pixel centre from the image centre / half-diagonal,
// so v = 1 at the centre, 1 - s in the corners, falling monotonically in between (the first
// term of the usual even polynomial; cos^4 falloff is ~ 1 - 2 tan^2 of the field angle).
// s in [0, 1).
#pragma once

#include "core/image/image.h"

namespace hdr4d {

// Pixel (x, y) of a width x height image, pixel centres at (x + 0.5, y + 0.5).
double VignettingFactor(int x, int y, int width, int height, double strength);

// Every colour channel multiplied by v(r) in place (a 4th channel, alpha, untouched).
void ApplyVignetting(Image& image, double strength);

}  // namespace hdr4d
