// What a synthetic capture's cameras add to the pinhole render (`hdr4d datagen --capture`):
// each camera's own lens (radial distortion, vignetting) and its sensor's black pedestal with
// dark noise. The truth (truth/cameras.json) records every number drawn here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/camera.h"
#include "core/image/image.h"

namespace hdr4d::datagen {

struct CaptureLens {
  // COLMAP's RADIAL model on normalised coordinates: x_d = x (1 + k1 r^2 + k2 r^4).
  double k1 = 0, k2 = 0;
  // Radiance times 1 - vignetting (r / r_corner)^2, r the distance from the principal point.
  double vignetting = 0;
  bool Identity() const { return k1 == 0 && k2 == 0 && vignetting == 0; }
};

// Camera c's lens for `mode` (none, distortion, vignetting, both), drawn from the seed for every
// camera whatever the mode (so one camera's lens does not depend on it): k1 in [0.03, 0.10],
// k2 in [0, 0.03] (pincushion: every distorted pixel looks inside the pinhole render, none
// needs what was not rendered), vignetting in [0.05, 0.25].
std::vector<CaptureLens> DrawCaptureLenses(const std::string& mode, std::uint64_t seed, int count);

// The pinhole render `hdr` (intrinsics `k`, pixel i's centre at i + 0.5) as the lens images it:
// each output pixel's distorted ray undistorted (fixed-point iteration) and the render sampled
// bilinearly there, then the vignetting. The identity lens returns `hdr` unchanged.
Image ApplyCaptureLens(const Image& hdr, const CaptureLens& lens, const PinholeIntrinsics& k);

// The sensor's pedestal: display values y in [0, 1] (unquantised) to 8-bit codes
// round(black + (255 - black) y + N(0, noise)), clamped to [0, 255], as values code / 255; a
// clipped value (y = 1) stays 255.
// Deterministic in `seed`. Throws hdr4d::Error for a black level outside [0, 128) or a negative
// or non-finite noise.
Image ApplyBlackLevel(const Image& display, double black, double noise, std::uint64_t seed);

}  // namespace hdr4d::datagen
