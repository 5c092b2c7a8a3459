// The HDR-4DGS training loss of one view (ARCHITECTURE §4 "Losses") and its backward:
//   L = L(clamp(LDR_3D), gt)                              LDR supervision, 3D branch
//     + L(TM(log(HDR + 1e-5) + log e), gt)                 LDR supervision, 2D (pixel) branch
//     + 0.6 L(mu(HDR), mu(gt_hdr / max gt_hdr))            HDR supervision, views with HDR GT
// with L = 0.8 L1 + 0.2 (1 - SSIM) (method/train/loss.h) and mu(x) = log(1 + m x) / log(1 + m),
// m = 5000 and the maximum of each image (the reference), or m = 1e6 and one maximum over the
// scene's training views (--hdr-target scene-log, hdr_training_options.h). As in the reference,
// the HDR raster enters mu unnormalised (the target is normalised); evaluation normalises each
// image by its own maximum instead (core/metrics/metrics.h).
//
// The 2D branch's log takes a floor, log(HDR + eps) (PixelLog and its derivative,
// method/render/pixel_log.h): ResolvedHdrTraining::pixel_log_epsilon says which.
//
// The raster holds 3 channels (HDR only) or 6 (HDR, then the 3D branch's LDR), interleaved.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/metrics/metrics.h"

#include "method/render/pixel_log.h"
#include "method/tonemap/tone_mapper.h"
#include "method/train/hdr_training_options.h"

namespace hdr4d::method {

// mu-law of the loss, for x >= 0 (negative x is treated as 0: the HDR raster is a sum of
// non-negative values, so only rounding can make it negative). The constants are worked out once
// (a log per value fewer) and the operations keep their order, so a coder gives the same floats
// as the one-value functions below, bit for bit.
template <typename T>
struct MuLawCoder {
  explicit MuLawCoder(double mu_value) : mu(T(mu_value)), log1p_mu(std::log(T(1) + T(mu_value))) {}
  T Encode(T x) const {
    const T y = x > T(0) ? x : T(0);
    return std::log1p(mu * y) / log1p_mu;
  }
  T EncodeBackward(T x, T dL_dy) const {
    if (!(x > T(0))) return T(0);
    return dL_dy * mu / ((T(1) + mu * x) * log1p_mu);
  }
  T mu;
  T log1p_mu;
};
template <typename T>
inline T MuLawEncode(T x, double mu = kMuLawMu) {
  return MuLawCoder<T>(mu).Encode(x);
}
// Its inverse, for a stored target y in [0, 1]: the value in the loss's units.
template <typename T>
inline T MuLawDecode(T y, double mu = kMuLawMu) {
  return std::expm1(y * std::log1p(T(mu))) / T(mu);
}
template <typename T>
inline T MuLawEncodeBackward(T x, T dL_dy, double mu = kMuLawMu) {
  return MuLawCoder<T>(mu).EncodeBackward(x, dL_dy);
}

struct SupervisionTerms {
  bool ldr_gaussian = true;  // L(clamp(LDR_3D), gt): needs a 6-channel raster
  bool ldr_pixel = true;     // the 2D branch: needs a tone mapper
  bool hdr = true;           // used only for views with HDR ground truth
  float hdr_weight = 0.6f;
  float lambda_dssim = 0.2f;
  double hdr_mu = kMuLawMu;  // the mu of the HDR target's encoding (HdrTargetMu)
  bool hdr_align = false;    // scale the render to the target per view first (HdrTarget::kAligned)
  float pixel_log_epsilon = kReferencePixelLogEpsilon;  // the 2D branch's log(HDR + eps)
  // false (--no-hdr-geometry): the HDR term's gradient reaches the colours only; HdrFrameLoss
  // then also returns the gradient without it, which the blend's geometry takes.
  bool hdr_geometry = true;
};

struct FrameLoss {
  double total = 0, ldr_gaussian = 0, ldr_pixel = 0, hdr = 0;
  double hdr_scale = 1;  // the factor the HDR term applied to the render (1 unless aligned)
  bool geometry_split = false;  // dL_draster_geometry was written (HdrFrameLoss)
};

// Working buffers, reused from view to view. After HdrFrameLoss, `ldr` holds the clamped 3D
// branch (when that term ran) and `pixel_ldr` the 2D branch (when it ran).
struct HdrLossScratch {
  std::vector<float> hdr, ldr, grad, target, x, pixel_ldr, dpixel, dx;
  std::vector<double> ratios;  // HdrAlignScale's sample
};

// --hdr-target aligned: the factor k that brings the HDR render to the target's units, exp of the
// median over values of log(target) - log(render), on a regular sample of at most ~65k values
// where the target is above 1/mu (resolved by the encoding) and the render positive; 1 when none
// is. hdr: H x W x 3 linear render; hdr_mu_gt: its mu-law target; ratios_buffer: working memory
// reused from step to step (a fresh ~1 MB vector each training step would be page-faulted in).
double HdrAlignScale(const std::vector<float>& hdr,
                     const float* hdr_mu_gt,
                     double mu,
                     std::vector<double>* ratios_buffer);

// The HDR term alone: L(mu(scale * hdr), hdr_mu_gt), its weighted gradient added to channels
// 0-2 of dL_draster, the scale held constant (a stop-gradient, as the median's pixel would
// otherwise pull the whole view). Returns the unweighted term.
double AddHdrTerm(const std::vector<float>& hdr,
                  const float* hdr_mu_gt,
                  int width,
                  int height,
                  int channels,
                  const SupervisionTerms& terms,
                  double scale,
                  HdrLossScratch* scratch,
                  float* dL_draster);

// The loss of one view and dL/draster (same layout as `raster`, overwritten). ldr_gt: H x W x 3
// in [0,1] (read only by the LDR terms: may be null without them); hdr_mu_gt: mu(gt_hdr / max gt_hdr), H x W x 3, or null when the view has no HDR
// ground truth. The tone mapper must have begun this view's frame (HdrColorStage does); its
// parameter gradients are added to. With !terms.hdr_geometry, when the HDR term runs and
// dL_draster_geometry is non-null, that buffer (same layout) gets dL/draster of the LDR terms
// alone (the geometry's gradient, BlendBackward) and the result says geometry_split.
FrameLoss HdrFrameLoss(const float* raster,
                       int channels,
                       int width,
                       int height,
                       const float* ldr_gt,
                       const float* hdr_mu_gt,
                       ToneMapper* tone_mapper,
                       const SupervisionTerms& terms,
                       HdrLossScratch* scratch,
                       float* dL_draster,
                       float* dL_draster_geometry = nullptr);

}  // namespace hdr4d::method
