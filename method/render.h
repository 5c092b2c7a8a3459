// One frame of 4D Gaussian Splatting, forward and backward (DESIGN §4, §6): the preprocess per
// Gaussian (4D rotation and covariance, slice at time t, temporal cull, EWA projection,
// opacity x marginal, SH x time colour) and the tile rasteriser (method/raster/), and back.
//
// What costs nothing: a Gaussian whose marginal p(t) <= 0.05, one behind the near plane or
// outside the image gets radius 0 in the preprocess and is never binned, blended or
// back-propagated; an empty tile is never blended.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/camera.h"
#include "method/gaussian_model.h"
#include "method/projection.h"
#include "method/raster/splats.h"
#include "method/rotation4d.h"

namespace hdr4d::method {

// An optional stage between each visible Gaussian's colour (model.channels values: the SH x time
// value + 0.5, the log-HDR colour in ColorMode::kLogHdr) and the features the rasteriser blends.
// HDR-4DGS's 3D branch is one: [exp(c), tone-mapped c], six channels in one pass (DESIGN §4).
// Float production path only (RenderForward / RenderBackward).
class ColorStage {
 public:
  virtual ~ColorStage() = default;
  virtual int feature_channels() const = 0;
  // colors: N x color_channels, valid in the rows listed in `visible` (ascending). Writes those
  // rows of `features` (N x feature_channels).
  virtual void Forward(const float* colors,
                       int color_channels,
                       const std::vector<std::uint32_t>& visible,
                       float* features) = 0;
  // From the rows `visible` of dL_dfeatures to the same rows of dL_dcolors (overwritten).
  virtual void Backward(const float* colors,
                        int color_channels,
                        const std::vector<std::uint32_t>& visible,
                        const float* dL_dfeatures,
                        float* dL_dcolors) = 0;
};

struct RenderOptions {
  int sh_degree = 3;              // active spatial SH degree (grows during training)
  int time_degree = 2;            // active temporal degree (0 in 3D mode)
  float time_duration = 1.0f;     // T of the cosine time basis
  std::vector<float> background;  // one value per channel (empty: zeros)
  RasterBackend backend = RasterBackend::kSimd;
  ColorStage* color_stage = nullptr;  // null: the colours are the features
};

// The 3D Gaussian a 4D one (or a 3D one in static mode) presents at the frame's time, with the
// intermediate matrices the backward needs (kept by the forward instead of recomputed).
template <typename T>
struct ConditionalGaussian {
  Vec3<T> mean;
  Mat3<T> cov;
  T marginal = T(1);
  Mat4<T> rotation4, sigma4;  // 4D mode
  Mat3<T> rotation3;          // 3D mode
};

// Buffers of one frame, reused from frame to frame (they only grow).
template <typename T>
struct FrameStateT {
  SplatBuffersT<T> splats;
  SplatGradientsT<T> splat_grads;
  RasterState raster;
  std::vector<std::uint8_t> clamped;  // N x channels: LDR colour clamped at 0 (no gradient)
  std::vector<ConditionalGaussian<T>> conditionals;  // N: valid where splats.radius > 0
  // N: the reference's 3-sigma screen radius (0 = culled), what densification statistics use;
  // splats.radius is the tighter radius the tiles are binned with (see render.cpp).
  std::vector<int> screen_radius;
  std::size_t num_visible = 0;  // Gaussians with radius > 0 after the preprocess
  // With a colour stage only: the colours before it, their gradients, the visible rows.
  std::vector<T> colors, color_grads;
  std::vector<std::uint32_t> visible;
  // Reference (scalar, any T) path only: the forward's outputs the backward needs.
  std::vector<T> final_T;
  std::vector<std::int32_t> n_contrib;
};
using FrameState = FrameStateT<float>;

// Per-Gaussian preprocess into state->splats (parallel over Gaussians).
template <typename T>
void PreprocessForward(const GaussianModelT<T>& model,
                       const ViewParams<T>& view,
                       T time,
                       const RenderOptions& options,
                       FrameStateT<T>* state);

// The colour gradient rows of a block of Gaussians [begin, end): colour_dc and colour_rest of
// Gaussian begin + r at color_dc + r * channels and color_rest + r * rest_stride.
template <typename T>
struct GradientRowsT {
  const T* color_dc;
  const T* color_rest;
};
using GradientRows = GradientRowsT<float>;

// Called with Gaussian ranges [begin, end) whose gradient rows are final, from worker threads,
// each Gaussian exactly once per backward: the trainer's optimiser step runs here, on rows still
// in cache (AdamRowStep). The colour rows are passed (see PreprocessBackward); the other rows
// are in `grads`.
template <typename T>
using GradientRowsDoneT =
    std::function<void(std::int64_t begin, std::int64_t end, const GradientRowsT<T>& colour)>;
using GradientRowsDone = GradientRowsDoneT<float>;

// Backward of the preprocess: from state->splat_grads into `grads`, which must have the model's
// shape (e.g. from ZerosLike). Every Gaussian's rows are overwritten (zeros for a culled one):
// one frame's gradient, not a sum over calls. Deterministic: each Gaussian owns its rows.
// With rows_done, the colour rows may instead go only to rows_done (the fast 4D path keeps them
// in a reused per-thread block, which saves sending ~90% of the gradient to memory and back);
// grads->color_dc and color_rest are then unspecified.
template <typename T>
void PreprocessBackward(const GaussianModelT<T>& model,
                        const ViewParams<T>& view,
                        T time,
                        const RenderOptions& options,
                        const FrameStateT<T>& state,
                        GaussianGradientsT<T>* grads,
                        const GradientRowsDoneT<T>& rows_done = {});

// The production path (float; SIMD or scalar blending by options.backend). image: H x W x
// channels, interleaved.
void RenderForward(const GaussianModel& model,
                   const Camera& camera,
                   float time,
                   const RenderOptions& options,
                   FrameState* state,
                   float* image);
// dL_dimage: H x W x channels. Overwrites `grads` (see PreprocessBackward).
void RenderBackward(const GaussianModel& model,
                    const Camera& camera,
                    float time,
                    const RenderOptions& options,
                    FrameState* state,
                    const float* dL_dimage,
                    GaussianGradients* grads,
                    const GradientRowsDone& rows_done = {});

// The same in any floating type with the scalar reference blend (float and double are
// instantiated): what the whole-render finite-difference test runs in double.
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
