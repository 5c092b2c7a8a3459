// Image quality metrics, each defined exactly so that numbers can be reproduced elsewhere
// (ARCHITECTURE §5; the PU21 coefficients and golden values are cited in metrics.cpp and the
// tests).
//
// Shared conventions:
// - Both images must have the same shape (width, height, channels), else hdr4d::Error.
// - Empty images and NaN/Inf values are rejected with hdr4d::Error: a metric of garbage would
//   silently become a null in a results table.
// - Everything is accumulated in double; rows run in parallel, and partial sums are reduced in
//   row order, so results are identical at any thread count.
// - Psnr, PsnrChannelMean, Ssim and SsimMap use every channel they are given. The bundles
//   LdrMetrics / HdrMetrics and the Mu* / Pu21* functions use the first three channels
//   (Image::Rgb(), which drops alpha); a 1-channel image is a grey image (for PU21 its value is
//   the luminance).
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "core/image/image.h"

namespace hdr4d {

// ---- PSNR ------------------------------------------------------------------------------------

// Whole-image PSNR with peak 1: 10 log10(1 / MSE), MSE over all pixels and channels (the 3DGS
// `psnr`). +infinity when the images are identical.
double Psnr(const Image& pred, const Image& gt);

// PSNR of each channel separately (peak 1), then the arithmetic mean over channels. Because a
// channel with MSE 0 has PSNR +inf, the mean is +inf as soon as any one channel is identical.
// Differs from Psnr whenever the channel errors differ (log of a mean vs mean of logs).
double PsnrChannelMean(const Image& pred, const Image& gt);

// Mean squared error over all pixels and channels (what Psnr is built on).
double MeanSquaredError(const Image& pred, const Image& gt);

// ---- SSIM ------------------------------------------------------------------------------------

inline constexpr double kSsimC1 = 0.01 * 0.01;
inline constexpr double kSsimC2 = 0.03 * 0.03;
inline constexpr int kSsimWindow = 11;     // taps of the Gaussian window
inline constexpr double kSsimSigma = 1.5;  // its standard deviation in pixels

// The 1-D Gaussian of the SSIM window, normalised to sum 1 (the training loss uses it too).
std::array<double, kSsimWindow> SsimGaussianKernel();

// SSIM as in the 3DGS reference: an 11x11 Gaussian window (sigma 1.5, the 1-D kernel normalised
// to sum 1, applied separably), "same"-size maps with zero padding (windows at the border count
// the zeros outside the image), each channel on its own, and
//   ssim = ((2 mu_a mu_b + c1)(2 cov_ab + c2)) / ((mu_a^2 + mu_b^2 + c1)(var_a + var_b + c2))
// with var/cov from E[x^2] - mu^2 etc. The result is the mean over all pixels and channels.
// c1 and c2 assume a data range of 1; scale them by range^2 otherwise.
double Ssim(const Image& a, const Image& b, double c1 = kSsimC1, double c2 = kSsimC2);

// The per-pixel, per-channel SSIM map behind Ssim (same shape as the inputs, kLinear). Its mean
// equals Ssim up to float rounding of the stored values.
Image SsimMap(const Image& a, const Image& b, double c1 = kSsimC1, double c2 = kSsimC2);

// ---- HDR: mu-law tone mapping ----------------------------------------------------------------

inline constexpr double kMuLawMu = 5000.0;

// T(x) = log(1 + mu x) / log(1 + mu), per value; inputs are expected in [0,1] (T(0) = 0,
// T(1) = 1). Values below -1/mu have no mu-law value and give NaN; callers clamp first.
Image MuLaw(const Image& x, double mu = kMuLawMu);

// How an HDR prediction and its ground truth are brought to [0,1] before the mu-law.
enum class HdrNormalisation {
  // HDR-4DGS (the reference for this project): prediction / max(prediction), clamped to [0,1];
  // ground truth / max(ground truth). Scale-invariant per image: pred = k * gt scores +inf.
  kOwnMax,
  // HDR-NeRF: both divided by max(ground truth), prediction clamped to [0,1]. A prediction at
  // the wrong absolute level is penalised.
  kGtMax,
};

const char* HdrNormalisationName(HdrNormalisation normalisation);  // "own_max" / "gt_max"

// Mu-law PSNR / SSIM (peak 1, SSIM constants for range 1) on the RGB channels after the chosen
// normalisation. The ground truth is clamped to [0,1] as well: after dividing by a maximum it
// can only leave that range through negative values, which the mu-law cannot take.
// Throws hdr4d::Error when a maximum used for normalising is <= 0 (an all-black HDR image
// cannot be normalised) or when an input holds NaN/Inf.
double MuPsnr(const Image& pred,
              const Image& gt,
              HdrNormalisation normalisation = HdrNormalisation::kOwnMax);
double MuSsim(const Image& pred,
              const Image& gt,
              HdrNormalisation normalisation = HdrNormalisation::kOwnMax);

// ---- HDR: PU21 (Mantiuk & Azimi 2021, `banding_glare` fit) -----------------------------------

inline constexpr double kPu21MinLuminance = 0.005;    // cd/m^2
inline constexpr double kPu21MaxLuminance = 10000.0;  // cd/m^2
// PU value of ~100 cd/m^2, the peak the PU21 metrics use for PSNR and SSIM (not V(10000)).
inline constexpr double kPu21Peak = 256.0;
// Relative HDR renders are scaled so the ground truth's maximum luminance is this many cd/m^2
// (the PU21 README's example display peak); the same factor applies to the prediction.
inline constexpr double kPu21DisplayPeak = 4000.0;

// Perceptually uniform value of an absolute luminance in cd/m^2; the input is clamped to
// [0.005, 10000] first. About 0 at 0.005, 256 at 100 and 595.4 at 10000.
double Pu21Encode(double luminance_cd_m2);
// The inverse of Pu21Encode. Its input is clamped to [Pu21Encode(0.005), Pu21Encode(10000)],
// so the result always lies in [0.005, 10000].
double Pu21Decode(double v);

// Luminance of linear Rec.709/sRGB primaries: 0.212656 R + 0.715158 G + 0.072186 B.
double Luminance(double r, double g, double b);

// The factor PU21 metrics multiply both images by: 4000 / (max luminance of gt). Throws
// hdr4d::Error when that maximum is <= 0.
double Pu21Scale(const Image& gt);

// PU-PSNR: every RGB value times Pu21Scale(gt), PU-encoded, then 10 log10(256^2 / MSE) over all
// pixels and channels. +inf for identical images.
double Pu21Psnr(const Image& pred, const Image& gt);
// PU-SSIM: SSIM (the windowed SSIM above) on the PU-encoded luminance of the scaled images, with
// c1 = (0.01 * 256)^2, c2 = (0.03 * 256)^2.
double Pu21Ssim(const Image& pred, const Image& gt);

// ---- Bundles ---------------------------------------------------------------------------------

using MetricList = std::vector<std::pair<std::string, double>>;

// Display-encoded LDR images in [0,1], on their RGB channels, in this order:
// "psnr", "psnr_channel_mean", "ssim".
MetricList LdrMetrics(const Image& pred, const Image& gt);

// Linear HDR images, in this order: "mu_psnr", "mu_ssim" (kOwnMax), "mu_psnr_gt_max",
// "mu_ssim_gt_max" (kGtMax), "pu21_psnr", "pu21_ssim".
MetricList HdrMetrics(const Image& pred, const Image& gt);

}  // namespace hdr4d
