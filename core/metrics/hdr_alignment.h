// HDR metrics that a light saturated in every exposure cannot decide (issue 12 §4).
//
// LDR supervision fixes an HDR prediction up to one global factor, and it cannot say how bright
// a light is that clips in every bracket. The reference's own-maximum mu-law protocol divides the
// prediction by its brightest value, i.e. by exactly that guess. These metrics instead:
//   1. keep the pixels an LDR bracket measures: unclipped and not black in at least one
//      exposure of the view (MeasurableInBrackets), or, without brackets, every pixel; of those,
//      the ones whose true luminance is positive;
//   2. align the prediction to the truth by one robust factor per image,
//        scale = exp(median of (log Y_gt - log Y_pred)),   Y = luminance,
//      the median over the kept pixels where Y_pred is positive too; a kept pixel where the
//      prediction is more than 1000x darker than the darkest kept truth (after the factor),
//      zero included, counts at that floor in the diagnostics of 4: a hole in the model is an
//      error whether it renders black or e^-15, and dropping the black ones flattered a black
//      backdrop;
//   3. score the aligned prediction with the truth's maximum (mu-law, as the HDR-NeRF protocol)
//      and with PU21 (both images times 4000 / the truth's maximum luminance);
//   4. report, as diagnostics of the HDR's shape, the least-squares slope of log Y_pred on
//      log Y_gt over the same pixels (1 for a prediction proportional to the truth, 0.25 for
//      one that is the truth to the power 0.25), their Pearson correlation, and the ratio of
//      their spreads, std(log Y_pred) / std(log Y_gt). slope = corr x contrast: a render whose
//      pixels are misplaced (held-out geometry, blur) has corr < 1, which pulls the slope below
//      1 even when the HDR's shape is right; the contrast ratio is not pulled down by that;
//   5. when the rendered LDR brackets are known, the slope and correlation again over the measured
//      pixels whose LDR the model reproduces in a bracket that measures them
//      (ReproducedInBrackets). There the geometry is right, so what is left is the tone curve's
//      inverse: a squeezed HDR (truth^0.25 behind a right LDR) keeps its slope of 0.25 here,
//      while misplaced pixels, whose LDR is wrong too, drop out.
// Results go under stable keys (AlignedHdrMetrics) into `hdr4d eval` and RUN/results.json.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/metrics/metrics.h"

namespace hdr4d {

// Display values a bracket counts as clipped (>=) or black (<=): half a code of 8 bits from
// the ends, so 254/255 is measured and 255/255 is clipped.
inline constexpr double kBracketClipped = 1.0 - 0.5 / 255.0;
inline constexpr double kBracketBlack = 0.5 / 255.0;

// Per pixel (W x H, row-major; 1 = measurable): at least one of the LDR images of the view (the
// same view at several exposures, display values in [0,1]) has every colour channel below
// kBracketClipped and at least one above kBracketBlack. Throws hdr4d::Error for an empty list or
// images of different sizes.
std::vector<std::uint8_t> MeasurableInBrackets(const std::vector<Image>& brackets);

// When a rendered LDR bracket reproduces the truth's pixel: the truth's brightest colour channel
// is at least kLdrFitLevel (a dim pixel's display value pins its radiance loosely: through a
// gamma-2.2 response, 0.05 of display at 0.05 spans three decades) and every channel of the
// render is within kLdrFitRelative of that brightest value. Through a gamma response that is
// about +-25% of radiance; the floor keeps the tolerance above 8-bit quantisation and the
// datasets' sensor noise (>= 0.015, four codes).
inline constexpr double kLdrFitLevel = 0.15;
inline constexpr double kLdrFitRelative = 0.1;

// Per pixel (W x H; 1 = reproduced): some bracket measures the pixel (as MeasurableInBrackets)
// and its render reproduces it (kLdrFitLevel, kLdrFitRelative). truth[i] and rendered[i] are the
// same bracket. Throws hdr4d::Error for empty or unequal lists and for images of different
// sizes.
std::vector<std::uint8_t> ReproducedInBrackets(const std::vector<Image>& truth,
                                               const std::vector<Image>& rendered);

// Sums of squares and products of log Y_gt (g) and log Y_pred (p) about their means over one
// image's pixels: what AlignHdr's slope (gp / gg) and correlation come from.
struct LogShapeSums {
  double gg = 0, pp = 0, gp = 0;
};

// The slope and correlation of several images pooled within each image (each centred on its
// own means, so each image's scale drops out): sum gp / sum gg and sum gp / sqrt(sum gg sum pp).
// Each image weighs by its spread of log truth, so a view whose measured pixels span a narrow
// range (one bracket, mostly clipped) does not swing the result as it swings a mean of slopes.
// NaN when the truth has no spread.
struct PooledShape {
  double slope = 0.0;
  double corr = 0.0;
};
PooledShape PoolLogShape(const std::vector<LogShapeSums>& images);

struct HdrAlignment {
  double scale = 1.0;  // multiplies the prediction (1 when no pixel qualifies)
  double slope = 0.0;  // NaN when fewer than 2 pixels or log Y_gt is constant
  double corr = 0.0;   // NaN likewise, or when log Y_pred is constant
  double contrast = 0.0;  // std(log Y_pred) / std(log Y_gt); NaN as slope
  std::size_t pixels = 0;
  std::size_t total = 0;  // all pixels of the image
  LogShapeSums sums;
};

// The alignment of `pred` to `gt` (linear HDR, same size; RGB or grey) over the pixels `mask`
// keeps (W x H; null keeps all) whose true luminance is positive (see 1, 2 above). Throws
// hdr4d::Error for mismatched shapes, a mask of the wrong size, or NaN/Inf values.
HdrAlignment AlignHdr(const Image& pred, const Image& gt, const std::vector<std::uint8_t>* mask);

// In this order: "hdr_align_scale", "hdr_log_slope", "hdr_log_corr", "hdr_log_contrast",
// "hdr_measured_fraction" (pixels used / all pixels), "mu_psnr_aligned", "mu_ssim_aligned"
// (prediction times the scale, both divided by the truth's maximum, clamped, mu-law),
// "pu21_psnr_aligned", "pu21_ssim_aligned"; with `with_flip`, then "hdr_flip_aligned"
// (HDR-FLIP of the prediction times the scale: raw HDR-FLIP is not scale-free, and a model
// supervised as the paper does, on each image divided by its own maximum, renders in those
// units; on lego mini its raw HDR-FLIP read 0.81 for every such model, the scale alone).
// Throws as AlignHdr, and hdr4d::Error for an all-black truth.
MetricList AlignedHdrMetrics(const Image& pred,
                             const Image& gt,
                             const std::vector<std::uint8_t>* mask,
                             bool with_flip = false);

// The HDR's shape where the LDR is right (5 above): "hdr_log_slope_ldr_fit" and
// "hdr_log_corr_ldr_fit" (AlignHdr over the pixels `reproduced` keeps), and
// "hdr_ldr_fit_fraction" (those pixels over the ones `measured` keeps; `reproduced` is a subset
// of `measured` when both come from the same brackets). `sums` (optional) receives the sums
// behind the slope, for PoolLogShape over a split: the figure results.json and hdr4d eval's mean
// give for the two shape keys. Throws as AlignHdr.
MetricList LdrFitHdrShape(const Image& pred,
                          const Image& gt,
                          const std::vector<std::uint8_t>& measured,
                          const std::vector<std::uint8_t>& reproduced,
                          LogShapeSums* sums = nullptr);

// Why a key of the lists above is NaN (undefined) for a pair: what hdr4d eval writes under the
// pair's "undefined" object in place of a number.
std::string UndefinedMetricReason(const std::string& key);

// Replaces `mean`'s "hdr_log_slope_ldr_fit" and "hdr_log_corr_ldr_fit" with the pooled
// statistics of `images` (removes them when there are none).
void SetPooledLdrFitShape(const std::vector<LogShapeSums>& images, nlohmann::json* mean);

}  // namespace hdr4d
