#include "core/radiometry/frame_statistics.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/util/error.h"

namespace hdr4d {

FrameStatistics MeasureFrame(const Image& hdr, double low_percentile, double high_percentile) {
  if (hdr.empty()) Fail("frame statistics: the image is empty ({})", hdr.ShapeString());
  if (hdr.encoding() != Encoding::kLinear)
    Fail("frame statistics: expected linear radiance, got a display-encoded image ({})",
         hdr.ShapeString());
  if (!(low_percentile >= 0 && low_percentile <= high_percentile && high_percentile <= 100))
    Fail("frame statistics: percentiles {} and {} must satisfy 0 <= low <= high <= 100",
         low_percentile, high_percentile);
  const int channels = hdr.channels();
  const float* v = hdr.data();
  std::vector<double> logs(hdr.num_pixels());
  double sum = 0;
  for (std::size_t p = 0; p < logs.size(); ++p) {
    const float* px = v + p * channels;
    const double y = channels >= 3 ? 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2] : px[0];
    // NaN or negative radiance counts as black here; SynthesizeLdr rejects it with its pixel.
    logs[p] = std::log(std::isfinite(y) ? std::max(y, kLuminanceFloor) : kLuminanceFloor);
    sum += logs[p];
  }
  FrameStatistics stats;
  stats.log_mean = sum / static_cast<double>(logs.size());
  const auto rank = [&](double percentile) {
    const auto k = static_cast<std::size_t>(
        std::llround(percentile / 100.0 * static_cast<double>(logs.size() - 1)));
    std::nth_element(logs.begin(), logs.begin() + static_cast<std::ptrdiff_t>(k), logs.end());
    return logs[k];
  };
  stats.log_low = rank(low_percentile);
  stats.log_high = rank(high_percentile);
  return stats;
}

}  // namespace hdr4d
