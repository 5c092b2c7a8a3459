// The preprocess of one frame: per Gaussian the 4D rotation and covariance, the slice at time t,
// the temporal cull, the EWA projection, opacity x marginal and the SH x time colour, into the
// splats the rasteriser blends; and its backward (ARCHITECTURE §4, steps 3-5 and 10).
//
// Two implementations of the same maths, tested against each other:
//   - the reference, generic in the scalar type T (float and double), per Gaussian with the
//     header-only maths of method/gaussian/; every mode (4D and 3D). The finite-difference tests
//     run it in double.
//   - the fast path, float only, 4D and 3D: the Highway kernels of preprocess_simd.h over batches
//     of 16 Gaussians (runtime dispatch over the compiled targets), the colour sums per Gaussian.
//     The 3D mode matters as much as the 4D one: every static scene trains a 3D model, and there
//     the reference preprocess was a third of a real training iteration
//     (docs/history/real-run-speed.md).
// PreprocessForward / PreprocessBackward pick the fast path where it applies.
#pragma once

#include <type_traits>

#include "method/render/frame_state.h"

namespace hdr4d::method {

// Whether PreprocessForward / Backward take the fast path: float and the SIMD blend backend.
template <typename T>
bool FastPreprocessApplies(const GaussianModelT<T>& /*model*/, const RenderOptions& options) {
  return std::is_same_v<T, float> && options.backend == RasterBackend::kSimd;
}

// The reference, for any model and options.
template <typename T>
void PreprocessForwardReference(const GaussianModelT<T>& model,
                                const ViewParams<T>& view,
                                T time,
                                const RenderOptions& options,
                                FrameStateT<T>* state);
template <typename T>
void PreprocessBackwardReference(const GaussianModelT<T>& model,
                                 const ViewParams<T>& view,
                                 T time,
                                 const RenderOptions& options,
                                 const FrameStateT<T>& state,
                                 GaussianGradientsT<T>* grads,
                                 const GradientRowsDoneT<T>& rows_done = {});

// The fast path, 4D or 3D model. Same outputs as the reference up to float
// rounding; the backward does not read state.conditionals.
void PreprocessForwardFast(const GaussianModel& model,
                           const ViewParams<float>& view,
                           float time,
                           const RenderOptions& options,
                           FrameState* state);
void PreprocessBackwardFast(const GaussianModel& model,
                            const ViewParams<float>& view,
                            float time,
                            const RenderOptions& options,
                            const FrameState& state,
                            GaussianGradients* grads,
                            const GradientRowsDone& rows_done = {});

// The preprocess of a frame into state->splats (parallel over Gaussians): the fast path where it
// applies, else the reference.
template <typename T>
void PreprocessForward(const GaussianModelT<T>& model,
                       const ViewParams<T>& view,
                       T time,
                       const RenderOptions& options,
                       FrameStateT<T>* state) {
  if constexpr (std::is_same_v<T, float>) {
    if (FastPreprocessApplies(model, options))
      return PreprocessForwardFast(model, view, time, options, state);
  }
  PreprocessForwardReference(model, view, time, options, state);
}

// Backward of the preprocess: from state->splat_grads into `grads`, which must have the model's
// shape (e.g. from ZerosLike). Every Gaussian's rows are overwritten (zeros for a culled one):
// one frame's gradient, not a sum over calls. Deterministic: each Gaussian owns its rows.
// With rows_done, the colour rows may instead go only to rows_done (the fast path keeps them
// in a reused per-thread block, which saves sending ~90% of the gradient to memory and back);
// grads->color_dc and color_rest are then unspecified.
template <typename T>
void PreprocessBackward(const GaussianModelT<T>& model,
                        const ViewParams<T>& view,
                        T time,
                        const RenderOptions& options,
                        const FrameStateT<T>& state,
                        GaussianGradientsT<T>* grads,
                        const GradientRowsDoneT<T>& rows_done = {}) {
  if constexpr (std::is_same_v<T, float>) {
    if (FastPreprocessApplies(model, options))
      return PreprocessBackwardFast(model, view, time, options, state, grads, rows_done);
  }
  PreprocessBackwardReference(model, view, time, options, state, grads, rows_done);
}

}  // namespace hdr4d::method
