// 4D Gaussians in structure-of-arrays form (DESIGN §4, §6): one contiguous buffer per field,
// so preprocessing streams through memory and gradients have the same layout.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace hdr4d::method {

// How the colour coefficients are read.
enum class ColorMode {
  kLdr,     // 4DGS: colour = max(SH x time value + 0.5, 0)
  kLogHdr,  // HDR-4DGS: log HDR colour = SH x time value + 0.5, unclamped; HDR = exp of it
};

// Sizes of the colour basis: spatial SH degree D (0..3) gives (D+1)^2 functions; the temporal
// basis {1, cos(2 pi dt / T), cos(4 pi dt / T)} up to degree L (0..2) multiplies each, so a
// channel has (D+1)^2 (L+1) coefficients, index = 16-stride blocks: k = lm + 16 * n when the
// maximum spatial degree is 3 (in general lm + (Dmax+1)^2 * n).
struct ColorBasis {
  int max_sh_degree = 3;
  int max_time_degree = 2;  // 0 in 3D mode
  int sh_functions() const { return (max_sh_degree + 1) * (max_sh_degree + 1); }
  int coefficients() const { return sh_functions() * (max_time_degree + 1); }
};

// Parameters of N Gaussians. `temporal` false is the 3D mode (static scenes, static baselines):
// the t components of means/log_scales and the right quaternion are ignored and there is no
// temporal slicing or marginal.
struct GaussianModel {
  bool temporal = true;
  ColorMode color_mode = ColorMode::kLdr;
  ColorBasis basis;
  int channels = 3;  // colour channels the coefficients produce

  std::vector<float> means;          // N x 4: x, y, z, t
  std::vector<float> log_scales;     // N x 4: log standard deviations along the 4 axes
  std::vector<float> rot_left;       // N x 4: q_l = (a, b, c, d), normalised when used
  std::vector<float> rot_right;      // N x 4: q_r = (p, q, r, s), normalised when used
  std::vector<float> opacity_logit;  // N: opacity = sigmoid(logit)
  std::vector<float> color;          // N x K x channels: coefficient k of channel c at (i*K + k)*channels + c

  std::size_t size() const { return opacity_logit.size(); }
  void Resize(std::size_t n);       // fills new entries with zeros (identity rotations)
  std::string Validate() const;      // "" when the buffers agree in size
};

// Gradients with exactly the model's layout.
using GaussianGradients = GaussianModel;

}  // namespace hdr4d::method
