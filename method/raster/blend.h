// Front-to-back alpha blending of binned splats and its hand-written backward: the second half of
// the 3DGS / 4DGS tile rasteriser (ARCHITECTURE §4, §6), on the CPU, for any number of channels.
//
// Forward, per pixel with centre p, over its tile's list in depth order (binning.h):
//   d = mean2d - p;  power = -0.5 (a dx^2 + c dy^2) - b dx dy;  skip if power > 0;
//   alpha = min(kMaxAlpha, opacity exp(power));  skip if alpha < kMinAlpha;
//   test_T = T (1 - alpha);  if test_T < kMinTransmittance the pixel is done and this Gaussian
//   does NOT contribute;  colour += feature alpha T;  T = test_T.
//   image = colour + T background;  final_T = T;  n_contrib = 1 + list position of the last
//   contributor.
// Backward (the 3DGS backward): per pixel from n_contrib back to front, T is recovered by dividing
// out (1 - alpha), and with "behind" = the colour blended behind the current Gaussian (normalised
// by its transmittance),
//   dL/dalpha = T sum_c (f_c - behind_c) dL/dimage_c - T_final / (1 - alpha) g_T,
//   g_T = sum_c background_c dL/dimage_c + dL/dfinal_T   (the second term when given),
// then dL/dopacity = G dL/dalpha, dL/dG = opacity dL/dalpha, and the chain rule through power.
// As in the reference, the clamp alpha = min(kMaxAlpha, .) is NOT differentiated: a clamped
// alpha passes gradient as if unclamped (the true derivative would be 0). Tile binning is
// piecewise constant and has no gradient.
//
// Determinism: tiles run in parallel; each (tile, Gaussian) entry owns a gradient slot, and after
// all tiles every Gaussian sums its slots in ascending tile order (RasterState::entry_ranges),
// and dL/dbackground sums per-tile partials in tile order. Results are bit-identical at any
// thread count (not across backends or CPU targets).
//
// Backends (RasterSettings::backend):
// - kScalar: per-pixel loops in the order of the CUDA kernels, std::exp. The templated
//   BlendForwardReference / BlendBackwardReference below are this path; in double they are the
//   finite-difference reference.
// - kSimd (blend_simd.cpp): a tile's 256 pixels as Highway vectors (AVX-512 here: one tile row per
//   vector), dispatched at run time. Forward: per pixel vector, the Gaussians whose reach box
//   covers its row, accumulators in registers, leaving as soon as every lane is done. Backward:
//   for each Gaussian (back to front) the pixel vectors it reaches, per-pixel state in L1,
//   gradients summed over the tile in registers. The forward packs per-Gaussian records into the
//   state; the backward reuses them (so it must get the same splats, as it must anyway). With
//   RasterSettings::keep_records false (a render no backward follows) the forward reads the
//   per-Gaussian records in place instead of copying them per tile entry into the state, keeps
//   no n_contrib, and binning leaves out the backward's entry slots.
//   Differences from kScalar: the kernels take alpha = 2^(power + log2 opacity), the power in
//   log2 units (FastExp2 below, relative error <= 3e-7; the sum's rounding adds up to ~1e-6
//   where opacity is small), fused multiply-adds (T - alpha T for T (1 - alpha)), 1/(1 - alpha)
//   multiplied instead of divided, and the behind colour updated eagerly (same expression),
//   folded into one value per pixel in the SIMD backward; images and gradients agree within 1e-5
//   of each field's largest value (blend_test.cpp, on every compiled target). A pixel whose alpha
//   or test_T lies within ~1e-6 relative of kMinAlpha / kMinTransmittance may take the other branch
//   (about 1 pixel in 10^4 on dense random scenes).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "method/raster/splats.h"

namespace hdr4d::method {

// Blends binned splats (BinSplats must have run on the same splats and image size): writes
// `image` (H x W x channels) and state->final_transmittance / n_contrib.
void BlendForward(const SplatBuffers& splats,
                  const RasterSettings& settings,
                  RasterState* state,
                  float* image);

// BinSplats followed by BlendForward.
void RasterizeForward(const SplatBuffers& splats,
                      const RasterSettings& settings,
                      RasterState* state,
                      float* image);

// Backward of BlendForward (same splats, settings and state). dL_dimage: H x W x channels.
// dL_dfinal_T: H x W or nullptr (no loss on the transmittance map). Accumulates into `grads`
// (empty buffers are first sized and zeroed) and, when non-null, into dL_dbackground[channels].
// Uses the state's scratch, hence the non-const state.
//
// dL_dimage_geometry (H x W x channels, nullable): when given, dL/dalpha, and with it the
// gradients of the means, conics and opacities, is computed from this image instead of
// dL_dimage, while the features and the background still take dL_dimage. That is the backward of
// a loss some of whose terms reach the colours only (a stop-gradient on alpha for them): the HDR
// term under --no-hdr-geometry (method/train/hdr_training_options.h). Null: dL_dimage for both.
void BlendBackward(const SplatBuffers& splats,
                   const RasterSettings& settings,
                   RasterState* state,
                   const float* dL_dimage,
                   const float* dL_dfinal_T,
                   SplatGradients* grads,
                   float* dL_dbackground,
                   const float* dL_dimage_geometry = nullptr);

// A Gaussian's share of a pixel (RasterSettings::share_image) over its blending weight w = alpha
// T: 1, or the largest f_c / C_c over the first kShareChannels channels (the HDR radiance of
// HDR-4DGS's raster) where its colour f_c is a larger part of the pixel's value C_c than w says
// (w f_c / C_c is then its part of C_c). A log-space HDR loss weighs that part, not w: a faint
// Gaussian that is a light or a highlight, or one in a dark region
// (docs/history/time-to-quality.md, "Pruning by radiance share").
// C_c is floored at 0 and kShareFloor added, so the scale stays finite.
inline constexpr int kShareChannels = 3;
inline constexpr float kShareFloor = 1e-8f;
template <typename T>
inline T ShareInverse(T pixel_value) {
  return T(1) / ((pixel_value > T(0) ? pixel_value : T(0)) + T(kShareFloor));
}
template <typename T>
inline T ShareScale(const T* features, const T* pixel) {
  T scale = T(1);
  for (int c = 0; c < kShareChannels; ++c)
    scale = std::max(scale, features[c] * ShareInverse(pixel[c]));
  return scale;
}

// The scalar reference in any floating type (float and double are instantiated). `bins` needs
// only its binning part. background: `channels` values or nullptr (zeros). Writes image
// (H x W x C), final_T (H x W) and n_contrib (H x W).
template <typename T>
void BlendForwardReference(const SplatBuffersT<T>& splats,
                           const RasterState& bins,
                           const T* background,
                           T* image,
                           T* final_T,
                           std::int32_t* n_contrib);

// Its backward, with the forward's final_T and n_contrib; arguments as in BlendBackward.
template <typename T>
void BlendBackwardReference(const SplatBuffersT<T>& splats,
                            const RasterState& bins,
                            const T* background,
                            const T* final_T,
                            const std::int32_t* n_contrib,
                            const T* dL_dimage,
                            const T* dL_dfinal_T,
                            SplatGradientsT<T>* grads,
                            T* dL_dbackground,
                            const T* dL_dimage_geometry = nullptr,
                            const T* share_image = nullptr);

// The 2^x of the blend kernels (alpha = opacity 2^power, the power in log2 units), exposed so
// tests can bound its error: x clamped to [-125.5, 0], relative error <= 3e-7. x = n + r with
// |r| <= 1/2, a degree-5 minimax polynomial in r, 2^n in the exponent bits.
void FastExp2(const float* x, float* out, std::size_t n);

namespace detail {

// Gradient slot layout per entry: mean x, mean y, conic a, b, c, opacity, then the features.
inline constexpr int kSlotMean = 0;
inline constexpr int kSlotConic = 2;
inline constexpr int kSlotOpacity = 5;
inline constexpr int kSlotFeatures = 6;
inline int SlotStride(int channels) { return kSlotFeatures + channels; }

// Everything one tile's kernel reads and writes (the SIMD kernels live in blend_simd.cpp).
struct TileJob {
  const float* mean2d = nullptr;
  const float* conic = nullptr;
  const float* opacity = nullptr;
  const float* features = nullptr;
  int channels = 0;
  const float* background = nullptr;  // channels values (zeros when the settings have none)
  const std::int32_t* tile_ranges = nullptr;
  const std::int32_t* point_list = nullptr;
  int width = 0, height = 0, tiles_x = 0;
  // Forward outputs; backward inputs (final_T, n_contrib).
  float* image = nullptr;
  float* final_T = nullptr;
  std::int32_t* n_contrib = nullptr;
  // Backward.
  const float* dL_dimage = nullptr;
  const float* dL_dfinal_T = nullptr;         // nullable
  const float* dL_dimage_geometry = nullptr;  // nullable: dL/dalpha from dL_dimage
  float* entry_gradients = nullptr;           // SlotStride(channels) per entry
  const std::int32_t* entry_slots = nullptr;  // where each entry's slot goes (RasterState)
  float* tile_background_grad = nullptr;      // channels per tile; nullable
  float* entry_max_weight = nullptr;  // nullable: per entry (at its slot) the largest alpha T
  const float* share_image = nullptr;  // nullable: RasterSettings::share_image
  // Per-Gaussian records of the SIMD kernels (PackedStride(channels) floats per Gaussian),
  // written by PackSplatsSimd for the Gaussians listed in some tile (a non-empty rectangle in
  // rects, RasterState::rects).
  float* packed = nullptr;
  const std::int32_t* rects = nullptr;
  // Per-entry records (TileRecordStride(channels) per point_list entry: the per-Gaussian record
  // with its reach turned into tile rows/columns packed in one slot): written by the forward,
  // read by the backward when non-null and tile_records_ready (else the backward gathers its
  // own). They are the largest per-entry buffer, hence the compact form.
  float* tile_records = nullptr;
  bool tile_records_ready = false;
};
// Per Gaussian: 7 scalar fields, the features, then the reach box as 4 floats (absolute pixel
// indices); per tile entry: the same 7 fields and features, then the box in one 4-byte slot.
inline constexpr int kRecordScalars = 7;
inline int PackedStride(int channels) { return kRecordScalars + channels + 4; }
inline int TileRecordStride(int channels) { return kRecordScalars + channels + 1; }
// Packs the records of the listed Gaussians among ids [begin .. end).
void PackSplatsSimd(const TileJob& job, std::int64_t begin, std::int64_t end);
void ForwardTileSimd(const TileJob& job, int tile);
void BackwardTileSimd(const TileJob& job, int tile);

}  // namespace detail
}  // namespace hdr4d::method
