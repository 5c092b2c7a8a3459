#include "datagen/dynamic_range.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace hdr4d::datagen {

namespace {

constexpr int kNumBins = (LuminanceHistogram::kMaxStop - LuminanceHistogram::kMinStop) *
                         LuminanceHistogram::kBinsPerStop;

int BinOf(double luminance) {
  const double position =
      (std::log2(luminance) - LuminanceHistogram::kMinStop) * LuminanceHistogram::kBinsPerStop;
  return static_cast<int>(std::clamp(std::floor(position), 0.0, kNumBins - 1.0));
}

}  // namespace

LuminanceHistogram::LuminanceHistogram() : bins_(kNumBins, 0) {}

void LuminanceHistogram::Add(const Image& image) {
  HDR4D_CHECK(image.channels() >= 3);
  const float* p = image.data();
  for (std::size_t i = 0; i < image.num_pixels(); ++i, p += image.channels()) {
    const double y = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    HDR4D_CHECK(std::isfinite(y));
    if (y <= 0) {
      ++zeros_;
      continue;
    }
    ++bins_[BinOf(y)];
    min_positive_ = positive_ == 0 ? y : std::min(min_positive_, y);
    max_ = std::max(max_, y);
    ++positive_;
  }
}

void LuminanceHistogram::Merge(const LuminanceHistogram& other) {
  for (int i = 0; i < kNumBins; ++i) bins_[i] += other.bins_[i];
  if (other.positive_ > 0) {
    min_positive_ =
        positive_ == 0 ? other.min_positive_ : std::min(min_positive_, other.min_positive_);
    max_ = std::max(max_, other.max_);
  }
  positive_ += other.positive_;
  zeros_ += other.zeros_;
}

double LuminanceHistogram::Percentile(double q) const {
  HDR4D_CHECK(q >= 0 && q <= 1);
  if (positive_ == 0) return 0;
  const double target = q * static_cast<double>(positive_);
  double below = 0;
  for (int i = 0; i < kNumBins; ++i) {
    if (bins_[i] == 0) continue;
    if (below + bins_[i] >= target) {
      const double fraction = std::clamp((target - below) / bins_[i], 0.0, 1.0);
      const double stop = kMinStop + (i + fraction) / kBinsPerStop;
      // The end bins and the extremes are known exactly: never report beyond them.
      return std::clamp(std::exp2(stop), min_positive_, max_);
    }
    below += bins_[i];
  }
  return max_;
}

DynamicRange LuminanceHistogram::Summary() const {
  DynamicRange r;
  r.pixels = positive_ + zeros_;
  r.zero_fraction = r.pixels == 0 ? 0 : static_cast<double>(zeros_) / r.pixels;
  r.min_positive = min_positive_;
  r.max = max_;
  r.p001 = Percentile(0.001);
  r.p999 = Percentile(0.999);
  r.ratio = r.p001 > 0 ? r.p999 / r.p001 : 0;
  return r;
}

}  // namespace hdr4d::datagen
