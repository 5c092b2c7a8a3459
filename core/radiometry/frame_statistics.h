// What a camera's metering sees of one frame: its log mean luminance and log-luminance
// percentiles, measured on linear radiance (before any exposure).
#pragma once

#include "core/image/image.h"

namespace hdr4d {

// Luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 weights; a 1-channel image is Y
// itself). Logs are of max(Y, kLuminanceFloor), so black pixels do not send the mean to -inf.
inline constexpr double kLuminanceFloor = 1e-6;

struct FrameStatistics {
  double log_mean = 0;  // mean of ln Y over the pixels: ln of the geometric mean luminance
  double log_low = 0;   // ln Y at the low percentile
  double log_high = 0;  // ln Y at the high percentile
};

// hdr: linear, non-empty. Percentiles in [0, 100], low <= high (nearest rank). Throws
// hdr4d::Error for an empty or display-encoded image or bad percentiles.
FrameStatistics MeasureFrame(const Image& hdr, double low_percentile, double high_percentile);

}  // namespace hdr4d
