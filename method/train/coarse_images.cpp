#include "method/train/coarse_images.h"

#include <cstddef>

#include "core/util/error.h"
#include "method/train/train_views.h"  // DownscaledIntrinsics

namespace hdr4d::method {

int CoarseFactor(int iteration, int coarse_iterations, int width, int height) {
  if (coarse_iterations <= 0 || iteration > coarse_iterations) return 1;
  const int wanted = 2 * iteration <= coarse_iterations ? 4 : 2;
  for (int f = wanted; f > 1; f /= 2)
    if (width >= f && height >= f) return f;
  return 1;
}

PinholeIntrinsics CoarseIntrinsics(const PinholeIntrinsics& intrinsics, int factor) {
  HDR4D_CHECK(factor >= 1 && intrinsics.width >= factor && intrinsics.height >= factor);
  // Cropping the last columns and rows keeps the focal lengths and principal point; the cropped
  // size divides exactly.
  PinholeIntrinsics cropped = intrinsics;
  cropped.width -= intrinsics.width % factor;
  cropped.height -= intrinsics.height % factor;
  return DownscaledIntrinsics(cropped, factor);
}

void BoxReduceInPlace(std::vector<float>* image, int width, int height, int channels, int factor) {
  HDR4D_CHECK(image != nullptr && factor >= 1 && width > 0 && height > 0 && channels > 0);
  HDR4D_CHECK(width >= factor && height >= factor);
  HDR4D_CHECK(image->size() == static_cast<std::size_t>(width) * height * channels);
  if (factor == 1) return;
  const int w = width / factor, h = height / factor;
  const float inverse = 1.0f / static_cast<float>(factor * factor);
  float* data = image->data();
  // Output pixel (x, y) is written at or before any input pixel its block reads is needed again:
  // its index y w + x never exceeds the first input index of its block (y f W + x f, as w <= W),
  // and later blocks read only later inputs, so the reduction runs in place front to back. The
  // blocks cover the top-left w f x h f pixels (w = floor(W / f)); the rest is not read.
  std::vector<float> sum(channels);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < channels; ++c) sum[c] = 0.0f;
      for (int dy = 0; dy < factor; ++dy) {
        const float* row = data + (static_cast<std::size_t>(y * factor + dy) * width + x * factor) * channels;
        for (int dx = 0; dx < factor; ++dx)
          for (int c = 0; c < channels; ++c) sum[c] += row[dx * channels + c];
      }
      float* out = data + (static_cast<std::size_t>(y) * w + x) * channels;
      for (int c = 0; c < channels; ++c) out[c] = sum[c] * inverse;
    }
  }
  image->resize(static_cast<std::size_t>(w) * h * channels);
}

}  // namespace hdr4d::method
