// Rigs of unlike cameras: each camera's fused HDR differs from the others' on the same surface
// by a gain per colour channel (sensor sensitivity, white balance). The gains come from the
// sparse points that several cameras saw: each camera's log radiance there against the
// points' mean, a median over points (moving objects and occlusions are outliers).
// Each camera averages the same patch of surface around a point: a disc of footprint_pixels
// radius in the camera that sees the surface smallest, wider in proportion in the cameras that
// see it larger (focal length over depth). A fixed 3x3 window (footprint 0) averaged a larger
// patch in the farther camera; at the features' blobs and edges that biased the gains by the
// cameras' distances (unlike 320x240 and 640x480 rigs: the cameras' HDR scales 3.5% and 4.2%
// apart with it, 1.4% and 2.5% with a footprint of 3 px; docs/history/calibration.md, ninth pass).
#pragma once

#include <array>
#include <vector>

#include "calibration/rig_geometry.h"
#include "calibration/vignetting_correction.h"
#include "core/image/image.h"

namespace hdr4d {

struct CameraGains {
  std::vector<std::array<double, 3>> gain;  // per camera and channel; geometric mean 1 per channel
  // Median over (point, camera) of |radiance / the point's mean radiance - 1|, before and
  // after dividing by the gains.
  // Both carry the texture's scatter between where each camera samples a point (a floor of
  // 3-5% on textured walls even for a perfect calibration).
  double disagreement_before = 0, disagreement_after = 0;
  // What measures the calibration instead: gains from half the points (alternate ones), then
  // each camera's median residual on the other half, max over cameras, channels and the two
  // halves of |bias - 1| (0 below 20 points). Scatter averages out in the medians.
  double held_out_bias = 0;
  int points_used = 0;
  // Sampled in the static images (the empty scene) rather than the first frame's fused HDR.
  bool from_static_images = false;
  double footprint_pixels = 0;  // the patch each camera averaged (see above; 0: 3x3 windows)
  // Each camera's vignetting v (radiance x 1 - v (r / r_corner)^2) from the same points
  // (calibration/vignetting_estimate.h), and the v divided out of the samples before the gains
  // were solved (0 where not; vignetting_correction.h says which): calibrate divides the same
  // out of the camera's HDR and brackets.
  std::vector<double> vignetting, vignetting_error, vignetting_applied;  // error: its standard error
  double Mean(int camera) const;  // mean of the three channel gains
};

constexpr double kGainFootprintPixels = 3;

// `hdr` holds one fused RGB image per rig camera of the same time (distorted, as fused).
// `rig.visibility` says which cameras saw each point. Fewer than 10 shared points: gains 1, no
// vignetting. `vignetting` says which cameras' falloff is divided out before the gains.
CameraGains EstimateCameraGains(const Rig& rig, const std::vector<Image>& hdr,
                                double footprint_pixels = kGainFootprintPixels,
                                VignettingCorrection vignetting = VignettingCorrection::kAuto);

}  // namespace hdr4d
