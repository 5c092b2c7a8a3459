#include "baselines/durand_tone_mapper.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "baselines/bilateral_grid.h"
#include "baselines/chunked_reduce.h"
#include "baselines/log_domain.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

constexpr std::int64_t kDurandGrain = 4096;  // pixels per chunk
constexpr double kSpatialFraction = 0.02;

template <typename T>
struct DurandResolved {
  T compression, offset, inv_gamma;
  explicit DurandResolved(const T* p)
      : compression(std::exp(ClampAbs(p[0], kMaxAbsLogParam))),
        offset(ClampAbs(p[1], kMaxAbsLogParam)),
        inv_gamma(std::exp(-ClampAbs(p[2], kMaxAbsLogParam))) {}
};

template <typename T>
std::int64_t Pixels(int width, int height) {
  HDR4D_CHECK(width > 0 && height > 0);
  return std::int64_t(width) * height;
}

}  // namespace

DurandFilter DefaultDurandFilter(int width, int height) {
  DurandFilter filter;
  filter.sigma_space = std::max(1.0, kSpatialFraction * std::max(width, height));
  return filter;
}

template <typename T>
void DurandLogLuminance(const T* log_hdr, T log_exposure, int width, int height, T* log_lum) {
  ParallelForChunks(Pixels<T>(width, height), kDurandGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t p = b; p < e; ++p) {
      T x[3];
      for (int c = 0; c < 3; ++c)
        x[c] = ClampAbs(log_hdr[3 * p + c], kMaxAbsLogInput) + log_exposure;
      log_lum[p] = LogLuminance(x);
    }
  });
}

namespace {

// The forward from the image's log luminance and the filter's guide (nullptr: the luminance).
template <typename T>
void ForwardFromLuminance(const T* params,
                          T log_exposure,
                          const T* log_hdr,
                          int width,
                          int height,
                          const DurandFilter& filter,
                          const T* log_lum,
                          const T* guide,
                          T* ldr) {
  const std::int64_t pixels = Pixels<T>(width, height);
  const DurandResolved<T> r(params);
  std::vector<T> base(pixels);
  const BilateralGrid<T> grid(guide ? guide : log_lum, width, height, filter.sigma_space,
                              filter.sigma_range);
  grid.Filter(log_lum, base.data());
  ParallelForChunks(pixels, kDurandGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t p = b; p < e; ++p) {
      const T shift = (r.compression - T(1)) * base[p] + r.offset;
      for (int c = 0; c < 3; ++c) {
        const T x = ClampAbs(log_hdr[3 * p + c], kMaxAbsLogInput) + log_exposure;
        ldr[3 * p + c] = DisplayEncode(x + shift, r.inv_gamma);
      }
    }
  });
}

}  // namespace

template <typename T>
void DurandForwardGuided(const T* params,
                         T log_exposure,
                         const T* log_hdr,
                         int width,
                         int height,
                         const DurandFilter& filter,
                         const T* guide,
                         T* ldr) {
  std::vector<T> log_lum(Pixels<T>(width, height));
  DurandLogLuminance(log_hdr, log_exposure, width, height, log_lum.data());
  ForwardFromLuminance(params, log_exposure, log_hdr, width, height, filter, log_lum.data(), guide,
                       ldr);
}

template <typename T>
void DurandForward(const T* params,
                   T log_exposure,
                   const T* log_hdr,
                   int width,
                   int height,
                   const DurandFilter& filter,
                   T* ldr) {
  std::vector<T> log_lum(Pixels<T>(width, height));
  DurandLogLuminance(log_hdr, log_exposure, width, height, log_lum.data());
  ForwardFromLuminance(params, log_exposure, log_hdr, width, height, filter, log_lum.data(),
                       static_cast<const T*>(nullptr), ldr);
}

template <typename T>
void DurandBackward(const T* params,
                    T log_exposure,
                    const T* log_hdr,
                    int width,
                    int height,
                    const DurandFilter& filter,
                    const T* dL_dldr,
                    T* dL_dlog_hdr,
                    T* dL_dparams) {
  const std::int64_t pixels = Pixels<T>(width, height);
  const DurandResolved<T> r(params);
  std::vector<T> log_lum(pixels), base(pixels), d_base(pixels), d_log_lum(pixels);
  DurandLogLuminance(log_hdr, log_exposure, width, height, log_lum.data());
  const BilateralGrid<T> grid(log_lum.data(), width, height, filter.sigma_space,
                              filter.sigma_range);
  grid.Filter(log_lum.data(), base.data());
  // Per pixel: the display encoding, the parameters and dL/dbase; the colour's direct path
  // (log C_c = x_c + ...) is kept in dL_dlog_hdr until the luminance path is added below.
  auto chunk = [&](std::int64_t b, std::int64_t e, T* partial) {
    T d_compression = T(0), d_offset = T(0), d_inv_gamma = T(0);
    for (std::int64_t p = b; p < e; ++p) {
      const T shift = (r.compression - T(1)) * base[p] + r.offset;
      T sum_h = T(0);
      for (int c = 0; c < 3; ++c) {
        const T x = ClampAbs(log_hdr[3 * p + c], kMaxAbsLogInput) + log_exposure;
        const T log_c = x + shift;
        const T y = DisplayEncode(log_c, r.inv_gamma);
        T dy_dlog_c, dy_dinv_gamma;
        DisplayEncodeSlopes(log_c, r.inv_gamma, y, &dy_dlog_c, &dy_dinv_gamma);
        const T h = dL_dldr[3 * p + c] * dy_dlog_c;
        d_inv_gamma += dL_dldr[3 * p + c] * dy_dinv_gamma;
        if (dL_dlog_hdr) dL_dlog_hdr[3 * p + c] = h;
        sum_h += h;
      }
      d_offset += sum_h;
      d_compression += sum_h * base[p];
      d_base[p] = (r.compression - T(1)) * sum_h;
    }
    partial[0] += d_compression;
    partial[1] += d_offset;
    partial[2] += d_inv_gamma;
  };
  T sums[3] = {T(0), T(0), T(0)};
  ReduceInChunks<T>(pixels, kDurandGrain, 3, chunk, sums);
  // d compression / d log compression = compression; d(1/gamma) / d log gamma = -1/gamma.
  dL_dparams[0] += sums[0] * r.compression * ClampAbsSlope(params[0], kMaxAbsLogParam);
  dL_dparams[1] += sums[1] * ClampAbsSlope(params[1], kMaxAbsLogParam);
  dL_dparams[2] += sums[2] * -r.inv_gamma * ClampAbsSlope(params[2], kMaxAbsLogParam);
  if (!dL_dlog_hdr) return;
  grid.FilterBackward(d_base.data(), d_log_lum.data());
  ParallelForChunks(pixels, kDurandGrain, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t p = b; p < e; ++p) {
      T x[3], share[3];
      for (int c = 0; c < 3; ++c)
        x[c] = ClampAbs(log_hdr[3 * p + c], kMaxAbsLogInput) + log_exposure;
      LogLuminance(x, share);
      for (int c = 0; c < 3; ++c) {
        dL_dlog_hdr[3 * p + c] = (dL_dlog_hdr[3 * p + c] + d_log_lum[p] * share[c]) *
                                 ClampAbsSlope(log_hdr[3 * p + c], kMaxAbsLogInput);
      }
    }
  });
}

#define HDR4D_INSTANTIATE_DURAND(T)                                                               \
  template void DurandLogLuminance<T>(const T*, T, int, int, T*);                                 \
  template void DurandForwardGuided<T>(const T*, T, const T*, int, int, const DurandFilter&,      \
                                       const T*, T*);                                             \
  template void DurandForward<T>(const T*, T, const T*, int, int, const DurandFilter&, T*);       \
  template void DurandBackward<T>(const T*, T, const T*, int, int, const DurandFilter&, const T*, \
                                  T*, T*);
HDR4D_INSTANTIATE_DURAND(float)
HDR4D_INSTANTIATE_DURAND(double)
#undef HDR4D_INSTANTIATE_DURAND

DurandToneMapper::DurandToneMapper(const method::ToneMapperConfig& config)
    : ParamToneMapper(config,
                      {float(std::log(kInitialCompression)), float(kInitialOffset),
                       float(std::log(kInitialGamma))}) {}

void DurandToneMapper::Map(const float*, std::size_t, float*) const {
  HDR4D_CHECK(!"the Durand tone mapper is not pointwise: use MapImage");
}

void DurandToneMapper::MapBackward(const float*, std::size_t, const float*, float*) {
  HDR4D_CHECK(!"the Durand tone mapper is not pointwise: use MapImageBackward");
}

void DurandToneMapper::MapImage(const float* log_hdr, int width, int height, float* ldr) const {
  DurandForward(params_.data(), frame_.log_exposure, log_hdr, width, height,
                DefaultDurandFilter(width, height), ldr);
}

void DurandToneMapper::MapImageBackward(
    const float* log_hdr, int width, int height, const float* dL_dldr, float* dL_dlog_hdr) {
  DurandBackward(params_.data(), frame_.log_exposure, log_hdr, width, height,
                 DefaultDurandFilter(width, height), dL_dldr, dL_dlog_hdr, grads_.data());
}

}  // namespace hdr4d::baselines
