#include "baselines/static_mlp_tone_mapper.h"

#include <cstdint>
#include <vector>

#include "baselines/chunked_reduce.h"
#include "baselines/log_domain.h"
#include "baselines/static_mlp_curve.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/tonemap/monotone_mlp.h"

namespace hdr4d::baselines {
namespace {

constexpr std::int64_t kStaticMlpGrain = 1024;  // values per chunk, direct path
constexpr std::int64_t kPiecewiseGrain = 4096;  // values per chunk, piecewise-linear path

template <typename T>
std::vector<StaticMlpCurve<T>> Curves(const T* params) {
  std::vector<StaticMlpCurve<T>> curves;
  for (int c = 0; c < 3; ++c) {
    curves.emplace_back(params + c * StaticMlpShape().NumParams(), kStaticMlpHidden);
  }
  return curves;
}

}  // namespace

const method::MlpShape& StaticMlpShape() {
  static const method::MlpShape shape{{1, kStaticMlpHidden, 1}, method::MlpOutput::kSigmoid};
  return shape;
}

std::size_t StaticMlpNumParams() { return 3 * StaticMlpShape().NumParams(); }

template <typename T>
void StaticMlpForward(const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr) {
  const method::MlpShape& shape = StaticMlpShape();
  const std::size_t per_channel = shape.NumParams();
  ParallelForChunks(std::int64_t(n), kStaticMlpGrain, [&](std::int64_t begin, std::int64_t end) {
    std::vector<T> cache(shape.CacheSize());
    for (std::int64_t i = begin; i < end; ++i) {
      for (int c = 0; c < 3; ++c) {
        const T x = ClampAbs(log_hdr[3 * i + c], kMaxAbsLogInput) + log_exposure;
        method::MlpForward(shape, params + c * per_channel, &x, &ldr[3 * i + c], cache.data());
      }
    }
  });
}

template <typename T>
void StaticMlpBackward(const T* params,
                       T log_exposure,
                       const T* log_hdr,
                       std::size_t n,
                       const T* dL_dldr,
                       T* dL_dlog_hdr,
                       T* dL_dparams) {
  const method::MlpShape& shape = StaticMlpShape();
  const std::size_t per_channel = shape.NumParams();
  auto chunk = [&](std::int64_t begin, std::int64_t end, T* partial) {
    std::vector<T> cache(shape.CacheSize()), scratch(2 * shape.MaxWidth());
    for (std::int64_t i = begin; i < end; ++i) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t k = 3 * i + c;
        T dx = T(0);
        if (dL_dldr[k] != T(0)) {  // a zero output gradient adds nothing anywhere
          const T x = ClampAbs(log_hdr[k], kMaxAbsLogInput) + log_exposure;
          const T* p = params + c * per_channel;
          T y;
          method::MlpForward(shape, p, &x, &y, cache.data());
          method::MlpBackward(shape, p, &x, cache.data(), &dL_dldr[k], &dx,
                              partial + c * per_channel, scratch.data());
        }
        if (dL_dlog_hdr) dL_dlog_hdr[k] = dx * ClampAbsSlope(log_hdr[k], kMaxAbsLogInput);
      }
    }
  };
  ReduceInChunks<T>(std::int64_t(n), kStaticMlpGrain, 3 * per_channel, chunk, dL_dparams);
}

template <typename T>
void StaticMlpForwardPiecewise(
    const T* params, T log_exposure, const T* log_hdr, std::size_t n, T* ldr) {
  const std::vector<StaticMlpCurve<T>> curves = Curves(params);
  ParallelForChunks(std::int64_t(n), kPiecewiseGrain, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      for (int c = 0; c < 3; ++c) {
        const T x = ClampAbs(log_hdr[3 * i + c], kMaxAbsLogInput) + log_exposure;
        ldr[3 * i + c] = Logistic(curves[c].PreSigmoid(x, curves[c].Segment(x)));
      }
    }
  });
}

template <typename T>
void StaticMlpBackwardPiecewise(const T* params,
                                T log_exposure,
                                const T* log_hdr,
                                std::size_t n,
                                const T* dL_dldr,
                                T* dL_dlog_hdr,
                                T* dL_dparams) {
  const std::vector<StaticMlpCurve<T>> curves = Curves(params);
  // Per channel, the segment sums S0 then S1, one after another in the partial.
  std::size_t offset[3], width = 0;
  for (int c = 0; c < 3; ++c) {
    offset[c] = width;
    width += 2 * std::size_t(curves[c].segments());
  }
  auto chunk = [&](std::int64_t begin, std::int64_t end, double* partial) {
    for (std::int64_t i = begin; i < end; ++i) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t k = 3 * i + c;
        const T x = ClampAbs(log_hdr[k], kMaxAbsLogInput) + log_exposure;
        const int s = curves[c].Segment(x);
        const T y = Logistic(curves[c].PreSigmoid(x, s));
        const T dz = dL_dldr[k] * y * (T(1) - y);
        double* s0 = partial + offset[c];
        s0[s] += double(dz);
        s0[curves[c].segments() + s] += double(dz) * double(x);
        if (dL_dlog_hdr) {
          dL_dlog_hdr[k] = dz * curves[c].Slope(s) * ClampAbsSlope(log_hdr[k], kMaxAbsLogInput);
        }
      }
    }
  };
  std::vector<double> sums(width, 0.0);
  ReduceInChunks<double>(std::int64_t(n), kPiecewiseGrain, width, chunk, sums.data());
  for (int c = 0; c < 3; ++c) {
    const double* s0 = sums.data() + offset[c];
    curves[c].Backward(s0, s0 + curves[c].segments(),
                       dL_dparams + c * StaticMlpShape().NumParams());
  }
}

template void StaticMlpForward<float>(const float*, float, const float*, std::size_t, float*);
template void StaticMlpForward<double>(const double*, double, const double*, std::size_t, double*);
template void StaticMlpBackward<float>(
    const float*, float, const float*, std::size_t, const float*, float*, float*);
template void StaticMlpBackward<double>(
    const double*, double, const double*, std::size_t, const double*, double*, double*);
template void StaticMlpForwardPiecewise<float>(
    const float*, float, const float*, std::size_t, float*);
template void StaticMlpForwardPiecewise<double>(
    const double*, double, const double*, std::size_t, double*);
template void StaticMlpBackwardPiecewise<float>(
    const float*, float, const float*, std::size_t, const float*, float*, float*);
template void StaticMlpBackwardPiecewise<double>(
    const double*, double, const double*, std::size_t, const double*, double*, double*);

namespace {

std::vector<float> InitialWeights(std::uint64_t seed) {
  std::vector<float> params(StaticMlpNumParams());
  const std::size_t per_channel = StaticMlpShape().NumParams();
  for (int c = 0; c < 3; ++c) {
    // A distinct, well-mixed stream per channel, so the three curves start different.
    const std::uint64_t channel_seed = seed ^ (0x9E3779B97F4A7C15ull * std::uint64_t(c + 1));
    method::MlpInit(StaticMlpShape(), channel_seed, params.data() + c * per_channel);
  }
  return params;
}

}  // namespace

StaticMlpToneMapper::StaticMlpToneMapper(const method::ToneMapperConfig& config)
    : ParamToneMapper(config, InitialWeights(config.seed)) {}

const float* StaticMlpToneMapper::Effective(std::vector<float>* scratch) const {
  if (!config_.monotone_curves) return params_.data();
  scratch->resize(params_.size());
  const std::size_t per_channel = StaticMlpShape().NumParams();
  for (int c = 0; c < 3; ++c) {
    method::MonotoneEffective(StaticMlpShape(), params_.data() + c * per_channel,
                              scratch->data() + c * per_channel);
  }
  return scratch->data();
}

void StaticMlpToneMapper::Map(const float* log_hdr, std::size_t n, float* ldr) const {
  std::vector<float> scratch;
  const float* weights = Effective(&scratch);
  if (config_.tabulated) {
    StaticMlpForwardPiecewise(weights, frame_.log_exposure, log_hdr, n, ldr);
    return;
  }
  StaticMlpForward(weights, frame_.log_exposure, log_hdr, n, ldr);
}

void StaticMlpToneMapper::MapBackward(const float* log_hdr,
                                      std::size_t n,
                                      const float* dL_dldr,
                                      float* dL_dlog_hdr) {
  // The gradient with respect to the weights Map used, then (monotone) to the stored ones.
  float* grads = grads_.data();
  if (config_.monotone_curves) {
    effective_grad_.assign(params_.size(), 0.0f);
    grads = effective_grad_.data();
  }
  std::vector<float> scratch;
  const float* weights = Effective(&scratch);
  if (config_.tabulated) {
    StaticMlpBackwardPiecewise(weights, frame_.log_exposure, log_hdr, n, dL_dldr, dL_dlog_hdr,
                               grads);
  } else {
    StaticMlpBackward(weights, frame_.log_exposure, log_hdr, n, dL_dldr, dL_dlog_hdr, grads);
  }
  if (!config_.monotone_curves) return;
  const std::size_t per_channel = StaticMlpShape().NumParams();
  for (int c = 0; c < 3; ++c) {
    method::MonotoneGradientAdd(StaticMlpShape(), params_.data() + c * per_channel,
                                effective_grad_.data() + c * per_channel,
                                grads_.data() + c * per_channel);
  }
}

}  // namespace hdr4d::baselines
