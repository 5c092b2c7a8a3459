// The static MLP tone mapper of HDR-GS (Cai et al. 2024; ARCHITECTURE §4),
// the "MLP (HDR-GS)" row of the paper's tone-mapper ablation: three independent per-channel
// networks 1 -> 128 -> 1 with a ReLU hidden layer and a sigmoid output, applied pointwise to
// x_c = log_hdr_c + log exposure. It has no notion of time: one curve for every frame.
//
// Two exact evaluations: `direct` runs method::MlpForward / MlpBackward per value; the default
// (ToneMapperConfig::tabulated, the same switch as the Dynamic Tone Mapper's fast path) uses the
// network's piecewise-linear form (baselines/static_mlp_curve.h), much faster
// (docs/history/tone-mappers.md) and equal to the direct path up to float rounding (tested), so the
// baseline is not slowed by its evaluator.
//
// Like HDR-GS it starts from PyTorch's default initialisation with no pretraining. By default
// (ToneMapperConfig::monotone_curves) its weights are used as monotone_mlp.h says, so each curve
// is non-decreasing; without it, as in HDR-GS, the curve is unconstrained and learns one branch
// per exposure on multi-exposure data (issue 12). Its learning rate is
// HDR-GS's 5e-4 (HDR-GS configures a decay but never applies it). Inputs are clamped as
// log_domain.h says, so log 0 behaves as very dark radiance with zero gradient.
#pragma once

#include <cstddef>

#include "baselines/param_tone_mapper.h"
#include "method/tonemap/mlp.h"

namespace hdr4d::baselines {

inline constexpr int kStaticMlpHidden = 128;

// One channel's network: {1, 128, 1}, sigmoid output.
const method::MlpShape& StaticMlpShape();
// All parameters: the R, G and B networks one after another.
std::size_t StaticMlpNumParams();

// ldr (n x 3) from log_hdr (n x 3). Parallel over fixed chunks.
template <typename T>
void StaticMlpForward(const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr);

// dL_dlog_hdr (n x 3, overwritten; may be null) and dL_dparams (ADDED to), reduced in chunk
// order: the same bits at any thread count.
template <typename T>
void StaticMlpBackward(const T* params,
                       T log_exposure,
                       const T* log_hdr,
                       std::size_t n,
                       const T* dL_dldr,
                       T* dL_dlog_hdr,
                       T* dL_dparams);

// The same two through the piecewise-linear form (static_mlp_curve.h).
template <typename T>
void StaticMlpForwardPiecewise(
    const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr);
template <typename T>
void StaticMlpBackwardPiecewise(const T* params,
                                T log_exposure,
                                const T* log_hdr,
                                std::size_t n,
                                const T* dL_dldr,
                                T* dL_dlog_hdr,
                                T* dL_dparams);

class StaticMlpToneMapper final : public ParamToneMapper {
 public:
  // Weights from config.seed (a different stream per channel).
  explicit StaticMlpToneMapper(const method::ToneMapperConfig& config);

  bool pointwise() const override { return true; }
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr,
                   std::size_t n,
                   const float* dL_dldr,
                   float* dL_dlog_hdr) override;

 private:
  // The weights Map uses: params_ itself, or (config.monotone_curves) their monotone effective
  // form (monotone_mlp.h), made from the current params_ on every call (about 1000 values).
  const float* Effective(std::vector<float>* scratch) const;
  std::vector<float> effective_grad_;
};

}  // namespace hdr4d::baselines
