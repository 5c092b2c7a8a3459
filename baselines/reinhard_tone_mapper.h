// Reinhard et al. 2002 ("Photographic tone reproduction"), the global operator with a white
// point, as a learnable pointwise tone mapper (the paper's "Reinhard" row of its tone-mapper
// ablation). For one pixel with exposed radiance E_c = exp(log_hdr_c) * exposure:
//   L_w = 0.2126 E_r + 0.7152 E_g + 0.0722 E_b           (luminance)
//   L_s = key * L_w                                       (scaled luminance)
//   L_d = L_s (1 + L_s / L_white^2) / (1 + L_s)           (display luminance; 1 at L_s = L_white)
//   C_c = L_d * E_c / L_w                                 (colours keep their ratios)
//   LDR_c = min(C_c, 1)^(1 / gamma)                       (display gamma)
// The 2002 paper scales by key / (log-average luminance of the image); that average is one
// constant per image, so here it is folded into the learned key (which is then also shared by
// every image: exposure enters only through E). The display gamma stands in for the camera
// response the LDR data went through (the 2002 operator outputs linear display luminance).
//
// Parameters (log-parameterised so they stay positive; each clamped to +-20 where used):
//   [0] log key       init log 0.18 (the paper's "normal key", middle grey)
//   [1] log L_white   init log 2 (burns out 3.5 stops above middle grey; 1 would make L_d = L_s)
//   [2] log gamma     init log 2.2
// Everything is evaluated on logs (log L_d = -softplus(-l) + softplus(l - 2 log L_white) with
// l = log L_s, luminance by log-sum-exp), so radiance from e^-60 to e^60 at any exposure gives
// finite values in [0, 1] and finite gradients. Learning rate 0.01 (Adam moves each
// log-parameter by about 1% per step; see sigmoid_tone_mapper.h for the reasoning).
#pragma once

#include <cstddef>

#include "baselines/param_tone_mapper.h"

namespace hdr4d::baselines {

inline constexpr int kReinhardNumParams = 3;

// ldr (n x 3) from log_hdr (n x 3) with params [log key, log white, log gamma].
template <typename T>
void ReinhardForward(const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr);

// dL_dlog_hdr (n x 3, overwritten; may be null) and dL_dparams (3 values, ADDED to), reduced in
// chunk order (the same bits at any thread count).
template <typename T>
void ReinhardBackward(const T* params,
                      T log_exposure,
                      const T* log_hdr,
                      std::size_t n,
                      const T* dL_dldr,
                      T* dL_dlog_hdr,
                      T* dL_dparams);

class ReinhardToneMapper final : public ParamToneMapper {
 public:
  static constexpr float kLearningRate = 0.01f;
  static constexpr double kInitialKey = 0.18;
  static constexpr double kInitialWhite = 2.0;
  static constexpr double kInitialGamma = 2.2;

  explicit ReinhardToneMapper(const method::ToneMapperConfig& config);

  bool pointwise() const override { return true; }
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr,
                   std::size_t n,
                   const float* dL_dldr,
                   float* dL_dlog_hdr) override;
  float learning_rate() const override { return kLearningRate; }
};

}  // namespace hdr4d::baselines
