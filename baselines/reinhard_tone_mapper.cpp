#include "baselines/reinhard_tone_mapper.h"

#include <cmath>
#include <cstdint>

#include "baselines/chunked_reduce.h"
#include "baselines/log_domain.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

constexpr std::int64_t kReinhardGrain = 2048;  // pixels per chunk

// The parameters as used: clamped logs, and 1/gamma.
template <typename T>
struct ReinhardResolved {
  T log_key, log_white, inv_gamma;
  explicit ReinhardResolved(const T* p)
      : log_key(ClampAbs(p[0], kMaxAbsLogParam)),
        log_white(ClampAbs(p[1], kMaxAbsLogParam)),
        inv_gamma(std::exp(-ClampAbs(p[2], kMaxAbsLogParam))) {}
};

// One pixel's forward, keeping what its backward needs.
template <typename T>
struct Pixel {
  T x[3];      // exposed log radiance
  T share[3];  // each channel's fraction of the luminance
  T log_lum;   // log L_w
  T l;         // log L_s
  T log_c[3];  // log of the colour before the display encoding
  T y[3];

  Pixel(const ReinhardResolved<T>& r, T log_exposure, const T* log_hdr) {
    for (int c = 0; c < 3; ++c) x[c] = ClampAbs(log_hdr[c], kMaxAbsLogInput) + log_exposure;
    log_lum = LogLuminance(x, share);
    l = r.log_key + log_lum;
    // log L_d = l + log(1 + e^(l - 2 log L_white)) - log(1 + e^l)
    const T log_display = -Softplus(-l) + Softplus(l - T(2) * r.log_white);
    for (int c = 0; c < 3; ++c) {
      log_c[c] = log_display + x[c] - log_lum;
      y[c] = DisplayEncode(log_c[c], r.inv_gamma);
    }
  }
};

}  // namespace

template <typename T>
void ReinhardForward(const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr) {
  const ReinhardResolved<T> r(params);
  ParallelForChunks(std::int64_t(n), kReinhardGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      const Pixel<T> px(r, log_exposure, log_hdr + 3 * i);
      for (int c = 0; c < 3; ++c) ldr[3 * i + c] = px.y[c];
    }
  });
}

template <typename T>
void ReinhardBackward(const T* params,
                      T log_exposure,
                      const T* log_hdr,
                      std::size_t n,
                      const T* dL_dldr,
                      T* dL_dlog_hdr,
                      T* dL_dparams) {
  const ReinhardResolved<T> r(params);
  auto chunk = [&](std::int64_t begin, std::int64_t end, T* partial) {
    T d_log_key = T(0), d_log_white = T(0), d_inv_gamma = T(0);
    for (std::int64_t i = begin; i < end; ++i) {
      const T* g = dL_dldr + 3 * i;
      const Pixel<T> px(r, log_exposure, log_hdr + 3 * i);
      T h[3], d_log_display = T(0), sum_h = T(0);
      for (int c = 0; c < 3; ++c) {
        T dy_dlog_c, dy_dinv_gamma;
        DisplayEncodeSlopes(px.log_c[c], r.inv_gamma, px.y[c], &dy_dlog_c, &dy_dinv_gamma);
        h[c] = g[c] * dy_dlog_c;
        d_inv_gamma += g[c] * dy_dinv_gamma;
        d_log_display += h[c];
        sum_h += h[c];
      }
      const T s_white = Logistic(px.l - T(2) * r.log_white);
      const T d_l = d_log_display * (Logistic(-px.l) + s_white);
      d_log_white += d_log_display * T(-2) * s_white;
      d_log_key += d_l;
      const T d_log_lum = d_l - sum_h;  // log_c carries -log L_w
      if (dL_dlog_hdr) {
        for (int c = 0; c < 3; ++c) {
          dL_dlog_hdr[3 * i + c] =
              (h[c] + d_log_lum * px.share[c]) * ClampAbsSlope(log_hdr[3 * i + c], kMaxAbsLogInput);
        }
      }
    }
    partial[0] += d_log_key;
    partial[1] += d_log_white;
    partial[2] += d_inv_gamma;
  };
  T sums[3] = {T(0), T(0), T(0)};
  ReduceInChunks<T>(std::int64_t(n), kReinhardGrain, 3, chunk, sums);
  dL_dparams[0] += sums[0] * ClampAbsSlope(params[0], kMaxAbsLogParam);
  dL_dparams[1] += sums[1] * ClampAbsSlope(params[1], kMaxAbsLogParam);
  // d(1/gamma)/d(log gamma) = -1/gamma
  dL_dparams[2] += sums[2] * -r.inv_gamma * ClampAbsSlope(params[2], kMaxAbsLogParam);
}

template void ReinhardForward<float>(const float*, float, const float*, std::size_t, float*);
template void ReinhardForward<double>(const double*, double, const double*, std::size_t, double*);
template void ReinhardBackward<float>(
    const float*, float, const float*, std::size_t, const float*, float*, float*);
template void ReinhardBackward<double>(
    const double*, double, const double*, std::size_t, const double*, double*, double*);

ReinhardToneMapper::ReinhardToneMapper(const method::ToneMapperConfig& config)
    : ParamToneMapper(config,
                      {float(std::log(kInitialKey)), float(std::log(kInitialWhite)),
                       float(std::log(kInitialGamma))}) {}

void ReinhardToneMapper::Map(const float* log_hdr, std::size_t n, float* ldr) const {
  ReinhardForward(params_.data(), frame_.log_exposure, log_hdr, n, ldr);
}

void ReinhardToneMapper::MapBackward(const float* log_hdr,
                                     std::size_t n,
                                     const float* dL_dldr,
                                     float* dL_dlog_hdr) {
  ReinhardBackward(params_.data(), frame_.log_exposure, log_hdr, n, dL_dldr, dL_dlog_hdr,
                   grads_.data());
}

}  // namespace hdr4d::baselines
