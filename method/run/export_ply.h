// The slice of a 4D model at time t as a standard 3D Gaussian Splatting .ply (the attribute
// layout every 3DGS viewer reads): x y z, nx ny nz, f_dc_0..2, f_rest_* (channel-major, 15 per
// channel at SH degree 3), opacity (logit), scale_0..2 (log), rot_0..3 (w x y z); with the HDR
// extension (HdrPlyExtension), the same columns plus the log-radiance SH of a log-HDR model
// (docs/hdr-ply.md has the layout; gaussian_ply_reader.h reads both back).
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/render/hdr_head.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

// How a log-HDR model's colours become the display colours viewers expect: each Gaussian's
// view-independent log-HDR colour (the DC term at the slice time) through the run's tone mapper
// at `frame` (its exposure and time), or, without a tone mapper, exp(c) x exposure encoded as
// sRGB. The view-dependent SH terms of a log-HDR model do not survive a nonlinear map and are
// written as zeros (the HDR extension keeps them exactly).
struct ExportDisplay {
  ToneMapper* tone_mapper = nullptr;  // pointwise; null: exposure + sRGB
  ToneFrame frame;
};

// The HDR extension: columns f_hdr_dc_0..2 and f_hdr_rest_* with the SH coefficients of the
// natural log of linear radiance, radiance(d) = exp(0.5 + sum_lm Y_lm(d) f_hdr_lm) (the HDR
// head's offsets and factor folded in), and header comments naming the extension, the slice
// time, the scene's exposure range and the learned background.
struct HdrPlyExtension {
  double exposure_min = 0, exposure_max = 0;    // seconds, the training images'
  std::vector<float> background_log_radiance;  // 3, or empty: a black background
  const HdrHead* head = nullptr;               // null or empty: none
};

// Writes the Gaussians visible at `time` (marginal > 0.05); the temporal basis is folded into
// the SH coefficients at that time and the marginal into the opacity. Returns how many were
// written. A log-HDR model needs `display`; `hdr` (a log-HDR model only) adds the extension.
std::size_t ExportSlicePly(const GaussianModel& model,
                           float time,
                           float time_duration,
                           const std::filesystem::path& path,
                           const ExportDisplay* display = nullptr,
                           const HdrPlyExtension* hdr = nullptr);

}  // namespace hdr4d::method
