#include "core/radiometry/camera_pipeline_vignetting.h"

namespace hdr4d {

double VignettingFactor(int x, int y, int width, int height, double strength) {
  const double dx = x + 0.5 - 0.5 * width, dy = y + 0.5 - 0.5 * height;
  const double half_diagonal_sq = 0.25 * (static_cast<double>(width) * width +
                                          static_cast<double>(height) * height);
  // A 0x0 image has no pixel to ask about; guard the division anyway.
  const double r_sq = half_diagonal_sq > 0 ? (dx * dx + dy * dy) / half_diagonal_sq : 0.0;
  return 1.0 - strength * r_sq;
}

void ApplyVignetting(Image& image, double strength) {
  if (strength == 0) return;
  const int channels = image.channels();
  const int colour = channels == 4 ? 3 : channels;
  float* v = image.data();
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const auto f = static_cast<float>(VignettingFactor(x, y, image.width(), image.height(),
                                                         strength));
      float* px = v + (static_cast<std::size_t>(y) * image.width() + x) * channels;
      for (int c = 0; c < colour; ++c) px[c] *= f;
    }
  }
}

}  // namespace hdr4d
