#include "method/render/hdr_color_stage.h"

#include <cmath>

#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::method {

namespace {
constexpr std::int64_t kGrain = 4096;
}

HdrColorStage::HdrColorStage(ToneMapper* tone_mapper, bool map_gaussians)
    : tm_(tone_mapper), map_(map_gaussians && tone_mapper && tone_mapper->pointwise()) {}

void HdrColorStage::SetLdrOnly(bool ldr_only) {
  HDR4D_CHECK(!ldr_only || map_);
  ldr_only_ = ldr_only;
}

void HdrColorStage::Forward(const float* colors,
                            int color_channels,
                            const std::vector<std::uint32_t>& visible,
                            float* features) {
  HDR4D_CHECK(color_channels == 3);
  const std::size_t m = visible.size();
  packed_.resize(m * 3);
  const int out = feature_channels();
  ParallelForChunks(static_cast<std::int64_t>(m), kGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t j = b; j < e; ++j) {
      const std::uint32_t i = visible[j];
      for (int c = 0; c < 3; ++c) {
        const float v = colors[i * 3 + c];
        packed_[j * 3 + c] = v;
        if (ldr_only_) continue;
        features[std::size_t(i) * out + c] =
            GuardedExp(offset_ ? v + offset_[std::size_t(i) * 3 + c] : v);
      }
    }
  });
  if (!tm_) return;
  if (observe_bank_ && m > 0) {
    double sum[3] = {0, 0, 0};  // serial: a fixed summation order
    for (std::size_t j = 0; j < m; ++j) {
      for (int c = 0; c < 3; ++c) sum[c] += packed_[j * 3 + c];
    }
    const float mean[3] = {float(sum[0] / m), float(sum[1] / m), float(sum[2] / m)};
    tm_->ObserveMeanLogHdr(frame_.time_index, mean);
  }
  tm_->BeginFrame(frame_);
  if (!map_) return;
  ldr_.resize(m * 3);
  tm_->Map(packed_.data(), m, ldr_.data());
  const int ldr_at = ldr_only_ ? 0 : 3;
  ParallelFor(static_cast<std::int64_t>(m), kGrain, [&](std::int64_t j) {
    float* f = features + std::size_t(visible[j]) * out + ldr_at;
    for (int c = 0; c < 3; ++c) f[c] = ldr_[j * 3 + c];
  });
}

void HdrColorStage::Backward(const float* colors,
                             int color_channels,
                             const std::vector<std::uint32_t>& visible,
                             const float* dL_dfeatures,
                             float* dL_dcolors) {
  HDR4D_CHECK(color_channels == 3 && packed_.size() == visible.size() * 3 && !ldr_only_);
  const std::size_t m = visible.size();
  const int out = feature_channels();
  if (map_) {
    dldr_.resize(m * 3);
    dlog_.resize(m * 3);
    ParallelFor(static_cast<std::int64_t>(m), kGrain, [&](std::int64_t j) {
      const float* g = dL_dfeatures + std::size_t(visible[j]) * out + 3;
      for (int c = 0; c < 3; ++c) dldr_[j * 3 + c] = g[c];
    });
    tm_->MapBackward(packed_.data(), m, dldr_.data(), dlog_.data());
  }
  ParallelForChunks(static_cast<std::int64_t>(m), kGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t j = b; j < e; ++j) {
      const std::size_t i = visible[j];
      for (int c = 0; c < 3; ++c) {
        const float c_hdr = offset_ ? colors[i * 3 + c] + offset_[i * 3 + c] : colors[i * 3 + c];
        float d = GuardedExpBackward(c_hdr, dL_dfeatures[i * out + c]);
        if (offset_grad_) offset_grad_[i * 3 + c] = d;  // d(c + offset)/d(offset) = 1
        if (map_) d += dlog_[j * 3 + c];
        dL_dcolors[i * 3 + c] = d;
      }
    }
  });
}

}  // namespace hdr4d::method
