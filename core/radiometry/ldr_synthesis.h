// LDR images from HDR radiance through exposure, sensor noise, a camera response and
// quantisation (the datagen path), their inverse, and the merge of a bracketed LDR stack with
// a known response back into HDR.
//
// Channels: every channel is a colour channel, except that the 4th channel of a 4-channel
// image is alpha (as in hdr4d::ToSrgb): it gets no exposure, noise or response, only the clamp
// to [0,1] and the quantisation, and LinearizeLdr / MergeExposures pass it through.
#pragma once

#include <cstdint>
#include <vector>

#include "core/radiometry/crf.h"
#include "core/image/image.h"

namespace hdr4d {

// A simple physically motivated sensor, in units of the exposure x = radiance * exposure time
// (x = 1 is full scale). Noise is drawn per value from a counter-based generator keyed by
// (seed, value index), so results are identical at any thread count.
struct SensorNoise {
  // Photo-electrons at x = 1; 0 disables shot noise. The electron count is Poisson with mean
  // x * full_well: sampled exactly (by inversion) for means <= 20 electrons and by the Gaussian
  // approximation N(mean, mean) above, where its error is negligible.
  double full_well = 0;
  // Read noise standard deviation in units of x, added after shot noise.
  double read_sigma = 0;
  std::uint64_t seed = 0;
};

struct LdrSynthesisOptions {
  double exposure = 1.0;  // seconds, > 0 and finite
  SensorNoise noise;
  int bits = 8;  // quantisation: 8 or 16; 0 = no quantisation (float output)
  // Throws hdr4d::Error for a zero, negative or non-finite exposure, bits not in {0, 8, 16},
  // or a negative or non-finite noise parameter.
  void Validate() const;
};

// hdr: linear radiance (Encoding::kLinear, >= 1 channel, finite, >= 0; anything else throws
// hdr4d::Error naming the pixel). Per value:
//   x = radiance * exposure, + shot and read noise, -> clamp to >= 0 -> y = crf.Apply(x)
//   -> clamp to [0,1] -> round to the nearest k / (2^bits - 1).
// Returns display values tagged Encoding::kSrgb ("display-encoded", whatever the CRF is).
Image SynthesizeLdr(const Image& hdr, const Crf& crf, const LdrSynthesisOptions& options);

// The inverse for an invertible CRF: x = crf.Inverse(y), radiance = x / exposure
// (Encoding::kLinear). A clipped value (y = 1) maps to the saturation radiance
// crf.Saturation() / exposure, a lower bound of the truth; y = 0 maps to 0. Throws
// hdr4d::Error for a linear-tagged input (probably linearised already), values outside [0,1],
// a bad exposure, or a non-invertible CRF.
Image LinearizeLdr(const Image& ldr, const Crf& crf, double exposure);

// Merges a bracketed stack (same shape, display-encoded, exposure times in seconds) into
// linear radiance with a known, invertible CRF, in the manner of Debevec & Malik: per value,
//   ln E = sum_j w(y_j) ln(crf.Inverse(y_j) / t_j) / sum_j w(y_j),
// a weighted mean of the per-exposure log-radiance estimates with the hat weight
// w(y) = min(y, 1 - y) on the display value, so clipped (y = 1) and black (y = 0) values do not
// vote and mid-range values, furthest from both clip points, count most. When no exposure
// votes: if any is clipped, the shortest exposure's estimate (the saturation radiance, a lower
// bound); otherwise (all black) the longest exposure's. Alpha is the mean over the stack.
// Throws hdr4d::Error naming the image index for mismatched shapes, counts or bad values.
Image MergeExposures(const std::vector<Image>& ldr_stack,
                     const std::vector<double>& exposures,
                     const Crf& crf);

}  // namespace hdr4d
