// The slice of a 4D model at time t as a standard 3D Gaussian Splatting .ply (the attribute
// layout every 3DGS viewer reads): x y z, nx ny nz, f_dc_0..2, f_rest_* (channel-major, 15 per
// channel at SH degree 3), opacity (logit), scale_0..2 (log), rot_0..3 (w x y z).
#pragma once

#include <cstddef>
#include <filesystem>

#include "method/gaussian_model.h"

namespace hdr4d::method {

// Writes the Gaussians visible at `time` (marginal > 0.05); the temporal basis is folded into
// the SH coefficients at that time and the marginal into the opacity. Returns how many were
// written. A log-HDR model is refused (viewers expect display colours).
std::size_t ExportSlicePly(const GaussianModel& model,
                           float time,
                           float time_duration,
                           const std::filesystem::path& path);

}  // namespace hdr4d::method
