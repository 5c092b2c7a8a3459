#include "method/render/pixel_log.h"

#include <cstdint>

#include "core/util/parallel.h"

namespace hdr4d::method {

namespace {

constexpr std::int64_t kPixelLogGrain = 8192;

}  // namespace

void ExtractChannels(
    const float* src, int channels, int first, std::size_t pixels, std::vector<float>* dst) {
  dst->resize(pixels * 3);
  ParallelFor(static_cast<std::int64_t>(pixels), kPixelLogGrain, [&](std::int64_t p) {
    for (int c = 0; c < 3; ++c) (*dst)[p * 3 + c] = src[p * channels + first + c];
  });
}

void PixelLogImage(const std::vector<float>& hdr, float eps, std::vector<float>* x) {
  x->resize(hdr.size());
  // Both threads: a log per value (480k per 400x400 view) ran on one while the other waited.
  ParallelFor(static_cast<std::int64_t>(hdr.size()), kPixelLogGrain,
              [&](std::int64_t i) { (*x)[i] = PixelLog(hdr[i], eps); });
}

}  // namespace hdr4d::method
