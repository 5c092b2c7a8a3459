// Dividing each rig camera's vignetting out of what calibrate writes (issue 54). The falloff is
// datagen's model, radiance x (1 - v (r / r_corner)^2) with r from the principal point in the
// image as captured (before any undistortion), v estimated from the shared sparse points
// (vignetting_estimate.h). A per-camera gain cannot undo a radial falloff: on rendered captures
// with vignetting it left one camera's HDR scale 3.5-3.7% off the others.
//
// Both the fused HDR and the LDR brackets are corrected, so the dataset stays consistent
// (LDR = response(radiance x exposure) for the devignetted radiance): each bracket is
// linearised through the camera's response, divided by the falloff and encoded again (a
// saturated code stays saturated; written as 16-bit PNG, as undistorted brackets are).
#pragma once

#include <string>
#include <vector>

#include "calibration/response_recovery.h"
#include "calibration/rig_geometry.h"
#include "core/image/image.h"

namespace hdr4d {

enum class VignettingCorrection {
  kAuto,    // correct the cameras whose falloff is measured (see VignettingToApply)
  kAlways,  // correct every camera by its estimate (where one was made)
  kNever,   // measure and report only
};

// "auto", "on" or "off"; throws hdr4d::Error naming the flag otherwise.
VignettingCorrection ParseVignettingCorrection(const std::string& text);
std::string ToString(VignettingCorrection mode);

// `auto` divides out a camera's falloff where it is both large enough to matter and resolved
// by the data: v >= kVignettingApplyFrom and v >= kVignettingSignificance standard errors
// (vignetting_estimate.h; that error ignores the points' means and the texture's sampling bias,
// so it is a lower bound). Measured on rendered captures (docs/history/calibration.md, tenth
// pass): without vignetting the estimates reached 0.079 at 320x240, at 3.0-3.4 standard errors;
// with it, every estimate within 0.03 of the truth stood at 4.1 standard errors or more.
constexpr double kVignettingApplyFrom = 0.05;
constexpr double kVignettingSignificance = 4;

// The v to divide out per camera: the estimate or 0 (negative or non-finite estimates never;
// `on` ignores the thresholds).
std::vector<double> VignettingToApply(const std::vector<double>& estimate, const std::vector<double>& standard_error,
                                      VignettingCorrection mode);

// (r / r_corner)^2 of pixel position (u, v) (pixel i spans [i, i + 1)): r from the principal
// point, r_corner to the farthest image corner. In [0, 1].
double CornerRadius2(const RigCamera& camera, double u, double v);

// The falloff 1 - strength x CornerRadius2, floored at 0.1 (the estimate is clamped below 0.9).
double VignettingFalloff(const RigCamera& camera, double strength, double u, double v);

// Linear radiance divided by the falloff at every pixel.
Image DevignetteLinear(const Image& hdr, const RigCamera& camera, double strength);

// Display values (an LDR bracket in [0,1]) linearised by `response`, divided by the falloff
// and encoded again.
Image DevignetteDisplay(const Image& ldr, const RigCamera& camera, double strength, const CameraResponse& response);

}  // namespace hdr4d
