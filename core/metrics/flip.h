// FLIP, the perceptual difference evaluator of Andersson et al.: LDR-FLIP ("FLIP: A Difference
// Evaluator for Alternating Images", HPG 2020) and HDR-FLIP ("Visualizing Errors in Rendered
// High Dynamic Range Images", Eurographics 2021). It needs no learned weights, so it stands in
// for LPIPS where those cannot be downloaded. Written from the papers and the facts of NVIDIA's
// reference (github.com/NVlabs/flip, checked against its tool at commit 1eb247c; numbers in
// flip_test.cpp); lower is better, 0 for identical images, at most 1.
//
// LDR-FLIP, per pixel, of two linear-RGB images in [0,1]:
// - colour pipeline: both images to YCxCz (the linear opponent space of CIELab: Y = 116 y - 16,
//   Cx = 500 (x - y), Cz = 200 (y - z) of XYZ over the D65 white), each channel blurred by the
//   contrast sensitivity of the eye at `ppd` pixels per degree (a Gaussian for Y and Cx, a sum
//   of two for Cz; clamp-to-edge borders), back to linear RGB clamped to [0,1], to CIELab with
//   the Hunt adjustment (a and b times 0.01 L), then the HyAB distance |dL| + |d(a, b)| raised
//   to 0.7 and mapped to [0,1]: the distance between pure green and pure blue is 1, 40 % of it
//   maps to 0.95;
// - feature pipeline: the luminance (Y + 16) / 116 of both images filtered with the first and
//   second derivatives of a Gaussian of sigma 0.041 degrees (edges and points), the feature
//   difference is sqrt(max(|edge_ref - edge_test|, |point_ref - point_test|) / sqrt 2);
// - FLIP = colour difference ^ (1 - feature difference).
// HDR-FLIP tone maps both images with ACES at a range of exposures chosen from the reference
// (HdrFlipExposureRange) and keeps, per pixel, the largest LDR-FLIP.
//
// Conventions as in metrics.h: same shape else hdr4d::Error, empty or non-finite images are
// rejected, the first three channels are used (one channel is grey). Means are accumulated in
// double in row order. Pixels run in parallel (core/util/parallel.h); results do not depend
// on the thread count.
#pragma once

#include "core/image/image.h"

namespace hdr4d {

// The reference's default viewing setup: a 0.7 m wide, 3840-pixel monitor seen from 0.7 m,
// 3840 * pi / 180 = 67.02 pixels per degree.
inline constexpr double kFlipDefaultPpd = 3840.0 * 3.14159265358979323846 / 180.0;

// ---- LDR-FLIP --------------------------------------------------------------------------------

// The per-pixel LDR-FLIP map (one channel, kLinear, values in [0,1]). Display-encoded images
// (Encoding::kSrgb, as PNGs are read) are decoded to linear first; kLinear images are taken
// as linear values. Both are clamped to [0,1] as the reference does.
Image FlipMap(const Image& pred, const Image& gt, double ppd = kFlipDefaultPpd);

// Mean of FlipMap: the number the reference tool reports as "Mean".
double Flip(const Image& pred, const Image& gt, double ppd = kFlipDefaultPpd);

// ---- HDR-FLIP --------------------------------------------------------------------------------

// The exposures (in stops, applied as 2^e) HDR-FLIP evaluates, from the reference (ground
// truth) alone, as the HDR-FLIP paper specifies: with x_85 the linear value that ACES maps to
// 0.85, the range runs from log2(x_85 / Ymax) (the brightest pixel just below the shoulder) to
// log2(x_85 / Ymedian) (the median pixel there), in max(2, ceil(stop - start)) equal steps; Y
// is the Rec. 709 luminance. Where the median luminance is <= 0 (more than half of the image
// black, where the reference has no defined range) the median of the positive luminances is
// used. Throws hdr4d::Error when no pixel has positive luminance.
struct HdrFlipExposures {
  double start = 0.0;
  double stop = 0.0;
  int count = 0;
};
HdrFlipExposures HdrFlipExposureRange(const Image& gt);

// The per-pixel HDR-FLIP map (one channel, kLinear, in [0,1]) of linear HDR images: at each
// exposure e, both images times 2^e, ACES-tone-mapped (the reference's fit with its 0.6
// pre-exposure folded in), clamped to [0,1] and compared with LDR-FLIP as linear RGB; the
// maximum over the exposures.
Image HdrFlipMap(const Image& pred, const Image& gt, double ppd = kFlipDefaultPpd);

// Mean of HdrFlipMap.
double HdrFlip(const Image& pred, const Image& gt, double ppd = kFlipDefaultPpd);

// ---- Showing the error -----------------------------------------------------------------------

// Arithmetic mean of a one-channel map (double, row order).
double FlipMean(const Image& map);

// A FLIP map coloured with the magma colour map as the reference tool writes it (256 entries,
// value v at index round(255 v)): a 3-channel display-encoded (kSrgb) image.
Image FlipMagma(const Image& map);

}  // namespace hdr4d
