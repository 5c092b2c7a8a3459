// Durand & Dorsey 2002 ("Fast bilateral filtering for the display of high-dynamic-range
// images"), a local operator, as a learnable whole-image tone mapper (the paper's "Durand" row of
// its tone-mapper ablation). For an image with exposed log radiance x_c = log_hdr_c + log exposure
// per pixel:
//   l      = log(0.2126 e^x_r + 0.7152 e^x_g + 0.0722 e^x_b)       log luminance (natural log)
//   base   = bilateral filter of l (guided by l)                    large-scale layer
//   detail = l - base                                               kept as it is
//   l_out  = compression * base + detail + offset                   only the base is compressed
//   C_c    = exp(l_out + x_c - l)                                   colour ratios restored
//   LDR_c  = min(C_c, 1)^(1 / gamma)                                display gamma
// so log C_c = x_c + (compression - 1) base + offset. Filter: spatial sigma 2% of the larger
// image side (at least 1 pixel), range sigma 0.4 decades (0.4 ln 10 in natural-log units), the
// 2002 paper's values, computed by the bilateral grid (baselines/bilateral_grid.h) rather than
// the paper's piecewise-linear scheme: its cost does not grow with the spatial sigma.
//
// The 2002 paper picks compression = log(5) / (max base - min base) and offset = -compression *
// max base per image, which would map every exposure of a view to the same LDR image; to
// reproduce multi-exposure LDR data both are learned instead, shared by all images (exposure then
// shifts the output by compression * log exposure). Parameters (each clamped to +-20 where used):
//   [0] log compression   init log 0.5
//   [1] offset            init log 0.18 (exposed radiance 1 maps to middle grey, as Reinhard's key)
//   [2] log gamma         init log 2.2 (stands in for the camera response of the LDR data)
// Learning rate 0.01, as the other few-scalar mappers (see sigmoid_tone_mapper.h).
//
// Gradients. Exact through: the log luminance l (every pixel's log-sum-exp, including the detail
// layer and the colour ratios), the filtered values (base is linear in l for fixed weights), the
// compression, the offset and the gamma. Held constant: every weight of the bilateral filter, i.e.
// the grid positions of the pixels along the range axis, their trilinear splat/slice weights, the
// grid's range origin (min l) and the normalisation, all of which depend on l through its role as
// the filter's guide. The backward is therefore the exact gradient of DurandForwardGuided with the
// guide fixed at the current l. (The range weights' own gradient is what makes a bilateral filter
// discontinuous at a grid cell boundary; dropping it is the usual choice for edge-aware filters.)
//
// Not pointwise: Map and MapBackward are a caller bug (checked); use MapImage / MapImageBackward.
#pragma once

#include <cstddef>

#include "baselines/param_tone_mapper.h"

namespace hdr4d::baselines {

inline constexpr int kDurandNumParams = 3;

struct DurandFilter {
  double sigma_space = 1.0;                      // pixels
  double sigma_range = 0.4 * 2.302585092994046;  // natural-log units
};
// The 2002 paper's filter for an image of this size.
DurandFilter DefaultDurandFilter(int width, int height);

// Per-pixel log luminance of the exposed, clamped log radiance (width x height values).
template <typename T>
void DurandLogLuminance(const T* log_hdr, T log_exposure, int width, int height, T* log_lum);

// The forward with the filter's weights taken from `guide` (width x height) instead of from the
// image's own log luminance: DurandForward is DurandForwardGuided with guide = that luminance.
template <typename T>
void DurandForwardGuided(const T* params,
                         T log_exposure,
                         const T* log_hdr,
                         int width,
                         int height,
                         const DurandFilter& filter,
                         const T* guide,
                         T* ldr);

template <typename T>
void DurandForward(const T* params,
                   T log_exposure,
                   const T* log_hdr,
                   int width,
                   int height,
                   const DurandFilter& filter,
                   T* ldr);

// The gradient described above: dL_dlog_hdr (width x height x 3, overwritten; may be null) and
// dL_dparams (3 values, ADDED to, reduced in chunk order).
template <typename T>
void DurandBackward(const T* params,
                    T log_exposure,
                    const T* log_hdr,
                    int width,
                    int height,
                    const DurandFilter& filter,
                    const T* dL_dldr,
                    T* dL_dlog_hdr,
                    T* dL_dparams);

class DurandToneMapper final : public ParamToneMapper {
 public:
  static constexpr float kLearningRate = 0.01f;
  static constexpr double kInitialCompression = 0.5;
  static constexpr double kInitialOffset = -1.7147984280919266;  // log 0.18
  static constexpr double kInitialGamma = 2.2;

  explicit DurandToneMapper(const method::ToneMapperConfig& config);

  bool pointwise() const override { return false; }
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr,
                   std::size_t n,
                   const float* dL_dldr,
                   float* dL_dlog_hdr) override;
  void MapImage(const float* log_hdr, int width, int height, float* ldr) const override;
  void MapImageBackward(const float* log_hdr,
                        int width,
                        int height,
                        const float* dL_dldr,
                        float* dL_dlog_hdr) override;
  float learning_rate() const override { return kLearningRate; }
};

}  // namespace hdr4d::baselines
