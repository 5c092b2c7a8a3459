// One frame of 4D Gaussian Splatting, forward and backward (ARCHITECTURE §4, §6): the preprocess
// per Gaussian (4D rotation and covariance, slice at time t, temporal cull, EWA projection, opacity
// x marginal, SH x time colour) and the tile rasteriser (method/raster/), and back.
//
// What costs nothing: a Gaussian whose marginal p(t) <= 0.05, one behind the near plane or
// outside the image gets radius 0 in the preprocess and is never binned, blended or
// back-propagated; an empty tile is never blended.
#pragma once

#include "core/geometry/camera.h"
#include "method/render/frame_state.h"
#include "method/render/preprocess.h"

namespace hdr4d::method {

// The production path (float; SIMD or scalar blending by options.backend). image: H x W x
// channels, interleaved.
void RenderForward(const GaussianModel& model,
                   const Camera& camera,
                   float time,
                   const RenderOptions& options,
                   FrameState* state,
                   float* image);
// dL_dimage: H x W x channels. Overwrites `grads` (see PreprocessBackward). dL_dimage_geometry:
// nullable, the image the geometry's gradients take instead (BlendBackward). grads null: the
// model's gradients are not wanted, only what the colour stage and the background source take
// from the blend (the HDR head's offsets), so the preprocess backward is skipped.
void RenderBackward(const GaussianModel& model,
                    const Camera& camera,
                    float time,
                    const RenderOptions& options,
                    FrameState* state,
                    const float* dL_dimage,
                    GaussianGradients* grads,
                    const GradientRowsDone& rows_done = {},
                    const float* dL_dimage_geometry = nullptr);

// The same in any floating type with the reference preprocess and the scalar reference blend
// (float and double are instantiated): what the whole-render finite-difference test runs in
// double, and what the fast path is tested against.
template <typename T>
void RenderForwardReference(const GaussianModelT<T>& model,
                            const Camera& camera,
                            T time,
                            const RenderOptions& options,
                            FrameStateT<T>* state,
                            T* image);
template <typename T>
void RenderBackwardReference(const GaussianModelT<T>& model,
                             const Camera& camera,
                             T time,
                             const RenderOptions& options,
                             FrameStateT<T>* state,
                             const T* dL_dimage,
                             GaussianGradientsT<T>* grads);

}  // namespace hdr4d::method
