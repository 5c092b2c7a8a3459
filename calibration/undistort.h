// Radial undistortion of rig images to the pinhole camera the trainer renders (same focal
// length and principal point, k1 = k2 = 0), with OpenCV's remap.
#pragma once

#include "calibration/bundle_refinement.h"
#include "core/image/image.h"

namespace hdr4d {

// The largest displacement (pixels) the distortion causes inside a width x height image.
double MaxDistortionPixels(const BundleIntrinsics& k, int width, int height);

// The image as a pinhole camera with intrinsics f, cx, cy would see it (bilinear, borders
// replicated). Keeps the encoding.
Image Undistort(const Image& image, const BundleIntrinsics& k);

}  // namespace hdr4d
