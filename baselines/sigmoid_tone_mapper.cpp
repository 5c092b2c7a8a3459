#include "baselines/sigmoid_tone_mapper.h"

#include <cstdint>

#include "baselines/chunked_reduce.h"
#include "baselines/log_domain.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

constexpr std::int64_t kSigmoidGrain = 4096;  // values per chunk

}  // namespace

template <typename T>
void SigmoidForward(T offset, T log_exposure, const T* log_hdr, std::size_t n, T* ldr) {
  const T shift = log_exposure + offset;
  ParallelForChunks(std::int64_t(3 * n), kSigmoidGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t k = begin; k < end; ++k) {
      ldr[k] = Logistic(ClampAbs(log_hdr[k], kMaxAbsLogInput) + shift);
    }
  });
}

template <typename T>
void SigmoidBackward(T offset,
                     T log_exposure,
                     const T* log_hdr,
                     std::size_t n,
                     const T* dL_dldr,
                     T* dL_dlog_hdr,
                     T* dL_doffset) {
  const T shift = log_exposure + offset;
  auto chunk = [&](std::int64_t begin, std::int64_t end, T* partial) {
    T sum = T(0);
    for (std::int64_t k = begin; k < end; ++k) {
      const T y = Logistic(ClampAbs(log_hdr[k], kMaxAbsLogInput) + shift);
      const T dx = dL_dldr[k] * y * (T(1) - y);
      sum += dx;
      if (dL_dlog_hdr) dL_dlog_hdr[k] = dx * ClampAbsSlope(log_hdr[k], kMaxAbsLogInput);
    }
    partial[0] += sum;
  };
  ReduceInChunks<T>(std::int64_t(3 * n), kSigmoidGrain, 1, chunk, dL_doffset);
}

template void SigmoidForward<float>(float, float, const float*, std::size_t, float*);
template void SigmoidForward<double>(double, double, const double*, std::size_t, double*);
template void SigmoidBackward<float>(
    float, float, const float*, std::size_t, const float*, float*, float*);
template void SigmoidBackward<double>(
    double, double, const double*, std::size_t, const double*, double*, double*);

SigmoidToneMapper::SigmoidToneMapper(const method::ToneMapperConfig& config)
    : ParamToneMapper(config, std::vector<float>(std::max(config.num_images, 0), 0.f)) {}

void SigmoidToneMapper::BeginFrame(const method::ToneFrame& frame) {
  HDR4D_CHECK(frame.image_index < static_cast<int>(params_.size()));
  ParamToneMapper::BeginFrame(frame);
}

float SigmoidToneMapper::FrameOffset() const {
  if (frame_.image_index >= 0) return params_[frame_.image_index];
  if (params_.empty()) return 0.f;
  double sum = 0.0;
  for (float p : params_) sum += p;
  return float(sum / double(params_.size()));
}

void SigmoidToneMapper::Map(const float* log_hdr, std::size_t n, float* ldr) const {
  SigmoidForward(FrameOffset(), frame_.log_exposure, log_hdr, n, ldr);
}

void SigmoidToneMapper::MapBackward(const float* log_hdr,
                                    std::size_t n,
                                    const float* dL_dldr,
                                    float* dL_dlog_hdr) {
  float d_offset = 0.f;
  SigmoidBackward(FrameOffset(), frame_.log_exposure, log_hdr, n, dL_dldr, dL_dlog_hdr, &d_offset);
  if (frame_.image_index >= 0) {
    grads_[frame_.image_index] += d_offset;
  } else if (!grads_.empty()) {
    const float share = float(double(d_offset) / double(grads_.size()));
    for (float& g : grads_) g += share;
  }
}

}  // namespace hdr4d::baselines
