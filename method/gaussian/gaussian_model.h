// 4D Gaussians in structure-of-arrays form (ARCHITECTURE §4, §6): one contiguous buffer per field,
// so preprocessing streams through memory and gradients have the same layout.
#pragma once

#include <algorithm>
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
// channel has K = (D+1)^2 (L+1) coefficients, k = lm + (Dmax+1)^2 n (16-stride blocks when the
// maximum spatial degree is 3). Coefficient 0 is the DC term.
struct ColorBasis {
  int max_sh_degree = 3;
  int max_time_degree = 2;  // 0 in 3D mode
  int sh_functions() const { return (max_sh_degree + 1) * (max_sh_degree + 1); }
  int coefficients() const { return sh_functions() * (max_time_degree + 1); }
  // The coefficients a colour at these degrees reads: k = n F + lm with n <= time degree and
  // lm < (sh degree + 1)^2 end at the last such k; every weight after it is 0.
  int used_coefficients(int sh_degree, int time_degree) const {
    const int active = (sh_degree + 1) * (sh_degree + 1);
    return std::min(coefficients(), time_degree * sh_functions() + active);
  }
};

// Parameters of N Gaussians. `temporal` false is the 3D mode (static scenes, static baselines):
// the t components of means/log_scales and the right quaternion are ignored and there is no
// temporal slicing or marginal. Templated on the scalar so the finite-difference tests can run
// the renderer in double; training uses GaussianModel (float).
template <typename T>
struct GaussianModelT {
  bool temporal = true;
  ColorMode color_mode = ColorMode::kLdr;
  ColorBasis basis;
  int channels = 3;  // colour channels the coefficients produce

  // One buffer per optimiser group, as the reference's parameter tensors (they get different
  // learning rates): xyz, t, scales (3 + 1), both quaternions, opacity, colour DC and the rest.
  std::vector<T> xyz;            // N x 3: spatial mean
  std::vector<T> t;              // N: temporal mean
  std::vector<T> log_scales;     // N x 4: log standard deviations along the 4 axes
  std::vector<T> rot_left;       // N x 4: q_l = (a, b, c, d), normalised when used
  std::vector<T> rot_right;      // N x 4: q_r = (p, q, r, s), normalised when used
  std::vector<T> opacity_logit;  // N: opacity = sigmoid(logit)
  std::vector<T> color_dc;       // N x channels: coefficient 0 (Y_00, time block 0)
  std::vector<T> color_rest;     // N x (K - 1) x channels: coefficient k at ((i (K-1) + k-1) C + c)

  std::size_t size() const { return opacity_logit.size(); }
  std::size_t rest_stride() const {  // floats of color_rest per Gaussian
    return static_cast<std::size_t>(basis.coefficients() - 1) * channels;
  }

  // Fills new entries with zeros and identity rotations.
  void Resize(std::size_t n) {
    const std::size_t old = size();
    xyz.resize(n * 3, T(0));
    t.resize(n, T(0));
    log_scales.resize(n * 4, T(0));
    rot_left.resize(n * 4, T(0));
    rot_right.resize(n * 4, T(0));
    opacity_logit.resize(n, T(0));
    color_dc.resize(n * channels, T(0));
    color_rest.resize(n * rest_stride(), T(0));
    for (std::size_t i = old; i < n; ++i) rot_left[i * 4] = rot_right[i * 4] = T(1);
  }

  // Same shape as `other`, every value zero (a gradient buffer for it). Without `colour` the
  // colour buffers are left empty: training hands the colour gradient rows straight from the
  // backward to the optimiser (fused_adam_step.h), so nine tenths of the gradient need no buffer.
  void ZerosLike(const GaussianModelT& other, bool colour = true) {
    temporal = other.temporal;
    color_mode = other.color_mode;
    basis = other.basis;
    channels = other.channels;
    xyz.assign(other.xyz.size(), T(0));
    t.assign(other.t.size(), T(0));
    log_scales.assign(other.log_scales.size(), T(0));
    rot_left.assign(other.rot_left.size(), T(0));
    rot_right.assign(other.rot_right.size(), T(0));
    opacity_logit.assign(other.opacity_logit.size(), T(0));
    if (colour) {
      color_dc.assign(other.color_dc.size(), T(0));
      color_rest.assign(other.color_rest.size(), T(0));
    } else {
      // Swapped with empty buffers to release the memory (`= {}` and clear keep the capacity).
      std::vector<T>().swap(color_dc);
      std::vector<T>().swap(color_rest);
    }
  }

  // "" when the buffers agree in size and the basis is in range, else what is wrong.
  std::string Validate() const {
    const std::size_t n = size();
    if (basis.max_sh_degree < 0 || basis.max_sh_degree > 3 || basis.max_time_degree < 0 ||
        basis.max_time_degree > 2) {
      return "colour basis out of range: SH degree " + std::to_string(basis.max_sh_degree) +
             ", time degree " + std::to_string(basis.max_time_degree);
    }
    if (channels < 1) return "a model needs at least one colour channel";
    if (xyz.size() != n * 3 || t.size() != n || log_scales.size() != n * 4 ||
        rot_left.size() != n * 4 || rot_right.size() != n * 4 || color_dc.size() != n * channels ||
        color_rest.size() != n * rest_stride()) {
      return "Gaussian buffers disagree in size with " + std::to_string(n) + " opacities";
    }
    return "";
  }
};

using GaussianModel = GaussianModelT<float>;
// Gradients with exactly the model's layout.
template <typename T>
using GaussianGradientsT = GaussianModelT<T>;
using GaussianGradients = GaussianModel;

}  // namespace hdr4d::method
