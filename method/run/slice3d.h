// One 4D Gaussian as the 3D Gaussian it shows at a time t (its conditional mean and covariance,
// and the temporal marginal that scales its opacity), and that covariance as the scale and
// rotation of a 3DGS .ply. Shared by the .ply exports (export_ply.h, hdr_ply.h).
#pragma once

#include <cstddef>
#include <optional>

#include "method/gaussian/gaussian_model.h"
#include "method/gaussian/rotation4d.h"

namespace hdr4d::method {

struct Slice3D {
  Vec3<double> mean;
  Mat3<double> cov;
  double marginal = 1.0;  // 1 for a static model
};

// Gaussian i at `time`; nullopt when the renderer's temporal cull drops it (marginal <= 0.05).
std::optional<Slice3D> SliceGaussian(const GaussianModel& model, std::size_t i, float time);

// The covariance's principal axes as 3DGS writes them: log standard deviations (scale_0..2) and
// the unit rotation quaternion (w, x, y, z) whose columns are the axes (a proper rotation).
struct ScaleRotation {
  double log_scale[3];
  double quaternion[4];
};
ScaleRotation PrincipalAxes(const Mat3<double>& cov);

// The colour coefficients of Gaussian i with the temporal basis folded in at `time` (dt = mu_t -
// time, period `time_duration`): sh_functions() values per channel, coefficient-major
// (out[lm * channels + c]), DC first. A static model's are its coefficients as they are.
void FoldedShCoefficients(const GaussianModel& model,
                          std::size_t i,
                          float time,
                          float time_duration,
                          double* out);

}  // namespace hdr4d::method
