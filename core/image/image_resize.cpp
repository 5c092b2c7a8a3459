#include "core/image/image_resize.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "core/util/error.h"

namespace hdr4d {

Image DownsampleBox(const Image& image, int factor) {
  HDR4D_CHECK(factor >= 1 && image.width() % factor == 0 && image.height() % factor == 0);
  if (factor == 1) return image;
  const int w = image.width() / factor, h = image.height() / factor, c = image.channels();
  Image out(w, h, c, image.encoding());
  const double scale = 1.0 / (double(factor) * factor);
  std::vector<double> sum(c);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::fill(sum.begin(), sum.end(), 0.0);
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx)
          for (int k = 0; k < c; ++k) sum[k] += image.at(x * factor + dx, y * factor + dy, k);
      for (int k = 0; k < c; ++k) out.at(x, y, k) = static_cast<float>(sum[k] * scale);
    }
  }
  return out;
}

std::string ResolutionProblem(int width, int height, int resolution) {
  if (resolution < 1) return fmt::format("--resolution {} must be >= 1", resolution);
  if (width % resolution != 0 || height % resolution != 0) {
    return fmt::format(
        "{}x{} is not divisible by --resolution {} (a reduced pixel must cover whole pixels; "
        "pick a factor of both sides)",
        width, height, resolution);
  }
  return "";
}

}  // namespace hdr4d
