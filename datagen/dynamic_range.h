// The dynamic range of a set of HDR frames: percentiles of linear luminance (Rec. 709 weights,
// Blender's scene-linear primaries) from a histogram in log2 luminance, so any number of frames
// is summarised in fixed memory. The figure of merit is p99.9 / p0.1.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image/image.h"

namespace hdr4d::datagen {

struct DynamicRange {
  double p001 = 0;   // 0.1th percentile of the positive luminances
  double p999 = 0;   // 99.9th percentile
  double ratio = 0;  // p999 / p001 (0 when there is no positive pixel)
  double min_positive = 0, max = 0;
  double zero_fraction = 0;  // pixels with luminance <= 0 (left out of the percentiles)
  std::int64_t pixels = 0;
};

class LuminanceHistogram {
 public:
  // Bins of 1/64 stop from 2^-64 to 2^64: a percentile is exact to within 1.1 %; luminances
  // beyond the range are clamped into the end bins (min/max stay exact).
  static constexpr int kBinsPerStop = 64;
  static constexpr int kMinStop = -64, kMaxStop = 64;

  LuminanceHistogram();
  // Adds every pixel of a linear image with >= 3 channels (checked); non-finite values abort.
  void Add(const Image& image);
  void Merge(const LuminanceHistogram& other);
  // q in [0, 1] over the positive luminances, interpolated in log space within a bin; 0 when
  // there is none.
  double Percentile(double q) const;
  DynamicRange Summary() const;

 private:
  std::vector<std::int64_t> bins_;
  std::int64_t positive_ = 0, zeros_ = 0;
  double min_positive_ = 0, max_ = 0;
};

}  // namespace hdr4d::datagen
