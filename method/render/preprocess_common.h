// What the two preprocess implementations share (preprocess.h): the per-Gaussian helpers, the
// colour sums over a Gaussian's coefficient rows, the frame state's set-up and finish. Internal
// to method/render/.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <vector>

#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/rotation4d.h"
#include "method/gaussian/sh4d.h"
#include "method/gaussian/slice.h"
#include "method/render/frame_state.h"

namespace hdr4d::method::detail {

inline constexpr std::int64_t kGaussianGrain = 1024;
inline constexpr std::int64_t kRowsDoneBlock = 256;

template <typename T>
Vec4<T> Row4(const std::vector<T>& v, std::size_t i) {
  return Vec4<T>(v[i * 4], v[i * 4 + 1], v[i * 4 + 2], v[i * 4 + 3]);
}

template <typename T>
Vec4<T> Mean4(const GaussianModelT<T>& model, std::size_t i) {
  return Vec4<T>(model.xyz[i * 3], model.xyz[i * 3 + 1], model.xyz[i * 3 + 2], model.t[i]);
}

template <typename T>
ConditionalGaussian<T> ConditionAt(const GaussianModelT<T>& model, std::size_t i, T time) {
  ConditionalGaussian<T> c;
  const Vec4<T> mean4 = Mean4(model, i);
  const Vec4<T> log_scales = Row4(model.log_scales, i);
  if (model.temporal) {
    c.rotation4 = Rotation4D(Row4(model.rot_left, i), Row4(model.rot_right, i));
    c.sigma4 = Covariance4D(c.rotation4, log_scales);
    const Slice<T> slice = SliceAtTime(mean4, c.sigma4, time);
    c.mean = slice.mean;
    c.cov = slice.cov;
    c.marginal = slice.marginal;
  } else {
    c.rotation3 = Rotation3D(Row4(model.rot_left, i));
    c.cov = Covariance3D(c.rotation3, Vec3<T>(log_scales.template head<3>()));
    c.mean = mean4.template head<3>();
  }
  return c;
}

template <typename T>
int TimeDegree(const GaussianModelT<T>& model, const RenderOptions& options) {
  return model.temporal ? std::min(options.time_degree, model.basis.max_time_degree) : 0;
}

inline constexpr int kMaxChannels = 8;

// The radius the tiles are binned with: the 3-sigma screen radius, tightened to where
// opacity x G can still reach the blending threshold 1/255 (G = exp(-d^2 / (2 lambda)) along the
// widest axis), so tiles the splat cannot touch get no entry. Pixels outside it have
// alpha < 1/255 and are skipped by the blend anyway: images and gradients are unchanged.
template <typename T>
int BinningRadius(const Splat2D<T>& splat, T opacity) {
  const T reach = opacity * T(255);
  if (!(reach > T(1))) return 0;  // can never reach 1/255 anywhere
  const T mid = T(0.5) * (splat.cov2d[0] + splat.cov2d[2]);
  const T det = splat.cov2d[0] * splat.cov2d[2] - splat.cov2d[1] * splat.cov2d[1];
  const T lambda = mid + std::sqrt(std::max(T(0.1), mid * mid - det));
  const T r = std::sqrt(T(2) * std::log(reach) * lambda);
  return std::min(splat.radius, static_cast<int>(std::ceil(r)) + 1);  // +1: rounding margin
}

// The same reach per axis, for the binning's rectangle (SplatBuffers::reach): on the ellipse
// d^T Sigma^-1 d <= 2 ln(255 opacity), |dx| is at most sqrt(2 ln(255 opacity) Sigma_xx) (and
// |dy| with Sigma_yy), which for an elongated or tilted splat is well inside the square of the
// widest axis. Each at most `radius` (BinningRadius), so the binning never lists a tile the
// square would not: it only drops tiles whose pixels all have alpha < 1/255.
template <typename T>
void BinningReach(const Splat2D<T>& splat, T opacity, int radius, int* reach) {
  reach[0] = reach[1] = 0;
  const T level = opacity * T(255);
  if (radius <= 0 || !(level > T(1))) return;
  const T t2 = T(2) * std::log(level);
  for (int axis = 0; axis < 2; ++axis) {
    const T r = std::sqrt(t2 * std::max(splat.cov2d[2 * axis], T(0)));
    reach[axis] = std::min(radius, static_cast<int>(std::ceil(r)) + 1);  // +1: rounding margin
  }
}

// Clears Gaussian i's gradient rows; the colour rows only when asked (a visible Gaussian's
// colour rows are overwritten in full by the backward).
template <typename T>
void ZeroRows(GaussianGradientsT<T>* g, std::size_t i, bool colour) {
  std::fill_n(&g->xyz[i * 3], 3, T(0));
  g->t[i] = T(0);
  std::fill_n(&g->log_scales[i * 4], 4, T(0));
  std::fill_n(&g->rot_left[i * 4], 4, T(0));
  std::fill_n(&g->rot_right[i * 4], 4, T(0));
  g->opacity_logit[i] = T(0);
  if (!colour) return;
  std::fill_n(&g->color_dc[i * g->channels], g->channels, T(0));
  const std::size_t rest = g->rest_stride();
  std::fill_n(&g->color_rest[i * rest], rest, T(0));
}

// colour[c] = kColorOffset + sum over the active coefficients k of w[k] coef_k[c] (coefficient 0
// from dc, k >= 1 from rest at (k - 1) * channels). The inactive ones have w = 0.
template <typename T>
void ColorFromWeights(const T* w,
                      const T* dc,
                      const T* rest,
                      int channels,
                      int functions,
                      int active,
                      int time_degree,
                      T* color) {
  for (int ch = 0; ch < channels; ++ch) color[ch] = static_cast<T>(kColorOffset) + w[0] * dc[ch];
  for (int n = 0; n <= time_degree; ++n) {
    for (int lm = n == 0 ? 1 : 0; lm < active; ++lm) {
      const int k = n * functions + lm;
      const T* ck = rest + (k - 1) * channels;
      for (int ch = 0; ch < channels; ++ch) color[ch] += w[k] * ck[ch];
    }
  }
}

// Three channels in float, the common case: a coefficient's 3 values as one 4-lane vector (the
// 4th lane is the next coefficient's and ignored), in 4 independent accumulators. The scalar loop
// above kept the colour in memory (it may alias) and was a third of the whole preprocess.
using Float4 = float __attribute__((vector_size(16)));
inline Float4 Load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
inline Float4 Load3(const float* p) { return Float4{p[0], p[1], p[2], 0.0f}; }

inline void ColorFromWeights3(const float* w,
                              const float* dc,
                              const float* rest,
                              int functions,
                              int active,
                              int time_degree,
                              int coefficients,
                              float* color) {
  Float4 acc0 = Load3(dc) * w[0], acc1 = {}, acc2 = {}, acc3 = {};
  const auto term = [&](int k) {
    // The last coefficient of the row has no 4th float after it.
    const float* ck = rest + (k - 1) * 3;
    return (k + 1 < coefficients ? Load4(ck) : Load3(ck)) * w[k];
  };
  for (int n = 0; n <= time_degree; ++n) {
    const int end = n * functions + active;
    int k = n * functions + (n == 0 ? 1 : 0);
    for (; k + 4 <= end; k += 4) {
      acc0 += term(k);
      acc1 += term(k + 1);
      acc2 += term(k + 2);
      acc3 += term(k + 3);
    }
    for (; k < end; ++k) acc1 += term(k);
  }
  const Float4 sum = (acc0 + acc1) + (acc2 + acc3);
  for (int ch = 0; ch < 3; ++ch) color[ch] = static_cast<float>(kColorOffset) + sum[ch];
}

template <typename T>
void Color(const T* w,
           const T* dc,
           const T* rest,
           int channels,
           const ColorBasis& basis,
           int sh_degree,
           int time_degree,
           T* color) {
  const int functions = basis.sh_functions();
  const int active = (sh_degree + 1) * (sh_degree + 1);
  if constexpr (std::is_same_v<T, float>) {
    if (channels == 3) {
      return ColorFromWeights3(w, dc, rest, functions, active, time_degree, basis.coefficients(),
                               color);
    }
  }
  ColorFromWeights(w, dc, rest, channels, functions, active, time_degree, color);
}

// The colour rows' gradient for coefficients [0, coefficients) (w = 0 for the inactive ones
// among them); the rest of the row is not written.
template <typename T>
void ColorGradRows(const T* w, const T* dcolor, int channels, int coefficients, T* gdc, T* grest) {
  if constexpr (std::is_same_v<T, float>) {
    if (channels == 3) {
      const Float4 d = Load3(dcolor);
      for (int ch = 0; ch < 3; ++ch) gdc[ch] = w[0] * dcolor[ch];
      // Overlapping 4-float stores, each 4th lane overwritten by the next; the last row of 3
      // is stored alone (it ends the Gaussian's row).
      int k = 1;
      for (; k + 1 < coefficients; ++k) {
        const Float4 g = d * w[k];
        std::memcpy(grest + (k - 1) * 3, &g, sizeof(g));
      }
      if (k < coefficients) {
        for (int ch = 0; ch < 3; ++ch) grest[(k - 1) * 3 + ch] = w[k] * dcolor[ch];
      }
      return;
    }
  }
  for (int ch = 0; ch < channels; ++ch) gdc[ch] = w[0] * dcolor[ch];
  for (int k = 1; k < coefficients; ++k) {
    for (int ch = 0; ch < channels; ++ch) grest[(k - 1) * channels + ch] = w[k] * dcolor[ch];
  }
}

inline constexpr int kColorAhead = 8;
template <typename T>
void PrefetchRow(const T* row, std::size_t count) {
  const char* p = reinterpret_cast<const char*>(row);
  for (std::size_t b = 0; b < count * sizeof(T); b += 64) __builtin_prefetch(p + b);
}

template <typename T>
void CheckInputs(const GaussianModelT<T>& model, const RenderOptions& options) {
  HDR4D_CHECK(model.Validate().empty());
  HDR4D_CHECK(model.channels <= kMaxChannels);
  HDR4D_CHECK(options.sh_degree >= 0 && options.sh_degree <= model.basis.max_sh_degree);
  HDR4D_CHECK(options.time_degree >= 0);
  const int features =
      options.color_stage ? options.color_stage->feature_channels() : model.channels;
  HDR4D_CHECK(features <= kMaxChannels);
  HDR4D_CHECK(options.background.empty() ||
              static_cast<int>(options.background.size()) == features);
}

// The frame state sized for `model` before a forward: every output row is written by it.
template <typename T>
void BeginPreprocess(const GaussianModelT<T>& model,
                     const RenderOptions& options,
                     FrameStateT<T>* state) {
  CheckInputs(model, options);
  const std::size_t n = model.size();
  const int channels = model.channels;
  ColorStage* const stage = options.color_stage;
  HDR4D_CHECK(stage == nullptr ||
              (std::is_same_v<T, float> && model.color_mode == ColorMode::kLogHdr));
  state->splats.channels = stage ? stage->feature_channels() : channels;
  state->splats.Resize(n);
  state->splats.reach.resize(2 * n);  // each preprocess writes every Gaussian's pair
  if (stage) state->colors.resize(n * channels);
  state->clamped.assign(n * channels, 0);
  state->screen_radius.assign(n, 0);
}

// Gaussian i's colour from its basis weights w (into the colour stage's input, or straight into
// the features), an LDR colour clamped at 0 with the clamp remembered (it gets no gradient).
template <typename T>
void WriteColour(const GaussianModelT<T>& model,
                 std::size_t i,
                 const T* w,
                 const RenderOptions& options,
                 int time_degree,
                 FrameStateT<T>* state) {
  const int channels = model.channels;
  const std::size_t stride = model.rest_stride();
  T* color =
      options.color_stage ? &state->colors[i * channels] : &state->splats.features[i * channels];
  Color(w, &model.color_dc[i * channels], &model.color_rest[i * stride], channels, model.basis,
        options.sh_degree, time_degree, color);
  if (model.color_mode != ColorMode::kLdr) return;
  for (int ch = 0; ch < channels; ++ch) {
    if (color[ch] < T(0)) {
      color[ch] = T(0);
      state->clamped[i * channels + ch] = 1;
    }
  }
}

// Gaussian i's colour rows' gradient from its basis weights and the gradient of its colour
// (through the colour stage when there is one; none where the colour was clamped), for the
// first `coefficients` (at least ColorBasis::used_coefficients; the caller owns what follows).
// The view direction and dt are detached, as in the reference code.
template <typename T>
void WriteColourGradient(const GaussianModelT<T>& model,
                         std::size_t i,
                         const T* w,
                         const RenderOptions& options,
                         const FrameStateT<T>& state,
                         int coefficients,
                         T* gdc,
                         T* grest) {
  const int channels = model.channels;
  T dcolor[kMaxChannels];
  const T* dfeatures = options.color_stage ? &state.color_grads[i * channels]
                                           : &state.splat_grads.features[i * channels];
  for (int ch = 0; ch < channels; ++ch)
    dcolor[ch] = state.clamped[i * channels + ch] ? T(0) : dfeatures[ch];
  // Written, not accumulated, in one pass (w is 0 for inactive degrees).
  ColorGradRows(w, dcolor, channels, coefficients, gdc, grest);
}

// After a forward: the visible count and, with a colour stage, its forward over the visible rows.
template <typename T>
void FinishPreprocess(const RenderOptions& options,
                      const GaussianModelT<T>& model,
                      const std::vector<std::int64_t>& visible_per_chunk,
                      FrameStateT<T>* state) {
  state->num_visible = 0;
  for (std::int64_t v : visible_per_chunk) state->num_visible += static_cast<std::size_t>(v);
  ColorStage* const stage = options.color_stage;
  if (!stage) return;
  const std::size_t n = model.size();
  state->visible.clear();
  state->visible.reserve(state->num_visible);
  for (std::size_t i = 0; i < n; ++i) {
    if (state->splats.radius[i] > 0) state->visible.push_back(static_cast<std::uint32_t>(i));
  }
  if constexpr (std::is_same_v<T, float>) {
    stage->Forward(state->colors.data(), model.channels, state->visible,
                   state->splats.features.data());
  }
}

}  // namespace hdr4d::method::detail
