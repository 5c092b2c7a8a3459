// The slice of a 4D model at time t as a standard 3D Gaussian Splatting .ply (the attribute
// layout every 3DGS viewer reads): x y z, nx ny nz, f_dc_0..2, f_rest_* (channel-major, 15 per
// channel at SH degree 3), opacity (logit), scale_0..2 (log), rot_0..3 (w x y z).
#pragma once

#include <cstddef>
#include <filesystem>

#include "method/gaussian/gaussian_model.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

// How a log-HDR model's colours become the display colours viewers expect: each Gaussian's
// view-independent log-HDR colour (the DC term at the slice time) through the run's tone mapper
// at `frame` (its exposure and time), or, without a tone mapper, exp(c) x exposure encoded as
// sRGB. The view-dependent SH terms of a log-HDR model do not survive a nonlinear map and are
// written as zeros.
struct ExportDisplay {
  ToneMapper* tone_mapper = nullptr;  // pointwise; null: exposure + sRGB
  ToneFrame frame;
};

// Writes the Gaussians visible at `time` (marginal > 0.05); the temporal basis is folded into
// the SH coefficients at that time and the marginal into the opacity. Returns how many were
// written. A log-HDR model needs `display`.
std::size_t ExportSlicePly(const GaussianModel& model,
                           float time,
                           float time_duration,
                           const std::filesystem::path& path,
                           const ExportDisplay* display = nullptr);

}  // namespace hdr4d::method
