// The state one frame's render keeps between its forward and backward, and the options and
// hooks the renderer takes (ARCHITECTURE §4, "One training step").
#pragma once

#include <cstdint>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/gaussian/gradient_rows.h"  // GradientRowsDone, the backward's callback
#include "method/gaussian/projection.h"
#include "method/gaussian/rotation4d.h"
#include "method/raster/splats.h"

namespace hdr4d::method {

// An optional stage between each visible Gaussian's colour (model.channels values: the SH x time
// value + 0.5, the log-HDR colour in ColorMode::kLogHdr) and the features the rasteriser blends.
// HDR-4DGS's 3D branch is one: [exp(c), tone-mapped c], six channels in one pass (ARCHITECTURE §4).
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

// An optional learned background (method/render/learned_background.h): the values blended behind
// the Gaussians (image = colour + T background), made per frame after the colour stage (whose
// frame, e.g. the tone mapper's, it may use) and given dL/dbackground by the backward.
class BackgroundSource {
 public:
  virtual ~BackgroundSource() = default;
  // Writes `channels` values (the rasteriser's feature channels).
  virtual void Forward(int channels, std::vector<float>* background) = 0;
  // dL_dbackground: `channels` values; adds to the source's own gradient.
  virtual void Backward(int channels, const float* dL_dbackground) = 0;
};

struct RenderOptions {
  int sh_degree = 3;              // active spatial SH degree (grows during training)
  int time_degree = 2;            // active temporal degree (0 in 3D mode)
  float time_duration = 1.0f;     // T of the cosine time basis
  std::vector<float> background;  // one value per channel (empty: zeros)
  RasterBackend backend = RasterBackend::kSimd;
  ColorStage* color_stage = nullptr;  // null: the colours are the features
  BackgroundSource* background_source = nullptr;  // set: replaces `background` (float path only)
  // false for a render no backward follows (ViewRenderer): binning and blend then keep
  // nothing for one (RasterSettings::keep_records); RenderBackward of such a frame is a bug.
  bool backward_follows = true;
  // --prune-contribution (issue 55): the backward also keeps, per Gaussian, the largest blending
  // weight alpha T it had at any pixel of the frame, in splat_grads.max_weight (SplatGradientsT).
  bool track_max_weight = false;
  // --prune-radiance-share: with track_max_weight, the frame's forward image (H x W x the raster's
  // channels; its first three the HDR radiance), RasterSettings::share_image. Null: weights only.
  const float* share_image = nullptr;
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
  // Reference preprocess only (N, valid where splats.radius > 0); empty on the fast path.
  std::vector<ConditionalGaussian<T>> conditionals;
  // N: the reference's 3-sigma screen radius (0 = culled), what densification statistics use;
  // splats.radius is the tighter radius the tiles are binned with (preprocess_common.h).
  std::vector<int> screen_radius;
  std::size_t num_visible = 0;  // Gaussians with radius > 0 after the preprocess
  // With a colour stage only: the colours before it, their gradients, the visible rows.
  std::vector<T> colors, color_grads;
  std::vector<std::uint32_t> visible;
  // With a background source only: the background the forward blended and its gradient.
  std::vector<float> background, background_grad;
  // Reference (scalar, any T) path only: the forward's outputs the backward needs.
  std::vector<T> final_T;
  std::vector<std::int32_t> n_contrib;

  // Capacity for n Gaussians in the buffers sized per Gaussian, for a model of `channels` colour
  // channels blended as `features` channels (more with a colour stage, which also keeps the
  // colours). A buffer that grows past its capacity holds its old and new contents at once, so
  // the trainer reserves its Gaussian budget; capacity never written costs address space, not
  // memory. (The buffers sized per tile entry follow the views' overlaps and are not reserved.)
  void ReserveGaussians(std::size_t n, int channels, int features) {
    const std::size_t c = static_cast<std::size_t>(channels);
    const std::size_t f = static_cast<std::size_t>(features);
    for (auto* v : {&splats.mean2d, &splat_grads.mean2d}) v->reserve(2 * n);
    for (auto* v : {&splats.conic, &splat_grads.conic}) v->reserve(3 * n);
    for (auto* v : {&splats.opacity, &splats.depth, &splat_grads.opacity}) v->reserve(n);
    for (auto* v : {&splats.features, &splat_grads.features}) v->reserve(f * n);
    splats.radius.reserve(n);
    screen_radius.reserve(n);
    clamped.reserve(c * n);
    if (f != c) {
      for (auto* v : {&colors, &color_grads}) v->reserve(c * n);
      visible.reserve(n);
    }
    for (auto* v : {&raster.rects, &raster.sorted_rects}) v->reserve(4 * n);
    for (auto* v : {&raster.depth_order, &raster.entry_ranges}) v->reserve(n + 1);
    for (auto* v : {&raster.sort_keys, &raster.sort_keys_tmp}) v->reserve(n);
    raster.sort_ids_tmp.reserve(n);
  }
};
using FrameState = FrameStateT<float>;

}  // namespace hdr4d::method
